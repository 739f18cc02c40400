// The acceptance verdict (common/limits.hpp) by Monte Carlo: simulated gyros (gyrochar-sim's
// simulator, analyzed and fitted as gyrochar-analyze --fit ieee952 does: support/recovery.hpp)
// whose true angle random walk N sits 10 % inside the limit, at it, and 10 % beyond it, judged
// against N <= 0.003 deg/sqrt(h) after runs of 15 minutes and 1 hour. Oracles: the stated risk of the rule, a
// wrong verdict ("fail" for a gyro within the limit, "pass" for one beyond it) in at most 2.5 % of
// the runs; with 40 runs a cell, 5 or more wrong ones would happen with a chance of 0.31 % at a true
// rate of 2.5 % (binomial tail, computed exactly: sum over k >= 5 of C(40,k) 0.025^k 0.975^(40-k)
// = 0.0031), the bound tested. And the model of the decision time: the interval narrows as
// 1/sqrt(run length), so longer runs leave fewer gyros undecided away from the limit, and the
// forecast of the undecided ones (decide_at_s <= 4 T, the last column) is printed beside.
// GYROCHAR_VERDICT_RUNS=N runs N a cell and GYROCHAR_VERDICT_DURATIONS=900,3600,14400 other run
// lengths (s); the table is printed (docs/metrology.md, "Acceptance limits and verdicts", has the
// larger study's figures).
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "acceptance.hpp"
#include "limits.hpp"
#include "support/recovery.hpp"

namespace gyrochar::test_support {
namespace {

struct Tally {
  std::size_t runs = 0, pass = 0, fail = 0, undecided = 0, resolved = 0;
  std::size_t decided_by_prediction = 0;  // undecided with a predicted decision time <= 4 T
};

TEST(VerdictMonteCarlo, WrongVerdictsStayWithinTheStatedRiskAndUndecidedShrinks) {
  std::size_t runs = 40;
  if (const char* env = std::getenv("GYROCHAR_VERDICT_RUNS")) runs = std::strtoul(env, nullptr, 10);
  const double limit_n = 0.003;  // deg/sqrt(h)
  Limit limit = parse_limits("N <= 0.003 deg/sqrt(h)\n").front();
  constexpr std::array<double, 3> truth_ratio{0.9, 1.0, 1.1};  // inside, at, beyond
  constexpr std::array<const char*, 3> where{"10 % inside", "at the limit", "10 % beyond"};
  std::vector<double> durations{900, 3600};
  if (const char* env = std::getenv("GYROCHAR_VERDICT_DURATIONS")) {  // "900,3600,14400"
    durations.clear();
    for (const char* p = env; *p;) {
      char* end = nullptr;
      durations.push_back(std::strtod(p, &end));
      p = *end == ',' ? end + 1 : end;
      if (end == p && *p) break;
    }
  }
  ASSERT_GE(durations.size(), 2u);
  std::vector<std::array<Tally, 3>> tally(durations.size());
  for (std::size_t d = 0; d < durations.size(); ++d)
    for (std::size_t c = 0; c < truth_ratio.size(); ++c)
      for (std::size_t r = 0; r < runs; ++r) {
        SimOptions o;
        o.duration_s = durations[d];
        o.tau0_s = 0.1;
        o.white_angle_arcsec = 1;  // a random dither residue: white quantization
        o.arw_deg_per_sqrt_h = limit_n * truth_ratio[c];
        o.seed = 1000003 * (d + 1) + 7919 * c + r;
        const Recovery rec = recover(o);
        const Ieee952Fit& fit = rec.fit();
        const Ieee952Parameter& n = fit.p[1];
        const LimitEstimate e = fit.ok() && n.fitted && n.resolved ? fitted_term_estimate(n, o.duration_s)
                                                                   : no_estimate("not resolved");
        const Decision v = decide(limit, e);
        Tally& t = tally[d][c];
        ++t.runs;
        t.resolved += e.usable;
        t.pass += v.verdict == Verdict::pass;
        t.fail += v.verdict == Verdict::fail;
        t.undecided += v.verdict == Verdict::undecided;
        t.decided_by_prediction += v.verdict == Verdict::undecided && v.decide_at_s <= 4 * o.duration_s;
      }
  std::printf("true N         run    runs  resolved  pass  fail  undecided  (undecided expected to decide by 4 T)\n");
  for (std::size_t d = 0; d < durations.size(); ++d)
    for (std::size_t c = 0; c < truth_ratio.size(); ++c) {
      const Tally& t = tally[d][c];
      std::printf("%-13s %5.0f s %5zu %9zu %5zu %5zu %10zu  %zu\n", where[c], durations[d], t.runs, t.resolved, t.pass,
                  t.fail, t.undecided, t.decided_by_prediction);
    }
  // Binomial bound of the header: fewer than 5 wrong verdicts in 40 runs (scaled for other counts).
  const double bound = runs == 40
                           ? 4.0
                           : 0.025 * static_cast<double>(runs) + 3 * std::sqrt(0.025 * 0.975 * static_cast<double>(runs));
  for (std::size_t d = 0; d < durations.size(); ++d) {
    EXPECT_LE(static_cast<double>(tally[d][0].fail), bound) << "fail for a gyro inside, run " << durations[d] << " s";
    EXPECT_LE(static_cast<double>(tally[d][2].pass), bound) << "pass for a gyro beyond, run " << durations[d] << " s";
    EXPECT_LE(static_cast<double>(tally[d][1].pass), bound) << "pass at the limit (the boundary: at most the risk)";
    EXPECT_LE(static_cast<double>(tally[d][1].fail), bound) << "fail at the limit";
    for (const Tally& t : tally[d]) EXPECT_EQ(t.resolved, t.runs) << "N is resolved in every run of this gyro";
  }
  // Undecided shrinks with the run: pooled over the gyros off the limit, first and last run length.
  const auto& first = tally.front();
  const auto& last = tally.back();
  EXPECT_LT(last[0].undecided + last[2].undecided, first[0].undecided + first[2].undecided)
      << "a longer run leaves fewer undecided";
  EXPECT_GT(last[0].pass, first[0].pass) << "more gyros within the limit pass";
  EXPECT_GT(last[2].fail, first[2].fail) << "more gyros beyond the limit fail";
}

}  // namespace
}  // namespace gyrochar::test_support
