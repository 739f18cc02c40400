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
#include <vector>

#include "acceptance.hpp"
#include "limits.hpp"
#include "support/recovery.hpp"
#include "support/verdict_study.hpp"

namespace gyrochar::test_support {
namespace {

TEST(VerdictMonteCarlo, WrongVerdictsStayWithinTheStatedRiskAndUndecidedShrinks) {
  const std::size_t runs = env_count("GYROCHAR_VERDICT_RUNS", 40);
  const Limit limit = parse_limits(verdict_limit_text).front();
  const std::vector<double> durations = env_durations("GYROCHAR_VERDICT_DURATIONS", {900, 3600});
  ASSERT_GE(durations.size(), 2u);
  std::vector<std::array<VerdictTally, 3>> tally(durations.size());
  for (std::size_t d = 0; d < durations.size(); ++d)
    for (std::size_t c = 0; c < verdict_truth_ratio.size(); ++c)
      for (std::size_t r = 0; r < runs; ++r) {
        const SimOptions o = verdict_gyro(durations[d], d, c, r);
        const Recovery rec = recover(o);
        const Ieee952Fit& fit = rec.fit();
        const Ieee952Parameter& n = fit.p[1];
        const LimitEstimate e = fit.ok() && n.fitted && n.resolved ? fitted_term_estimate(n, o.duration_s)
                                                                   : no_estimate("not resolved");
        tally[d][c].add(decide(limit, e), o.duration_s);
      }
  print_verdict_table(durations, tally);
  // Binomial bound of the header: fewer than 5 wrong verdicts in 40 runs (scaled for other counts).
  const double bound = runs == 40
                           ? 4.0
                           : 0.025 * static_cast<double>(runs) + 3 * std::sqrt(0.025 * 0.975 * static_cast<double>(runs));
  for (std::size_t d = 0; d < durations.size(); ++d) {
    EXPECT_LE(static_cast<double>(tally[d][0].fail), bound) << "fail for a gyro inside, run " << durations[d] << " s";
    EXPECT_LE(static_cast<double>(tally[d][2].pass), bound) << "pass for a gyro beyond, run " << durations[d] << " s";
    EXPECT_LE(static_cast<double>(tally[d][1].pass), bound) << "pass at the limit (the boundary: at most the risk)";
    EXPECT_LE(static_cast<double>(tally[d][1].fail), bound) << "fail at the limit";
    for (const VerdictTally& t : tally[d]) EXPECT_EQ(t.resolved, t.runs) << "N is resolved in every run of this gyro";
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
