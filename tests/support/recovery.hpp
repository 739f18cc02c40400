#pragma once
// Monte Carlo recovery of simulated gyros by the IEEE-952 fit: simulate a gyro with known
// parameters many times (gyrochar-sim's simulator), analyze its counts as gyrochar-analyze does
// (the characterizer, the exact EDFs, the recommended fit of both curves) and count how often each
// fitted term lies within one and two of its stated standard uncertainties of the truth, and how
// often a term whose truth is zero is nevertheless called resolved. Used by
// tests/benchmarks/recovery_study.cpp (the full study, docs/metrology.md) and
// tests/host/test_recovery.cpp (a small, fast version).
//
// Long-tau scenarios also fit the same run twice more with total-family estimates standing in for
// OADEV on the Allan curve (docs/total.md, docs/metrology.md): TOTDEV, bias-corrected, wherever
// SP 1065's EDF for it exceeds the OADEV estimate's; and TheoH: OADEV below its switch point k,
// TheoBR points (Theo1 times the data's bias ratio) from tau = 1.5 k on, as far as an Allan
// geometry exists (tau <= T/2). Every fit is the recommended one of both curves.
#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "gyrochar/ieee952.hpp"
#include "analysis_report.hpp"
#include "sim_truth.hpp"

namespace gyrochar::test_support {

/// One simulated gyro of the study: a name for the tables and the simulator's options (the seed
/// is replaced per run).
struct Scenario {
  std::string name;
  SimOptions sim;
  bool long_tau = false;  // also fit with TOTDEV and with TheoH at long tau
};

/// Names of the fits by LongTau (analysis_report.hpp) in the study's tables.
inline constexpr std::array<const char*, 3> long_tau_names{"OADEV", "TOTDEV", "TheoH"};

/// The grid of docs/metrology.md: quantization made white by a random dither residue and left
/// periodic (no dither), angle random walk, bias instability, rate random walk and rate ramp in
/// the combinations of the issue's reports and a complete RLG; then one long-run gyro (every term
/// but Q dominating somewhere, the ramp only after 17 h) over 24 h and 120 h, and the same gyro
/// without the ramp over 24 h, with long_tau set; and gyros with one and two Markov terms, a
/// sinusoid, and a sinusoid beside a Markov term.
std::vector<Scenario> standard_scenarios();

/// One run: the fits (by LongTau; only OADEV's unless long_tau) and the truth (SI units).
struct Recovery {
  std::array<Ieee952Fit, 3> fits;
  Ieee952Truth truth;
  const Ieee952Fit& fit() const { return fits[0]; }
};

/// Simulates `sim`, analyzes the counts (stride factor full, octave taus), looks for sinusoids in
/// the rate's PSD as gyrochar-analyze does (Welch, default segment, 1 % false alarms) and fits both
/// curves with the ones found offered;
/// with long_tau also with TOTDEV and TheoH on the Allan curve (holding the run's phase, 8 bytes a
/// sample). O(samples). Throws what the analyzer throws.
Recovery recover(const SimOptions& sim, bool long_tau = false);

/// The terms tallied: Q N B K R, then a Markov term's sigma and its Tc (each simulated Markov term
/// against the fitted one nearest in ln Tc; with none simulated, a resolved one is "false"), then a
/// sinusoid's amplitude (each simulated one against the fitted one nearest in frequency; likewise).
inline constexpr std::size_t tallied_terms = 8;
inline constexpr std::array<const char*, tallied_terms> tallied_names{"Q",         "N",         "B",
                                                                      "K",         "R",         "Markov sigma",
                                                                      "Markov Tc", "Sinusoid A"};

/// The tally of one term over the runs of a scenario.
struct TermTally {
  std::size_t runs = 0;
  std::size_t present = 0;                // runs whose truth is not zero
  std::size_t fitted = 0;                 // the fit kept the term in its model
  std::size_t resolved = 0;               // ... and called it resolved
  std::size_t within1 = 0, within2 = 0;   // resolved and within 1 (2) stated sigma of a non-zero truth
  std::size_t false_resolved = 0;         // resolved although the truth is zero
  std::size_t held = 0;                   // not fitted but held at a known value (Q of periodic quantization)
  double sum_relative_uncertainty = 0;    // over resolved runs of a non-zero truth: stated sigma / truth
  double sum_squared_relative_error = 0;  // ... and ((value - truth) / truth)^2
};

struct RecoveryCell {
  std::string scenario;
  std::size_t runs = 0;
  std::size_t ok = 0, rejected = 0, too_few = 0, singular = 0;  // fit status counts
  std::size_t quantization_white = 0;                           // runs that found it white
  double mean_chi2_per_dof = 0;
  std::array<TermTally, tallied_terms> terms{};  // the OADEV fit
  bool long_tau = false;
  std::array<std::array<TermTally, tallied_terms>, 3> by_long_tau{};  // long_tau: every fit by LongTau
  std::array<std::size_t, 3> long_tau_ok{};                           // ... its fits with status ok
  std::array<double, 3> long_tau_chi2{};                              // ... their mean chi2/dof
};

struct RecoverySettings {
  std::vector<Scenario> scenarios = standard_scenarios();
  std::size_t runs = 100;  // per scenario
  unsigned workers = 2;    // results do not depend on it
  std::uint64_t seed = 1;  // run r of scenario s is seeded by a hash of both and this
  std::function<void(std::size_t done, std::size_t total)> progress;
};

std::vector<RecoveryCell> run_recovery_study(const RecoverySettings& settings);

}  // namespace gyrochar::test_support
