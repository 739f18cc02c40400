#pragma once
// What the Monte Carlo studies of the acceptance verdict share (tests/host/test_verdict_montecarlo.cpp
// on the analyzer's path, tests/firmware/test_board_verdict_montecarlo.cpp on the board's and the
// decoder's): the gyros and the limit, the tally of verdicts per cell, its table, the study's size
// from the environment, and the exact binomial tail the tests state their bound with.
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "limits.hpp"
#include "sim_truth.hpp"

namespace gyrochar::test_support {

/// The limit judged, N <= 0.003 deg/sqrt(h), and where the simulated gyros' true N sits against it.
inline constexpr double verdict_limit_n = 0.003;  // deg/sqrt(h)
inline constexpr const char* verdict_limit_text = "N <= 0.003 deg/sqrt(h)\n";
inline constexpr std::array<double, 3> verdict_truth_ratio{0.9, 1.0, 1.1};  // inside, at, beyond
inline constexpr std::array<const char*, 3> verdict_where{"10 % inside", "at the limit", "10 % beyond"};

/// The seed of run r of cell (run length d, gyro c): the same in both studies, so that a cell's
/// run r is the same simulated record on either path.
inline std::uint64_t verdict_seed(std::size_t d, std::size_t c, std::size_t r) { return 1000003 * (d + 1) + 7919 * c + r; }

/// The simulated gyro of run r of cell (run length d lasting `duration_s`, gyro c): white quantization
/// (1 arcsec pulses and a random 1 arcsec dither residue, tau0 0.1 s), its true N at the cell's
/// ratio to the limit.
inline SimOptions verdict_gyro(double duration_s, std::size_t d, std::size_t c, std::size_t r) {
  SimOptions o;
  o.duration_s = duration_s;
  o.tau0_s = 0.1;
  o.white_angle_arcsec = 1;
  o.arw_deg_per_sqrt_h = verdict_limit_n * verdict_truth_ratio[c];
  o.seed = verdict_seed(d, c, r);
  return o;
}

struct VerdictTally {
  std::size_t runs = 0, pass = 0, fail = 0, undecided = 0, resolved = 0;
  std::size_t decided_by_prediction = 0;  // undecided with a predicted decision time <= 4 T
  /// Adds one run's decision of a run of `run_s`.
  void add(const Decision& v, double run_s) {
    ++runs;
    resolved += v.estimate.usable;
    pass += v.verdict == Verdict::pass;
    fail += v.verdict == Verdict::fail;
    undecided += v.verdict == Verdict::undecided;
    decided_by_prediction += v.verdict == Verdict::undecided && v.decide_at_s <= 4 * run_s;
  }
};

/// The number in environment variable `name`, or `fallback` when it is not set.
inline std::size_t env_count(const char* name, std::size_t fallback) {
  const char* env = std::getenv(name);
  return env ? std::strtoul(env, nullptr, 10) : fallback;
}

/// The run lengths (s) in environment variable `name` ("900,3600,14400"), or `fallback`.
inline std::vector<double> env_durations(const char* name, std::vector<double> fallback) {
  const char* env = std::getenv(name);
  if (!env) return fallback;
  std::vector<double> durations;
  for (const char* p = env; *p;) {
    char* end = nullptr;
    durations.push_back(std::strtod(p, &end));
    p = *end == ',' ? end + 1 : end;
    if (end == p && *p) break;
  }
  return durations;
}

/// The table of the study (docs/metrology.md, "Monte Carlo of the verdict", shows it as markdown):
/// a row per run length and gyro.
inline void print_verdict_table(const std::vector<double>& durations,
                                const std::vector<std::array<VerdictTally, 3>>& tally) {
  std::printf("true N         run    runs  resolved  pass  fail  undecided  (undecided expected to decide by 4 T)\n");
  for (std::size_t d = 0; d < durations.size(); ++d)
    for (std::size_t c = 0; c < verdict_truth_ratio.size(); ++c) {
      const VerdictTally& t = tally[d][c];
      std::printf("%-13s %5.0f s %5zu %9zu %5zu %5zu %10zu  %zu\n", verdict_where[c], durations[d], t.runs, t.resolved,
                  t.pass, t.fail, t.undecided, t.decided_by_prediction);
    }
}

/// P(X >= k) for X binomial with n trials of probability p, summed exactly term by term. O(n).
inline double binomial_tail(std::size_t n, std::size_t k, double p) {
  double sum = 0, term = std::pow(1 - p, static_cast<double>(n));  // P(X = 0)
  for (std::size_t j = 0; j <= n; ++j) {
    if (j >= k) sum += term;
    term *= static_cast<double>(n - j) / static_cast<double>(j + 1) * p / (1 - p);
  }
  return sum;
}

}  // namespace gyrochar::test_support
