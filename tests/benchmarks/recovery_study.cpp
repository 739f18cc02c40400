// recovery_study: how well the IEEE-952 fit recovers simulated gyros (tests/support/recovery.hpp):
// per scenario and term, how often a term is resolved, how often a resolved term lies within one and
// two of its stated standard uncertainties of the truth, and how often a term whose truth is zero
// is called resolved; for the long-run scenarios also how the fits with TOTDEV and TheoH at long
// tau compare with the one from OADEV alone. Markdown on stdout (toolchain/metrology.sh puts it into docs/metrology.md),
// progress and the wall time on stderr.
#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <string>
#include <vector>

#include "support/recovery.hpp"

namespace {

using namespace gyrochar::test_support;

std::string share(std::size_t k, std::size_t n) {
  return n ? fmt::format("{:.1f}", 100.0 * static_cast<double>(k) / static_cast<double>(n)) : "-";
}

// Binomial standard error of a fraction p over n runs, in points.
std::string error_of(double p, std::size_t n) {
  return n ? fmt::format("{:.1f}", 100.0 * std::sqrt(p * (1 - p) / static_cast<double>(n))) : "-";
}

std::string describe(const gyrochar::SimOptions& o) {
  std::string s = fmt::format("{:g} h at tau0 {:g} s, {:g} arcsec pulses", o.duration_s / 3600, o.tau0_s, o.pulse_arcsec);
  if (o.white_angle_arcsec > 0) s += fmt::format(", white angle {:g} arcsec", o.white_angle_arcsec);
  if (o.arw_deg_per_sqrt_h > 0) s += fmt::format(", N {:g} deg/sqrt(h)", o.arw_deg_per_sqrt_h);
  if (o.bias_deg_per_h > 0) s += fmt::format(", B {:g} deg/h", o.bias_deg_per_h);
  if (o.rrw_deg_per_h_sqrt_h > 0) s += fmt::format(", K {:g} deg/h/sqrt(h)", o.rrw_deg_per_h_sqrt_h);
  if (o.ramp_deg_per_h2 > 0) s += fmt::format(", R {:g} deg/h/h", o.ramp_deg_per_h2);
  for (const gyrochar::SimMarkov& m : o.markov)
    s += fmt::format(", Markov {:g} deg/h at Tc {:g} s", m.sigma_deg_per_h, m.tc_s);
  for (const gyrochar::SimSinusoid& w : o.sinusoids)
    s += fmt::format(", sinusoid {:g} deg/h at {:g} Hz", w.amplitude_deg_per_h, w.frequency_hz);
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"recovery_study: Monte Carlo recovery of simulated gyros by the IEEE-952 fit.", "recovery_study"};
  app.footer(R"(Each scenario (a simulated gyro, tests/support/recovery.cpp) runs RUNS times with independent
seeds through the analyzer and its recommended fit of both curves. For every term: runs where the
term is resolved; of the resolved ones with a non-zero truth, the share within 1 and 2 stated
standard uncertainties; and runs where a term whose truth is zero is resolved ("false").

Examples:
  recovery_study                 the full study (100 runs per scenario)
  recovery_study --runs 20       a quick look
  recovery_study --only long-run the long-run scenarios alone
  recovery_study --except long-run every other scenario)");
  RecoverySettings s;
  app.add_option("--runs", s.runs, "runs per scenario")->capture_default_str()->check(CLI::Range(1, 100000));
  app.add_option("--workers", s.workers, "threads")->capture_default_str()->check(CLI::Range(1, 64));
  app.add_option("--seed", s.seed, "base seed (runs are reproducible)")->capture_default_str();
  std::string only;
  app.add_option("--only", only, "run only the scenarios whose name contains this text");
  std::string except;
  app.add_option("--except", except, "leave out the scenarios whose name contains this text");
  CLI11_PARSE(app, argc, argv);
  std::erase_if(s.scenarios, [&](const Scenario& sc) {
    return sc.name.find(only) == std::string::npos || (!except.empty() && sc.name.find(except) != std::string::npos);
  });

  const auto start = std::chrono::steady_clock::now();
  const std::clock_t cpu_start = std::clock();
  s.progress = [&](std::size_t done, std::size_t total) {
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::fprintf(stderr, "\rrecovery_study: %zu of %zu runs, %.0f s   ", done, total, elapsed);
  };
  std::vector<RecoveryCell> cells;
  try {
    cells = run_recovery_study(s);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "\nrecovery_study: %s\n", e.what());
    return 1;
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const double cpu = static_cast<double>(std::clock() - cpu_start) / CLOCKS_PER_SEC;
  std::fprintf(stderr, "\nrecovery_study: %zu scenarios in %.1f s wall time (%u workers), %.1f s CPU time\n", cells.size(),
               wall, s.workers, cpu);

  std::string out;
  auto to = std::back_inserter(out);
  fmt::format_to(to,
                 "{} runs per scenario, independent seeds. Wall time {:.0f} s with {} workers, {:.0f} s of CPU time.\n\n",
                 s.runs, wall, s.workers, cpu);
  // Pooled over the scenarios: every resolved term with a non-zero truth, every term with a zero one.
  std::size_t resolved_present = 0, within1 = 0, within2 = 0, absent = 0, false_resolved = 0;
  for (const RecoveryCell& c : cells)
    for (const TermTally& t : c.terms) {
      resolved_present += t.resolved - t.false_resolved;
      within1 += t.within1;
      within2 += t.within2;
      absent += t.runs - t.present;
      false_resolved += t.false_resolved;
    }
  const double p1 = resolved_present ? static_cast<double>(within1) / static_cast<double>(resolved_present) : 0;
  const double p2 = resolved_present ? static_cast<double>(within2) / static_cast<double>(resolved_present) : 0;
  const double pf = absent ? static_cast<double>(false_resolved) / static_cast<double>(absent) : 0;
  fmt::format_to(to, "| pooled over the scenarios | terms | share (%) | standard error (points) | target |\n");
  fmt::format_to(to, "|---|---:|---:|---:|---|\n");
  fmt::format_to(to, "| resolved terms within 1 stated sigma of the truth | {} | {} | {} | 68 +- 5 |\n", resolved_present,
                 share(within1, resolved_present), error_of(p1, resolved_present));
  fmt::format_to(to, "| resolved terms within 2 stated sigma of the truth | {} | {} | {} | >= 95 |\n", resolved_present,
                 share(within2, resolved_present), error_of(p2, resolved_present));
  fmt::format_to(to, "| terms of zero truth called resolved (false) | {} | {} | {} | <= 5 |\n\n", absent,
                 share(false_resolved, absent), error_of(pf, absent));

  for (std::size_t i = 0; i < cells.size(); ++i) {
    const RecoveryCell& c = cells[i];
    fmt::format_to(to,
                   "### {}\n\n{}. Fits: {} ok, {} rejected, {} too few points, {} singular; quantization found white "
                   "in {} % of the runs; mean chi2/dof {:.2f}.\n\n",
                   c.scenario, describe(s.scenarios[i].sim), c.ok, c.rejected, c.too_few, c.singular,
                   share(c.quantization_white, c.runs), c.mean_chi2_per_dof);
    fmt::format_to(to, "| term | truth | resolved (%) | within 1 sigma (%) | within 2 sigma (%) | false resolved (%) |\n");
    fmt::format_to(to, "|---|---|---:|---:|---:|---:|\n");
    for (std::size_t k = 0; k < tallied_terms; ++k) {
      const TermTally& t = c.terms[k];
      const std::size_t real = t.resolved - t.false_resolved;
      const bool present = t.present > 0;
      std::string resolved = share(t.resolved, t.runs);
      if (t.held) resolved += fmt::format(" (held in {} %)", share(t.held, t.runs));
      fmt::format_to(to, "| {} | {} | {} | {} | {} | {} |\n", tallied_names[k], present ? "present" : "zero", resolved,
                     present ? share(t.within1, real) : "-", present ? share(t.within2, real) : "-",
                     present ? "-" : share(t.false_resolved, t.runs));
    }
    const TermTally& markov = c.terms[5];
    if (markov.present == 0)
      fmt::format_to(to, "A Markov term in the model (resolved or not) where none was simulated: {} % of the runs.\n",
                     share(markov.fitted, markov.runs));
    const TermTally& sinusoid = c.terms[7];
    if (sinusoid.present == 0)
      fmt::format_to(to, "A sinusoid in the model (resolved or not) where none was simulated: {} % of the runs.\n",
                     share(sinusoid.fitted, sinusoid.runs));
    fmt::format_to(to, "\n");
    if (!c.long_tau) continue;
    fmt::format_to(to,
                   "The same runs fitted with the Allan curve's long taus from the total family (docs/total.md): "
                   "statistics over the runs where the term is resolved.");
    for (std::size_t in = 0; in < c.by_long_tau.size(); ++in)
      fmt::format_to(to, " {}: {} of {} fits ok, mean chi2/dof {:.2f}.", long_tau_names[in], c.long_tau_ok[in], c.runs,
                     c.long_tau_chi2[in]);
    fmt::format_to(to, "\n\n");
    fmt::format_to(to,
                   "| term | long taus from | resolved (%) | within 1 sigma (%) | within 2 sigma (%) | mean stated sigma / "
                   "truth | rms error / truth |\n");
    fmt::format_to(to, "|---|---|---:|---:|---:|---:|---:|\n");
    for (std::size_t k = 2; k < 5; ++k)
      for (std::size_t in = 0; in < c.by_long_tau.size(); ++in) {
        const TermTally& t = c.by_long_tau[in][k];
        const std::size_t real = t.resolved - t.false_resolved;
        const double n = static_cast<double>(real);
        fmt::format_to(to, "| {} | {} | {} | {} | {} | {} | {} |\n", tallied_names[k], long_tau_names[in],
                       share(t.resolved, t.runs), share(t.within1, real), share(t.within2, real),
                       real ? fmt::format("{:.3f}", t.sum_relative_uncertainty / n) : "-",
                       real ? fmt::format("{:.3f}", std::sqrt(t.sum_squared_relative_error / n)) : "-");
      }
    fmt::format_to(to, "\n");
  }
  if (std::fwrite(out.data(), 1, out.size(), stdout) != out.size() || std::fflush(stdout) != 0) {
    std::perror("recovery_study: stdout");
    return 3;
  }
  return 0;
}
