// Coverage of the offline engine's 68.3 % confidence intervals, a small and fast version of the
// study in docs/metrology.md (tests/benchmarks/coverage_study.cpp, same harness and seeds).
// Oracle: the exact expectation of AVAR and MVAR of the generated noise (closed forms for white PM
// 3/m^2, 3/m^3 and white FM 1/m, (m^2+1)/(2m^3); tests/support/power_law_noise.hpp), and the
// nominal coverage 0.682689 of a 1-sigma interval.
//
// 400 runs of N = 4096 phase points, white PM and white FM, OADEV and MDEV at m = 1 .. 64, stride
// factor full and 8, with the noise identified by the engine and with the true alpha given.
//  - Each cell: the binomial standard error of a coverage of 68.3 % over 400 runs is 2.3 points, so
//    the bound of 10 points is 4.3 standard errors: a correct engine fails one of these 112 cell
//    checks with probability about 0.2 %.
//  - Pooled over the 56 cells: the bound of 2.5 points tells 68 % from 63 %. The cells come from
//    800 independent realizations (400 per alpha, each analyzed at every m, both statistics and
//    both stride factors), so the pooled coverage's standard error lies between 0.3 points (cells
//    independent) and 1.6 points (cells of a realization moving together).
// The seeds are fixed, so the outcome is too. The full study (docs/metrology.md) has 1000 runs per
// cell and N = 65536 as well.
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

TEST(Coverage, WhiteNoiseIntervalsHoldTheTruthAboutTwoThirdsOfTheTime) {
  const StudySettings s = small_study(400, 2);
  const std::vector<CoverageCell> cells = run_coverage_study(s);
  ASSERT_EQ(cells.size(), 2u * 2u * 2u * 7u);  // stride factors x stats x alphas x m = 1 .. 64
  double pooled_auto = 0, pooled_true = 0;
  std::printf("stride stat  alpha    m  terms  auto   true   id    edf(true)  MC edf  mean dev^2/truth\n");
  for (const CoverageCell& c : cells) {
    std::printf("%-6s %-5s %+d %6llu %6llu  %.3f  %.3f  %.2f  %8.0f  %7.0f  %.4f\n", c.stride_factor == 0 ? "full" : "8",
                name(c.stat), c.alpha, static_cast<unsigned long long>(c.m), static_cast<unsigned long long>(c.terms),
                c.coverage_auto(), c.coverage_true(), c.identified_fraction(), c.edf_true, c.mc_edf, c.mean_ratio);
    const std::string where = std::string(name(c.stat)) + " alpha " + std::to_string(c.alpha) + " m " + std::to_string(c.m) +
                              " stride factor " + std::to_string(c.stride_factor);
    EXPECT_EQ(c.runs, s.runs) << where;
    EXPECT_EQ(c.no_interval_true, 0u) << where;
    EXPECT_NEAR(c.coverage_true(), nominal, 0.10) << where;
    EXPECT_NEAR(c.coverage_auto(), nominal, 0.10) << where;
    pooled_auto += c.coverage_auto() / static_cast<double>(cells.size());
    pooled_true += c.coverage_true() / static_cast<double>(cells.size());
    // The estimate itself is unbiased: the mean of dev^2 / truth over the runs is within 4 standard
    // errors (sqrt(2 / EDF / runs), EDF from the runs themselves) of 1.
    EXPECT_NEAR(c.mean_ratio, 1.0, 4.0 * std::sqrt(2.0 / c.mc_edf / static_cast<double>(c.runs))) << where;
  }
  std::printf("pooled coverage: %.4f with the identified alpha, %.4f with the true one\n", pooled_auto, pooled_true);
  EXPECT_NEAR(pooled_auto, nominal, 0.025);
  EXPECT_NEAR(pooled_true, nominal, 0.025);
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
