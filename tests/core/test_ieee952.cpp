// IEEE-952 weighted fit. Oracles: the model itself (exact curves must give back their parameters)
// and Monte Carlo with chi-squared scatter of known EDF (each parameter within its stated
// standard uncertainty about 68 % of the time).
#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "gyrochar/ieee952.hpp"

namespace gyrochar {
namespace {

// Q N B K R (rad, s), chosen so that each term dominates the curve over about a decade of tau.
const std::array<double, 5> truth{5.5e-7, 3e-6, 4.5e-7, 9.4e-9, 3.4e-11};

std::vector<VariancePoint> curve(const std::array<double, 5>& p, Ieee952Curve c, double tau0, double edf) {
  std::vector<VariancePoint> pts;
  for (double tau = tau0; tau < 2e5; tau *= 2) pts.push_back({tau, ieee952_variance(p, tau, c, tau0), edf});
  return pts;
}

TEST(Ieee952, ExactCurvesGiveTheirParametersBack) {
  for (auto c : {Ieee952Curve::avar, Ieee952Curve::mvar}) {
    const auto fit = fit_ieee952(curve(truth, c, 0.01, 200), c, 0.01);
    ASSERT_TRUE(fit.ok);
    for (int k = 0; k < 5; ++k) {
      EXPECT_TRUE(fit.p[k].resolved) << k;
      EXPECT_NEAR(fit.p[k].value / truth[k], 1.0, 1e-6) << "term " << k;
    }
    EXPECT_LT(fit.chi2_per_dof, 1e-9);
  }
}

TEST(Ieee952, MissingTermIsNotResolved) {
  auto p = truth;
  p[4] = 0;  // no rate ramp
  const auto fit = fit_ieee952(curve(p, Ieee952Curve::avar, 0.01, 200), Ieee952Curve::avar, 0.01);
  ASSERT_TRUE(fit.ok);
  EXPECT_LT(fit.p[4].value, 1e-3 * truth[4] + fit.p[4].uncertainty * 3);
  for (int k = 0; k < 4; ++k) EXPECT_NEAR(fit.p[k].value / truth[k], 1.0, 1e-4) << k;
}

TEST(Ieee952, StatedUncertaintyCoversTheTruth) {
  std::mt19937_64 rng(952);
  const double edf = 50;
  std::chi_squared_distribution<double> chi2(edf);
  const auto exact = curve(truth, Ieee952Curve::avar, 0.01, edf);
  std::array<int, 5> within{};
  const int trials = 300;
  for (int t = 0; t < trials; ++t) {
    auto pts = exact;
    for (auto& pt : pts) pt.variance *= chi2(rng) / edf;
    const auto fit = fit_ieee952(pts, Ieee952Curve::avar, 0.01);
    ASSERT_TRUE(fit.ok);
    for (int k = 0; k < 5; ++k)
      if (std::fabs(fit.p[k].value - truth[k]) <= fit.p[k].uncertainty) ++within[k];
  }
  for (int k = 0; k < 5; ++k) {
    const double coverage = static_cast<double>(within[k]) / trials;
    EXPECT_GT(coverage, 0.55) << "term " << k;
    EXPECT_LT(coverage, 0.85) << "term " << k;
    std::printf("term %d: %.1f %% within 1 sigma\n", k, 100 * coverage);
  }
}

}  // namespace
}  // namespace gyrochar
