#pragma once
// Monte Carlo coverage of the offline engine's confidence intervals: simulate power-law noise of a
// known exponent many times, let the engine estimate each deviation with its interval, and count
// how often the interval holds the true deviation. Used by tests/benchmarks/coverage_study.cpp
// (the full study, docs/metrology.md) and tests/host/test_coverage.cpp (a small, fast version).
//
// Every use of the engine's API (host_tools/analyze/analysis.hpp) is in run_engine(), and every true
// value comes from true_variance(): the engine is being rewritten, and only these two functions
// know how it is called and what it is compared with.
#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

namespace gyrochar::test_support {

enum class Statistic { oadev, mdev };
/// "oadev" or "mdev". Static string.
const char* name(Statistic s);

/// What is asked of the engine: phase data, tau0 = 1 s, confidence 0.682689 (1 sigma).
struct EngineRequest {
  std::vector<std::uint64_t> m_list;  // averaging factors, strictly increasing
  std::vector<Statistic> stats;
  std::uint32_t stride_factor = 0;  // 0: full (every tau fully overlapped); else S, a power of two
  std::optional<int> alpha;         // noise exponent given for the EDF; empty: the engine identifies it
};

/// One estimate as the engine states it (tau0 = 1, so deviations are in phase units per sample).
struct EngineEstimate {
  Statistic stat = Statistic::oadev;
  std::uint64_t m = 0;
  std::uint64_t terms = 0;   // number of terms in the estimate
  std::uint64_t stride = 1;  // terms every `stride` phase points
  double dev = 0.0;
  double ci_low = 0.0, ci_high = 0.0;
  bool ci_valid = false;     // false: the engine gave no interval
  std::optional<int> alpha;  // exponent the engine used (given or identified)
  double edf = 0.0;          // EDF the engine stated (0: none)
};

/// The adapter: runs the offline engine over `phase` (phase points, tau0 = 1) and returns its
/// estimates by statistic (in the order asked), then m; an (m, stat) with no term has no estimate.
/// O(phase.size() x taus), allocates the engine. Throws what the engine throws (std::invalid_argument
/// for a request it refuses).
std::vector<EngineEstimate> run_engine(const std::vector<double>& phase, const EngineRequest& request);

/// The true variance (AVAR for oadev, MVAR for mdev) of power-law noise of exponent alpha (-2..+2)
/// as made by power_law_phase(), at averaging factor m, tau0 = 1: expected_variance() of
/// power_law_noise.hpp, cached (thread-safe). O(m) the first time, then O(log cells).
double true_variance(int alpha, Statistic stat, std::uint64_t m);

struct StudySettings {
  std::vector<int> alphas{2, 1, 0, -1, -2};
  std::vector<std::size_t> lengths{4096};        // phase points per run
  std::vector<std::uint32_t> stride_factors{0};  // 0: full, else S
  std::vector<Statistic> stats{Statistic::oadev, Statistic::mdev};
  std::uint64_t max_m = 0;  // largest averaging factor; 0: every octave with a term
  std::size_t runs = 1000;  // independent realizations per (length, alpha)
  unsigned workers = 2;     // threads; results do not depend on it
  std::uint64_t seed = 1;   // run r of (length, alpha) is seeded by a hash of all four
  /// Called on the calling thread about once a second and at the end: realizations done, total.
  std::function<void(std::size_t done, std::size_t total)> progress;
};

/// The tally of one (length, stride factor, statistic, alpha, m) over the runs. "auto": the
/// engine identified alpha; "true": the engine was given the true alpha (same estimate, only the
/// EDF and so the interval differ), so EDF errors and identification errors can be told apart.
struct CoverageCell {
  std::size_t length = 0;
  std::uint32_t stride_factor = 0;
  Statistic stat = Statistic::oadev;
  int alpha = 0;
  std::uint64_t m = 0;
  std::uint64_t terms = 0;   // terms per estimate
  std::uint64_t stride = 1;  // terms every `stride` points
  double true_dev = 0.0;
  std::size_t runs = 0;
  std::size_t covered_auto = 0, covered_true = 0;  // intervals holding true_dev
  std::size_t no_interval_auto = 0, no_interval_true = 0;
  std::size_t identified_right = 0;
  std::array<std::size_t, 6> identified{};  // runs identified as +2, +1, 0, -1, -2, anything else or none
  double mean_edf_auto = 0.0;               // mean EDF stated with the identified alpha (runs with one)
  double edf_true = 0.0;                    // EDF stated with the true alpha (mean; the same every run)
  double mean_ratio = 0.0;                  // mean of dev^2 / true variance (1: unbiased)
  double mc_edf = 0.0;                      // 2 mean^2 / variance of dev^2 / true variance over the runs
  double coverage_auto() const { return runs ? double(covered_auto) / double(runs) : 0.0; }
  double coverage_true() const { return runs ? double(covered_true) / double(runs) : 0.0; }
  double identified_fraction() const { return runs ? double(identified_right) / double(runs) : 0.0; }
};

/// Runs the study: for each length, alpha and run one realization of power_law_phase(), analyzed
/// by run_engine() once per stride factor with alpha identified and once with the true alpha.
/// Work is spread over `workers` threads; the calling thread reduces the finished realizations
/// in task order, so the result is the same for any number of workers. Cells come out by length,
/// stride factor, statistic, alpha (each as listed in the settings), then m. Time: runs x
/// lengths x alphas realizations, each O(N log N) to make and O(N x taus) per engine pass (2 per
/// stride factor). Memory: the cells plus the estimates of the realizations finished ahead of the
/// oldest unfinished one. Rethrows the first exception of a worker (the engine's or the generator's).
std::vector<CoverageCell> run_coverage_study(const StudySettings& settings);

/// The binomial standard error of a coverage p over `runs` runs: sqrt(p (1 - p) / runs).
double coverage_standard_error(double p, std::size_t runs);

}  // namespace gyrochar::test_support
