// Coverage of the offline engine's 68.3 % confidence intervals, a small and fast version of the
// study in docs/metrology.md (tests/benchmarks/coverage_study.cpp, same harness and seeds).
// Oracle: the exact expectation of AVAR and MVAR of the generated noise (closed forms for white PM
// 3/m^2, 3/m^3 and white FM 1/m, (m^2+1)/(2m^3); tests/support/power_law_noise.hpp), and the
// nominal coverage 0.682689 of a 1-sigma interval.
//
// 400 runs of N = 4096 phase points, white PM and white FM, OADEV and MDEV at m = 1 .. 64, stride
// factor full and 8. The binomial standard error of a coverage of 68.3 % over 400 runs is 2.3
// points, so the bound of 10 points is 4.3 standard errors: a correct engine fails one of these
// 56 cells with probability about 0.1 %. The seeds are fixed, so the outcome is too.
//
// Cells the current engine is known to get wrong, measured with 1000 runs (docs/metrology.md);
// they are inside the loose bound or left out of it, and are to be tightened when the engine's EDF
// and noise identification are rewritten:
//  - white FM at m = 1, both statistics: 64.8 % with the true alpha. Greenhall's EDF is 3204 where
//    the estimator's is about 2700 (Monte Carlo 2694; design brief section 3): intervals 9 % narrow.
//  - white FM OADEV at m = 4: 72.6 %. The stated EDF 1258 is 12 % below the exact 1422 (from the
//    term autocovariance 8, 5, 2, -1, -4, -3, -2, -1; Monte Carlo 1426): intervals too wide.
//  - white PM with the identified alpha at m = 32 and 64, fully overlapped OADEV: 74.2 % and
//    76.2 %, because the lag-1 identifier calls 18 % and 24 % of these runs flicker PM, whose
//    smaller EDF (for unmodified AVAR) widens the interval. Not asserted with the identified alpha
//    (the true-alpha cells are).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "support/coverage.hpp"

namespace gyrochar::test_support {
namespace {

constexpr double nominal = 0.682689492137086;

StudySettings small_study(std::size_t runs, unsigned workers) {
  StudySettings s;
  s.alphas = {2, 0};
  s.lengths = {4096};
  s.stride_factors = {0, 8};
  s.stats = {Statistic::oadev, Statistic::mdev};
  s.max_m = 64;
  s.runs = runs;
  s.workers = workers;
  s.seed = 1;
  return s;
}

// The lag-1 identifier is unreliable here with the current engine (see the file comment).
bool identification_known_wrong(const CoverageCell& c) {
  return c.alpha == 2 && c.m >= 32 && c.stat == Statistic::oadev && c.stride_factor == 0;
}

TEST(Coverage, WhiteNoiseIntervalsHoldTheTruthAboutTwoThirdsOfTheTime) {
  const StudySettings s = small_study(400, 2);
  const std::vector<CoverageCell> cells = run_coverage_study(s);
  ASSERT_EQ(cells.size(), 2u * 2u * 2u * 7u);  // stride factors x stats x alphas x m = 1 .. 64
  std::printf("stride stat  alpha    m  terms  auto   true   id    edf(true)  MC edf  mean dev^2/truth\n");
  for (const CoverageCell& c : cells) {
    std::printf("%-6s %-5s %+d %6llu %6llu  %.3f  %.3f  %.2f  %8.0f  %7.0f  %.4f\n",
                c.stride_factor == 0 ? "full" : "8", name(c.stat), c.alpha, static_cast<unsigned long long>(c.m),
                static_cast<unsigned long long>(c.terms), c.coverage_auto(), c.coverage_true(), c.identified_fraction(),
                c.edf_true, c.mc_edf, c.mean_ratio);
    const std::string where = std::string(name(c.stat)) + " alpha " + std::to_string(c.alpha) + " m " +
                              std::to_string(c.m) + " stride factor " + std::to_string(c.stride_factor);
    EXPECT_EQ(c.runs, s.runs) << where;
    EXPECT_EQ(c.no_interval_true, 0u) << where;
    EXPECT_NEAR(c.coverage_true(), nominal, 0.10) << where;
    if (!identification_known_wrong(c)) {
      EXPECT_NEAR(c.coverage_auto(), nominal, 0.10) << where;
    }
    // The estimate itself is unbiased: the mean of dev^2 / truth over the runs is within 4 standard
    // errors (sqrt(2 / EDF / runs), EDF from the runs themselves) of 1.
    EXPECT_NEAR(c.mean_ratio, 1.0, 4.0 * std::sqrt(2.0 / c.mc_edf / static_cast<double>(c.runs))) << where;
  }
}

TEST(Coverage, ResultsDoNotDependOnTheNumberOfWorkers) {
  const auto one = run_coverage_study(small_study(12, 1));
  const auto two = run_coverage_study(small_study(12, 2));
  ASSERT_EQ(one.size(), two.size());
  for (std::size_t i = 0; i < one.size(); ++i) {
    EXPECT_EQ(one[i].covered_auto, two[i].covered_auto);
    EXPECT_EQ(one[i].covered_true, two[i].covered_true);
    EXPECT_EQ(one[i].identified, two[i].identified);
    EXPECT_EQ(one[i].mean_edf_auto, two[i].mean_edf_auto);
    EXPECT_EQ(one[i].mean_ratio, two[i].mean_ratio);
  }
}

TEST(Coverage, TrueVarianceIsTheClosedForm) {
  // The values the harness compares with: closed forms (design brief section 3).
  EXPECT_NEAR(true_variance(2, Statistic::oadev, 8) / (3.0 / 64.0), 1.0, 1e-12);
  EXPECT_NEAR(true_variance(2, Statistic::mdev, 8) / (3.0 / 512.0), 1.0, 1e-12);
  EXPECT_NEAR(true_variance(0, Statistic::oadev, 8) / (1.0 / 8.0), 1.0, 1e-12);
  EXPECT_NEAR(true_variance(0, Statistic::mdev, 8) / (65.0 / 1024.0), 1.0, 1e-12);
}

}  // namespace
}  // namespace gyrochar::test_support
