// The power-law noise generator of tests/support and the exact expectations it is checked with.
// Oracles: closed forms (white PM, white FM, random walk FM; sum_k C(a, k)^2 = Gamma(2a+1) /
// Gamma(a+1)^2 for the flicker filters at m = 1; NIST SP 1065's flicker FM floor 2 ln2 h_-1 and the
// MVAR/AVAR ratio 0.675), a brute-force convolution of the Kasdin response with the difference
// kernel, and the mean of the estimators over many independent realizations.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

#include "support/power_law_noise.hpp"

namespace gyrochar::test_support {
namespace {

double closed_form(int alpha, Variance v, double m) {
  const bool a = v == Variance::avar;
  switch (alpha) {
    case 2: return a ? 3.0 / (m * m) : 3.0 / (m * m * m);
    case 0: return a ? 1.0 / m : (m * m + 1.0) / (2.0 * m * m * m);
    case -2: return a ? m / 3.0 + 1.0 / (6.0 * m) : (11.0 * m * m * m * m + 5.0 * m * m + 4.0) / (40.0 * m * m * m);
  }
  return NAN;
}

TEST(ExpectedVariance, IntegerExponentsMatchTheClosedForms) {
  for (const int alpha : {2, 0, -2})
    for (const Variance v : {Variance::avar, Variance::mvar})
      for (const std::uint64_t m : {1, 2, 3, 5, 8, 64, 1000, 16384}) {
        const double want = closed_form(alpha, v, static_cast<double>(m));
        EXPECT_NEAR(expected_variance(alpha, v, m) / want, 1.0, 1e-12) << alpha << " " << (v == Variance::avar) << " " << m;
      }
}

TEST(ExpectedVariance, FlickerAtUnitAveragingFactorMatchesTheBinomialSum) {
  // m = 1: AVAR = MVAR = Var[(1 - B)^2 x] / 2 = sum_k C(2 - d, k)^2 / 2 = Gamma(5 - 2d) / Gamma(3 - d)^2 / 2.
  for (const int alpha : {1, -1}) {
    const double d = (2.0 - alpha) / 2.0;
    const double want = std::tgamma(5.0 - 2.0 * d) / std::pow(std::tgamma(3.0 - d), 2) / 2.0;
    EXPECT_NEAR(expected_variance(alpha, Variance::avar, 1) / want, 1.0, 1e-10) << alpha;
    EXPECT_NEAR(expected_variance(alpha, Variance::mvar, 1) / want, 1.0, 1e-10) << alpha;
  }
  EXPECT_NEAR(expected_variance(-1, Variance::avar, 1), 2.0 / std::numbers::pi, 1e-10);
}

TEST(ExpectedVariance, FlickerMatchesTheBruteForceFilterSum) {
  // The filter of the term, formed by explicit convolution of the Kasdin response (2^20
  // coefficients: the omitted tail is below 1e-10 of the sum for m <= 16) with the difference
  // kernel of the term on x (AVAR: 1, -2, 1 at lags 0, m, 2m; MVAR: m ones, m times -2, m ones),
  // then the sum of squares; independent of the lockstep recurrence and the tail formula.
  const std::size_t K = std::size_t{1} << 20;
  for (const int alpha : {1, -1}) {
    const std::vector<double> h = kasdin_response((2.0 - alpha) / 2.0, K);
    for (const std::uint64_t m : {1, 2, 5, 16}) {
      const double mm = static_cast<double>(m);
      double avar = 0.0, mvar = 0.0;
      for (std::size_t k = 0; k < K; ++k) {
        double g = h[k];
        if (k >= m) g -= 2.0 * h[k - m];
        if (k >= 2 * m) g += h[k - 2 * m];
        avar += g * g;
        double gm = 0.0;
        for (std::size_t a = 0; a < 3 * m && a <= k; ++a) gm += (a < m || a >= 2 * m ? 1.0 : -2.0) * h[k - a];
        mvar += gm * gm;
      }
      avar /= 2.0 * mm * mm;
      mvar /= 2.0 * mm * mm * mm * mm;
      EXPECT_NEAR(expected_variance(alpha, Variance::avar, m) / avar, 1.0, 1e-9) << alpha << " m " << m;
      EXPECT_NEAR(expected_variance(alpha, Variance::mvar, m) / mvar, 1.0, 1e-9) << alpha << " m " << m;
    }
  }
}

TEST(ExpectedVariance, TailFormulaAgreesWithALongerSum) {
  // expected_variance sums 64 m + 1024 terms and adds the asymptotic tail; a sum 64 times longer
  // (whose own tail share is below 3e-9 for flicker FM) must agree to well within that.
  for (const int alpha : {1, -1})
    for (const Variance v : {Variance::avar, Variance::mvar})
      for (const std::uint64_t m : {1, 7, 64, 1024}) {
        const double longer = expected_variance_partial(alpha, v, m, 64 * (64 * m + 1024));
        EXPECT_NEAR(expected_variance(alpha, v, m) / longer, 1.0, 5e-9) << alpha << " m " << m;
      }
}

TEST(ExpectedVariance, FlickerFmApproachesTheFloor) {
  // Flicker FM, y = (1 - B)^(-1/2) w: S_y(f) = 1 / sin(pi f) one-sided, h_-1 = 1/pi, so AVAR tends to
  // 2 ln2 / pi and MVAR to 0.675 of that (NIST SP 1065; design brief: 0.2977 / 0.4413 = 0.6746).
  const double floor = 2.0 * std::numbers::ln2 / std::numbers::pi;
  const double avar = expected_variance(-1, Variance::avar, 16384);
  const double mvar = expected_variance(-1, Variance::mvar, 16384);
  EXPECT_NEAR(avar / floor, 1.0, 1e-4);
  EXPECT_NEAR(mvar / avar, 0.6746, 0.001);
}

TEST(PowerLawNoise, BurnInTruncationIsNegligible) {
  // The exact share of the first term's variance lost by starting the innovations burn_in_length(n)
  // before the first point: the filter beyond k = b + 2m (AVAR) or b + 3m - 1 (MVAR), at the
  // largest octave with a term of both (m = n/4). Bound stated in power_law_noise.hpp.
  const std::size_t n = 4096;
  const std::uint64_t m = n / 4, b = burn_in_length(n);
  for (const int alpha : {1, -1}) {
    const double lost_avar = 1.0 - expected_variance_partial(alpha, Variance::avar, m, b + 2 * m + 1) /
                                       expected_variance(alpha, Variance::avar, m);
    const double lost_mvar = 1.0 - expected_variance_partial(alpha, Variance::mvar, m, b + 3 * m) /
                                       expected_variance(alpha, Variance::mvar, m);
    std::printf("alpha %+d, n %zu, m %llu: burn-in loses %.2e of the AVAR term, %.2e of the MVAR term\n", alpha, n,
                static_cast<unsigned long long>(m), lost_avar, lost_mvar);
    const double bound = alpha == -1 ? 3e-3 : 5e-5;
    EXPECT_GT(lost_avar, 0.0);
    EXPECT_LT(lost_avar, bound);
    EXPECT_LT(lost_mvar, bound);
  }
}

TEST(PowerLawNoise, ReproducibleBySeed) {
  for (const int alpha : {2, 1, 0, -1, -2, -3, -4}) {
    const auto a = power_law_phase(alpha, 1000, 42);
    ASSERT_EQ(a.size(), 1000u);
    EXPECT_EQ(a, power_law_phase(alpha, 1000, 42)) << alpha;
    EXPECT_NE(a, power_law_phase(alpha, 1000, 43)) << alpha;
  }
  EXPECT_TRUE(power_law_phase(-1, 0, 1).empty());
  EXPECT_THROW(power_law_phase(3, 10, 1), std::invalid_argument);
  EXPECT_THROW(power_law_phase(-5, 10, 1), std::invalid_argument);
  EXPECT_THROW(expected_variance(-3, Variance::avar, 1), std::invalid_argument);
  EXPECT_THROW(expected_variance(0, Variance::avar, 0), std::invalid_argument);
}

TEST(PowerLawNoise, WalkTypesHaveTheirThirdDifferences) {
  // alpha -4: (1 - B)^3 x = w, unit variance; alpha -3: (1 - B)^3 x = (1 - B)^(1/2) w, variance
  // sum_k C(1/2, k)^2 = Gamma(2) / Gamma(3/2)^2 = 4 / pi. One series of 65536 points: the mean
  // square has a standard error of about 0.6 % (lag-1 correlation -1/3 for alpha -3); bound 3 %.
  for (const auto& [alpha, want] : {std::pair{-4, 1.0}, std::pair{-3, 4.0 / std::numbers::pi}}) {
    const auto x = power_law_phase(alpha, 65536, 7);
    double sum = 0.0;
    for (std::size_t k = 3; k < x.size(); ++k) {
      const double t = x[k] - 3.0 * x[k - 1] + 3.0 * x[k - 2] - x[k - 3];
      sum += t * t;
    }
    EXPECT_NEAR(sum / static_cast<double>(x.size() - 3) / want, 1.0, 0.03) << alpha;
  }
}

// Overlapping AVAR and MVAR of one series at averaging factor m, tau0 = 1 (NIST SP 1065 eqs. 14
// and 15), straight from the definitions in double.
double avar_of(const std::vector<double>& x, std::size_t m) {
  double sum = 0.0;
  std::size_t n = 0;
  for (std::size_t j = 0; j + 2 * m < x.size(); ++j, ++n) {
    const double t = x[j + 2 * m] - 2.0 * x[j + m] + x[j];
    sum += t * t;
  }
  return sum / (2.0 * static_cast<double>(m * m) * static_cast<double>(n));
}
double mvar_of(const std::vector<double>& x, std::size_t m) {
  std::vector<double> p(x.size() + 1, 0.0);
  for (std::size_t k = 0; k < x.size(); ++k) p[k + 1] = p[k] + x[k];
  double sum = 0.0;
  std::size_t n = 0;
  for (std::size_t j = 0; j + 3 * m <= x.size(); ++j, ++n) {
    const double t = p[j + 3 * m] - 3.0 * p[j + 2 * m] + 3.0 * p[j + m] - p[j];
    sum += t * t;
  }
  const double mm = static_cast<double>(m);
  return sum / (2.0 * mm * mm * mm * mm * static_cast<double>(n));
}

TEST(PowerLawNoise, MeanEstimatesMatchTheExactExpectation) {
  // R = 1000 realizations of n = 1024 points per type; at every octave m with an MVAR term the
  // mean of the R estimates must lie within 4 standard errors (sample s.d. / sqrt R, 0.14 % .. 4.1 %
  // of the value) of expected_variance(). 90 comparisons of independent seeds: a correct
  // generator fails one with probability about 0.6 %; the seeds are fixed, so the test is stable.
  const std::size_t n = 1024, R = 1000;
  double worst_z = 0.0;
  for (const int alpha : {2, 1, 0, -1, -2}) {
    std::vector<std::vector<double>> est[2];
    for (std::size_t r = 0; r < R; ++r) {
      const auto x = power_law_phase(alpha, n, 1000003 * r + static_cast<std::uint64_t>(alpha + 10));
      std::vector<double> a, b;
      for (std::size_t m = 1; 3 * m <= n; m *= 2) {
        a.push_back(avar_of(x, m));
        b.push_back(mvar_of(x, m));
      }
      est[0].push_back(a);
      est[1].push_back(b);
    }
    for (int v = 0; v < 2; ++v) {
      std::size_t i = 0;
      for (std::size_t m = 1; 3 * m <= n; m *= 2, ++i) {
        double mean = 0.0, m2 = 0.0;  // Welford
        for (std::size_t r = 0; r < R; ++r) {
          const double delta = est[v][r][i] - mean;
          mean += delta / static_cast<double>(r + 1);
          m2 += delta * (est[v][r][i] - mean);
        }
        const double se = std::sqrt(m2 / static_cast<double>(R - 1) / static_cast<double>(R));
        const double want = expected_variance(alpha, v == 0 ? Variance::avar : Variance::mvar, m);
        const double z = (mean - want) / se;
        worst_z = std::max(worst_z, std::fabs(z));
        std::printf("alpha %+d %s m %4zu: mean/exact %.4f, standard error %.4f, z %+.2f\n", alpha, v == 0 ? "AVAR" : "MVAR",
                    m, mean / want, se / want, z);
        EXPECT_LT(std::fabs(z), 4.0) << "alpha " << alpha << (v == 0 ? " AVAR" : " MVAR") << " m " << m << ": mean " << mean
                                     << ", exact " << want;
      }
    }
  }
  std::printf("largest |z| over all cells: %.2f\n", worst_z);
}

}  // namespace
}  // namespace gyrochar::test_support
