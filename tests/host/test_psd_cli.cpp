// gyrochar-analyze's PSD, sinusoid search and --plot of a whole record, as a user meets them.
// Oracles: the simulator's truth (a sinusoid of 2 deg/h at 0.05 Hz on ARW 0.02 deg/sqrt(h), the
// issue's target), white rate noise's one-sided PSD 2 N^2 (N = 0.02 deg/sqrt(h) = 1.2 deg/h
// sqrt(s): 2.88 (deg/h)^2/Hz), the PNG and SVG file signatures, the exit codes of
// hal/program/exit_codes.hpp.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "hal/program/exit_codes.hpp"
#include "support/shell.hpp"

namespace {

using namespace gyrochar;

const std::string tool = GYROCHAR_BINARY_DIR "/host_tools/gyrochar-analyze";
const std::string sim = GYROCHAR_BINARY_DIR "/host_tools/gyrochar-sim";

using Outcome = gyrochar::test_support::ShellOutcome;

std::string temp(const std::string& name) { return gyrochar::test_support::temp_path(name); }

Outcome run_shell(const std::string& command) { return gyrochar::test_support::run_shell(command, "psd_err.txt"); }

std::string slurp(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(f), {}};
}

// The sinusoid target, at 2 h instead of 8 (the 8 h run is measured in docs/metrology.md).
const std::string& sinusoid_counts() {
  static const std::string path = [] {
    const std::string p = temp("sinusoid.txt");
    const Outcome r = run_shell(sim + " --duration 7200 --tau0 0.01 --arw 0.02 --sinusoid 2,0.05 --seed 3 > " + p);
    EXPECT_EQ(r.code, 0) << r.err;
    return p;
  }();
  return path;
}

TEST(AnalyzePsd, TheSimulatedSinusoidIsFoundWithinItsUncertaintyAndFitted) {
  const Outcome r = run_shell(tool + " --type counts --tau0 0.01 --pulse-weight 1 --fit ieee952 --format json " +
                              sinusoid_counts());
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  // The search: one peak, at 0.05 Hz, of amplitude 2 deg/h (the simulator's truth).
  const nlohmann::json& peaks = j.at("psd").at("peaks");
  ASSERT_EQ(peaks.size(), 1u) << peaks.dump();
  const double f = peaks[0]["frequency"]["value"], uf = peaks[0]["frequency"]["uncertainty"];
  const double a = peaks[0]["amplitude"]["value"], ua = peaks[0]["amplitude"]["uncertainty"];
  EXPECT_NEAR(f, 0.05, 3 * uf);
  EXPECT_NEAR(a, 2.0, 3 * ua);
  EXPECT_NEAR(a, 2.0, 0.3 * 2.0);
  // The fit took it: the recommended model has the sinusoid, within 30 % of 2 deg/h. (Not within 3
  // of the fit's own stated uncertainty: the fit takes a sinusoid's share of the points' covariance
  // as none, and states 0.0026 deg/h where it is off by 0.010: docs/metrology.md.)
  const nlohmann::json& fit = j.at("fit").at(0);
  ASSERT_TRUE(fit.at("ok").get<bool>()) << fit.at("chi2_per_dof");
  ASSERT_EQ(fit.at("sinusoids").size(), 1u) << fit.at("model").dump();
  const nlohmann::json& s = fit.at("sinusoids")[0];
  const double fa = s["amplitude"]["value"], fua = s["amplitude"]["uncertainty"];
  std::printf("peak %.4g +- %.2g deg/h at %.6g +- %.2g Hz; fit %.4g +- %.2g deg/h\n", a, ua, f, uf, fa, fua);
  EXPECT_NEAR(fa, 2.0, 0.3 * 2.0);
  EXPECT_GT(fua, 0);
  EXPECT_EQ(s["frequency"]["value"].get<double>(), f);
  EXPECT_EQ(s["frequency"]["uncertainty"].get<double>(), uf);
  // The white level of the PSD away from the line and below the quantization pattern's rise (above
  // about 5 Hz: 1 arcsec pulses without dither): 2 N^2 = 2.88 (deg/h)^2/Hz (N = 1.2 deg/h sqrt(s)).
  const nlohmann::json& psd = j.at("psd");
  EXPECT_EQ(psd.at("unit"), "(deg/h)^2/Hz");
  double sum = 0;
  int n = 0;
  for (std::size_t i = 0; i < psd.at("freq").size(); ++i)
    if (psd["freq"][i].get<double>() > 0.2 && psd["freq"][i].get<double>() < 2) sum += psd["psd"][i].get<double>(), ++n;
  EXPECT_NEAR(sum / n, 2.88, 0.05 * 2.88);
}

TEST(AnalyzePsd, WritesEveryBinToTheCsvAndTurnsTheSearchOff) {
  const std::string csv = temp("psd.csv");
  const Outcome r = run_shell(tool +
                              " --type counts --tau0 0.01 --pulse-weight 1 --fit ieee952 --format json "
                              "--no-sinusoid-search --psd-segment 4096 --psd " +
                              csv + " " + sinusoid_counts());
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_TRUE(j.at("psd").at("search").is_null());
  EXPECT_TRUE(j.at("fit").at(0).at("sinusoids").empty());
  std::istringstream lines(slurp(csv));
  std::string line;
  std::getline(lines, line);
  EXPECT_EQ(line, "freq,psd,ci_low,ci_high");
  std::size_t rows = 0;
  double low = 0, psd = 0, high = 0, freq = 0;
  while (std::getline(lines, line)) {
    ++rows;
    ASSERT_EQ(std::sscanf(line.c_str(), "%lf,%lf,%lf,%lf", &freq, &psd, &low, &high), 4) << line;
    EXPECT_LT(low, psd);
    EXPECT_GT(high, psd);
  }
  EXPECT_EQ(rows, 4096u / 2 - 1);                    // bins 1 .. L/2 - 1
  EXPECT_DOUBLE_EQ(freq, (4096.0 / 2 - 1) / 40.96);  // the last: k / (L tau0)
}

// The PSD runs on a thread of its own beside the analysis (run.cpp), unless one thread is asked
// for: the report, the PSD file and the notes are the same bytes either way. Oracle: the run on
// one thread, the spectrum after the analysis.
TEST(AnalyzePsd, ThePsdBesideTheAnalysisGivesTheBytesOfOneThread) {
  std::string out[2], err[2], csv[2];
  for (const int threads : {1, 2}) {
    const std::string path = temp("psd_threads" + std::to_string(threads) + ".csv");
    const Outcome r = run_shell(tool + " --threads " + std::to_string(threads) +
                                " --type counts --tau0 0.01 --pulse-weight 1 --stats oadev,mdev,totdev,theoh "
                                "--fit ieee952 --fit-long-tau theoh --format json --psd " +
                                path + " " + sinusoid_counts());
    ASSERT_EQ(r.code, 0) << r.err;
    out[threads - 1] = r.out, err[threads - 1] = r.err, csv[threads - 1] = slurp(path);
  }
  EXPECT_EQ(nlohmann::json::parse(out[1]).at("psd").at("peaks").size(), 1u);  // the simulated sinusoid
  EXPECT_EQ(out[0], out[1]);
  EXPECT_EQ(err[0], err[1]);
  EXPECT_GT(csv[0].size(), 1000u);
  EXPECT_EQ(csv[0], csv[1]);
}

TEST(AnalyzePsd, GivenFrequenciesAreOfferedToTheFitAndCheckedFirst) {
  const Outcome r = run_shell(tool +
                              " --type counts --tau0 0.01 --pulse-weight 1 --fit ieee952 --format json "
                              "--no-sinusoid-search --sinusoid-hz 0.05 " +
                              sinusoid_counts());
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j.at("fit").at(0).at("sinusoids").size(), 1u);
  EXPECT_EQ(j["fit"][0]["sinusoids"][0]["frequency"]["value"].get<double>(), 0.05);
  for (const std::string& args : {std::string("--sinusoid-hz 60"), std::string("--sinusoid-hz -1"),
                                  std::string("--sinusoid-hz 1 --sinusoid-hz 2 --sinusoid-hz 3")}) {
    const Outcome bad = run_shell(tool + " --type counts --tau0 0.01 --pulse-weight 1 --fit ieee952 " + args + " " +
                                  sinusoid_counts());
    EXPECT_EQ(bad.code, exit_code::bad_input) << args;
    EXPECT_NE(bad.err.find("gyrochar-analyze: --sinusoid-hz: "), std::string::npos) << bad.err;
    EXPECT_TRUE(bad.out.empty());
  }
  const Outcome odd = run_shell(tool + " --type counts --tau0 0.01 --pulse-weight 1 --psd-segment 1001 " +
                                sinusoid_counts());
  EXPECT_EQ(odd.code, exit_code::bad_input);
  EXPECT_NE(odd.err.find("--psd-segment: must be even"), std::string::npos) << odd.err;
}

TEST(AnalyzePsd, KalibrGetsNAndKAloneAndSaysWhatItLeavesOut) {
  // The sinusoid of the target with rate random walk (Kalibr needs K): the chosen model
  // has the sinusoid, which Kalibr's model has no place for; the file's first comment line and
  // stderr name it.
  const std::string counts = temp("sinusoid_rrw.txt"), yaml = temp("imu.yaml");
  ASSERT_EQ(run_shell(sim + " --duration 7200 --tau0 0.01 --arw 0.02 --rrw 2 --sinusoid 2,0.05 --seed 3 > " + counts).code,
            0);
  const Outcome r = run_shell(tool + " --type counts --tau0 0.01 --pulse-weight 1 --fit ieee952 --kalibr " + yaml + " " +
                              counts);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("gyrochar-analyze: note: --kalibr: gyroscope_noise_density is the fitted white-rate N"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("1 sinusoid"), std::string::npos) << r.err;
  const std::string text = slurp(yaml);
  const std::string first = text.substr(0, text.find('\n'));
  EXPECT_NE(first.find("N and K alone, without the model's"), std::string::npos) << first;
  EXPECT_NE(first.find("1 sinusoid"), std::string::npos) << first;
}

TEST(AnalyzePlot, DrawsValidNonTrivialPngAndSvg) {
  const std::string prefix = temp("static");
  const Outcome r = run_shell(tool + " --type counts --tau0 0.01 --pulse-weight 1 --fit ieee952 --plot " + prefix + " " +
                              sinusoid_counts());
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string png = slurp(prefix + ".png"), svg = slurp(prefix + ".svg");
  ASSERT_GT(png.size(), 20000u);  // four panels of curves, lines and text
  EXPECT_EQ(png.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  EXPECT_NE(svg.find("<svg"), std::string::npos);
  EXPECT_NE(svg.find("</svg>"), std::string::npos);
  EXPECT_GT(svg.size(), 50000u);
  std::FILE* part = std::fopen((prefix + ".png.part").c_str(), "r");
  EXPECT_EQ(part, nullptr) << "the part file was renamed";
  if (part) std::fclose(part);
}

TEST(AnalyzePlot, AnUnwritablePrefixIsAnOutputError) {
  const Outcome r = run_shell(tool + " --type counts --tau0 0.01 --pulse-weight 1 --plot /nonexistent/dir/x " +
                              sinusoid_counts());
  EXPECT_EQ(r.code, exit_code::output_failed) << r.err;
  EXPECT_NE(r.err.find("gyrochar-analyze: --plot: /nonexistent/dir/x.svg.part: No such file or directory"),
            std::string::npos)
      << r.err;
}

}  // namespace
