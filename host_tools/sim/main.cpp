// gyrochar-sim: a simulated ring laser gyro with known IEEE-952 parameters, faster than real time:
// writes pulse counts per tau0 (one per line) for gyrochar-analyze, the firmware's fakes or a test.
#include <CLI/CLI.hpp>

#include <cmath>
#include <cstdio>
#include <string>

#include "gyro_sim.hpp"

int main(int argc, char** argv) {
  using namespace gyrochar;
  CLI::App app{"gyrochar-sim: pulse counts of a simulated ring laser gyro with known parameters.",
               "gyrochar-sim"};
  app.footer(R"(Parameters are in the units gyro data sheets use; the quantization noise follows from the pulse
weight (Q = pulse weight / sqrt(12)). Bias instability is flicker rate noise over the band from
1e5 s down to 2 tau0.

Examples:
  gyrochar-sim --duration 7200 --tau0 0.01 --arw 0.002 --rrw 0.01 > counts.txt
  gyrochar-sim --duration 3600 --arw 0.002 | gyrochar-analyze --type counts --tau0 0.01 --pulse-weight 1 -

Exit codes: 0 success, 2 bad options, 3 cannot write.)");
  GyroParameters p;
  double duration_s = 3600, pulse_arcsec = 1.0, rate_dph = 15.041, q_arcsec = 0, arw = 0, rrw = 0, ramp = 0, bias = 0;
  double dither_arcsec = 0, dither_hz = 0;
  std::string out = "-";
  app.add_option("--duration", duration_s, "simulated time in seconds")->capture_default_str();
  app.add_option("--tau0", p.tau0_s, "sample interval in seconds")->capture_default_str();
  app.add_option("--pulse-weight", pulse_arcsec, "angle per pulse in arcsec")->capture_default_str();
  app.add_option("--rate", rate_dph, "input rate in deg/h (earth rate by default)")->capture_default_str();
  app.add_option("--white-angle", q_arcsec, "white angle noise beyond quantization, arcsec")->capture_default_str();
  app.add_option("--arw", arw, "angle random walk N in deg/sqrt(h)")->capture_default_str();
  app.add_option("--rrw", rrw, "rate random walk K in deg/h/sqrt(h)")->capture_default_str();
  app.add_option("--bias-instability", bias, "bias instability B in deg/h (flicker rate noise)")->capture_default_str();
  app.add_option("--ramp", ramp, "rate ramp R in deg/h/h")->capture_default_str();
  app.add_option("--dither", dither_arcsec, "dither amplitude in arcsec")->capture_default_str();
  app.add_option("--dither-hz", dither_hz, "dither frequency in Hz")->capture_default_str();
  app.add_option("--seed", p.seed, "random seed (runs are reproducible)")->capture_default_str();
  app.add_option("--out", out, "output file, '-' for standard output")->capture_default_str();
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "gyrochar-sim: options: %s (see --help)\n", e.what());
    return 2;
  }
  auto bad = [](const char* what, const char* why) {
    std::fprintf(stderr, "gyrochar-sim: %s: %s\n", what, why);
    return 2;
  };
  if (!(p.tau0_s > 0)) return bad("--tau0", "must be positive");
  if (!(duration_s >= p.tau0_s)) return bad("--duration", "must be at least tau0");
  if (!(pulse_arcsec > 0)) return bad("--pulse-weight", "must be positive");
  for (double v : {q_arcsec, arw, rrw, ramp, bias, dither_arcsec, dither_hz})
    if (!(v >= 0) || !std::isfinite(v)) return bad("noise parameters", "must be finite and >= 0");
  p.pulse_weight_rad = pulse_arcsec * units::arcsec;
  p.rate_rad_s = rate_dph * units::deg_per_h;
  p.q_rad = q_arcsec * units::arcsec;
  p.n_rad_sqrt_s = arw * units::deg_per_sqrt_h;
  p.k_rad_s_sqrt_s = rrw * units::deg_per_h_sqrt_h;
  p.r_rad_s2 = ramp * units::deg_per_h_per_h;
  p.b_rad_s = bias * units::deg_per_h;
  p.dither_amplitude_rad = dither_arcsec * units::arcsec;
  p.dither_frequency_hz = dither_hz;
  FILE* f = out == "-" ? stdout : std::fopen(out.c_str(), "w");
  if (f == nullptr) {
    std::fprintf(stderr, "gyrochar-sim: %s: cannot write\n", out.c_str());
    return 3;
  }
  std::fprintf(f, "# gyrochar-sim counts: tau0 %g s, pulse weight %g arcsec, rate %g deg/h, ARW %g deg/sqrt(h), "
               "RRW %g deg/h/sqrt(h), ramp %g deg/h/h, seed %llu\n", p.tau0_s, pulse_arcsec, rate_dph, arw, rrw, ramp,
               static_cast<unsigned long long>(p.seed));
  GyroSimulator sim(p);
  const auto n = static_cast<std::uint64_t>(std::llround(duration_s / p.tau0_s));
  for (std::uint64_t k = 0; k < n; ++k) std::fprintf(f, "%lld\n", static_cast<long long>(sim.next_count()));
  if (f != stdout) std::fclose(f);
  return 0;
}
