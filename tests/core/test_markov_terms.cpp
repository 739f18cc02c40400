// The terms beyond IEEE 952's five: the first-order Gauss-Markov rate (sampled AR(1)) and the
// sinusoid. Oracles: brute-force sums in long double of the terms' weights on the rate against its
// autocovariance (E[(sum w_i y_i)(sum v_j y_j)] = sum w_i v_j phi^|i-j|), N. F. Zhang's closed form
// of the AR(1) Allan variance (Metrologia 45, 2008) where it is well conditioned, the brute-force
// mean of a sampled sinusoid's estimator terms over its phase, and exact model curves that the fit
// must give back (their parameters, and the model selection that names the right terms).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <tuple>
#include <vector>

#include "gyrochar/ieee952.hpp"
#include "gyrochar/noise_model.hpp"

namespace gyrochar {
namespace {

// The weights of a term on the rate samples y, oldest first (phase x_k = sum_{i<k} y_i).
std::vector<long double> rate_weights(Stat s, long m) {
  std::vector<long double> w;
  if (s == Stat::avar) {
    w.assign(static_cast<std::size_t>(2 * m), 0);
    for (long i = 0; i < m; ++i) w[static_cast<std::size_t>(i)] = -1, w[static_cast<std::size_t>(m + i)] = 1;
  } else {  // the sum of m second differences
    w.assign(static_cast<std::size_t>(3 * m), 0);
    for (long j = 0; j < m; ++j)
      for (long i = 0; i < m; ++i) w[static_cast<std::size_t>(j + i)] -= 1, w[static_cast<std::size_t>(j + m + i)] += 1;
  }
  return w;
}

// Cov of term (sa, ma) with newest point e and term (sb, mb) with newest point e - lag.
long double brute_covariance(double a, Stat sa, long ma, Stat sb, long mb, long lag) {
  const auto wa = rate_weights(sa, ma), wb = rate_weights(sb, mb);
  const long na = static_cast<long>(wa.size()), nb = static_cast<long>(wb.size());
  long double c = 0;
  for (long i = 0; i < na; ++i)      // sample index e - na + i
    for (long j = 0; j < nb; ++j) {  // sample index e - lag - nb + j
      // The MVAR term's last weight slot is always 0: its newest rate sample is e - 1 as the Allan term's.
      const long d = (-na + i + (sa == Stat::mvar)) - (-lag - nb + j + (sb == Stat::mvar));
      c += wa[static_cast<std::size_t>(i)] * wb[static_cast<std::size_t>(j)] * expl(-static_cast<long double>(a) * labs(d));
    }
  return c;
}

TEST(MarkovTerms, CovarianceMatchesBruteForceFromShortToVeryLongCorrelation) {
  for (double a : {3.0, 0.5, 0.05, 1e-3, 3e-5, 1e-6})
    for (long m : {1L, 2L, 3L, 16L, 100L})
      for (Stat s : {Stat::avar, Stat::mvar}) {
        const long double want = brute_covariance(a, s, m, s, m, 0);
        // Rounding grows as 1e-16 / (a m)^2 where Tc >> tau (docs/metrology.md): 1e-6 relative at a = 1e-6, m = 2.
        const double tolerance = a < 1e-5 ? 1e-6 : 1e-9;
        EXPECT_NEAR(markov_term_covariance(a, s, m, s, m, 0), static_cast<double>(want),
                    tolerance * std::fabs(static_cast<double>(want)))
            << "a " << a << " m " << m;
      }
  // Different taus, statistics and lags (the covariance of two estimates' terms).
  for (double a : {0.3, 1e-3})
    for (long lag : {-7L, 0L, 5L, 40L}) {
      const long double want = brute_covariance(a, Stat::avar, 4, Stat::mvar, 8, lag);
      EXPECT_NEAR(markov_term_covariance(a, Stat::avar, 4, Stat::mvar, 8, lag), static_cast<double>(want),
                  1e-9 * std::fabs(static_cast<double>(brute_covariance(a, Stat::mvar, 8, Stat::mvar, 8, 0))))
          << "a " << a << " lag " << lag;
    }
}

// markov_pair_sums() against the double sums over every pair of terms, each c from
// markov_term_covariance() and term_covariance() (both exact and checked above and in
// test_noise_model): the sums' quadrature and the exponential tails beyond the kernel's span.
TEST(MarkovTerms, PairSumsMatchTheDoubleSumOverEveryPairOfTerms) {
  NoiseSet set;
  set.alpha = {2, 0, -1, -2, 0};
  set.count = 4;
  struct Case {
    Stat sa;
    std::uint64_t ma, stride_a;
    Stat sb;
    std::uint64_t mb, stride_b;
    double a0, a1;
  };
  const Case cases[] = {{Stat::avar, 8, 1, Stat::avar, 8, 1, 0.05, 0.004},
                        {Stat::avar, 4, 1, Stat::avar, 32, 2, 0.3, 0.01},
                        {Stat::mvar, 16, 1, Stat::mvar, 16, 1, 0.02, 0.2},
                        {Stat::mvar, 8, 1, Stat::mvar, 64, 4, 0.002, 0.05},
                        {Stat::avar, 600, 1, Stat::avar, 600, 1, 0.1, 0.001}};
  constexpr std::uint64_t n_phase = 3000;
  for (const Case& c : cases) {
    const TermGrid ga = unbroken_grid(c.sa, c.ma, c.stride_a, n_phase), gb = unbroken_grid(c.sb, c.mb, c.stride_b, n_phase);
    const double rates[] = {c.a0, c.a1};
    const MarkovPairSums got = markov_pair_sums(set, rates, ga, gb);
    // The pairs at each lag, counted one by one; then every c once per lag.
    std::map<std::int64_t, double> pairs;
    for (std::uint64_t i = 0; i < ga.n; ++i)
      for (std::uint64_t j = 0; j < gb.n; ++j)
        pairs[static_cast<std::int64_t>(ga.first + i * ga.stride) - static_cast<std::int64_t>(gb.first + j * gb.stride)] +=
            1;
    MarkovPairSums want;
    for (const auto& [lag, count] : pairs) {
      double cm[2], ct[4];
      for (int r = 0; r < 2; ++r) cm[r] = markov_term_covariance(rates[r], c.sa, c.ma, c.sb, c.mb, lag);
      for (int t = 0; t < 4; ++t)
        ct[t] = term_covariance(set.alpha[static_cast<std::size_t>(t)], c.sa, c.ma, c.sb, c.mb, lag);
      for (std::size_t r = 0; r < 2; ++r) {
        want.c[r] += count * cm[r];
        for (std::size_t t = 0; t < 4; ++t) want.cm[r][t] += count * cm[r] * ct[t];
        for (std::size_t l = 0; l < 2; ++l) want.mm[r][l] += count * cm[r] * cm[l];
      }
    }
    // Relative to the scale sqrt(sum c_r^2 sum c_t^2) of each sum (a cross sum may cancel to ~0).
    for (std::size_t r = 0; r < 2; ++r) {
      for (std::size_t l = 0; l < 2; ++l) {
        const double scale = std::sqrt(want.mm[r][r] * want.mm[l][l]);
        EXPECT_NEAR(got.mm[r][l], want.mm[r][l], 2e-4 * scale) << "m " << c.ma << "/" << c.mb << " mm " << r << l;
      }
      for (std::size_t t = 0; t < 4; ++t) {
        const PairSums own = pair_sums(set, ga, gb);
        const double scale = std::sqrt(want.mm[r][r] * std::fabs(own.cc[t][t]));
        EXPECT_NEAR(got.cm[r][t], want.cm[r][t], 2e-4 * scale + 1e-300) << "m " << c.ma << "/" << c.mb << " cm " << r << t;
      }
    }
  }
}

// The fit makes each pair's Markov sums for the power-law noises kept at that pair alone
// (markov_sums_of_points()), and relies on them being the bits they would be beside the others:
// the quadrature's nodes do not depend on the noises. Oracle: the same call with every noise.
TEST(MarkovTerms, PairSumsOfSomeNoisesAreTheBitsTheyAreBesideTheOthers) {
  NoiseSet all;
  all.alpha = {2, 0, -1, -2, 0};
  all.count = 4;
  const std::vector<std::vector<std::size_t>> subsets = {{0, 1, 3}, {0}, {0, 2}, {1, 2, 3}};
  const double rates[] = {0.01, 3e-4};
  constexpr std::uint64_t n_phase = 20000;
  for (const auto& [sa, ma, sb, mb] :
       {std::tuple{Stat::avar, 16u, Stat::mvar, 256u}, std::tuple{Stat::mvar, 64u, Stat::mvar, 1024u},
        std::tuple{Stat::avar, 2u, Stat::avar, 2048u}}) {
    const TermGrid ga = unbroken_grid(sa, ma, 1, n_phase), gb = unbroken_grid(sb, mb, 1, n_phase);
    const MarkovPairSums full = markov_pair_sums(all, rates, ga, gb);
    ASSERT_NE(full.c[0], 0.0);
    for (const auto& subset : subsets) {
      NoiseSet some;
      for (const std::size_t t : subset) some.alpha[some.count++] = all.alpha[t];
      const MarkovPairSums got = markov_pair_sums(some, rates, ga, gb);
      for (std::size_t r = 0; r < 2; ++r) {
        EXPECT_EQ(got.c[r], full.c[r]) << "m " << ma << "/" << mb;
        for (std::size_t l = 0; l < 2; ++l) EXPECT_EQ(got.mm[r][l], full.mm[r][l]) << "m " << ma << "/" << mb;
        for (std::size_t p = 0; p < subset.size(); ++p)
          EXPECT_EQ(got.cm[r][p], full.cm[r][subset[p]]) << "m " << ma << "/" << mb << " noise " << subset[p];
      }
    }
  }
}

TEST(MarkovTerms, AllanVarianceIsZhangsClosedForm) {
  // Zhang: AVAR(n) = s_e^2 (n - 3 phi - n phi^2 + 4 phi^(n+1) - phi^(2n+1)) / [n^2 (1-phi)^2 (1-phi^2)]
  // with s_e^2 the innovation variance, 1 - phi^2 for a unit stationary variance; E[a^2] = 2 n^2 AVAR.
  for (double a : {2.0, 0.2, 0.02})
    for (double n : {1.0, 5.0, 64.0, 1000.0}) {
      const double phi = std::exp(-a);
      const double avar = (n - 3 * phi - n * phi * phi + 4 * std::pow(phi, n + 1) - std::pow(phi, 2 * n + 1)) /
                          (n * n * (1 - phi) * (1 - phi));
      EXPECT_NEAR(markov_term_covariance(a, Stat::avar, static_cast<std::uint64_t>(n), Stat::avar,
                                         static_cast<std::uint64_t>(n), 0),
                  2 * n * n * avar, 1e-9 * 2 * n * n * avar);
    }
}

constexpr double tau0 = 0.01;
constexpr std::uint64_t n_phase = 1u << 22;

Ieee952Fit model_fit(const std::array<double, 5>& qnbkr, double markov_sigma, double tc, double sinusoid_a, double hz) {
  Ieee952Fit f;
  for (std::size_t t = 0; t < 5; ++t) f.p[t].value = qnbkr[t];
  if (markov_sigma > 0) f.n_markov = 1, f.markov[0].sigma.value = markov_sigma, f.markov[0].tc_s = tc;
  if (sinusoid_a > 0) f.n_sinusoids = 1, f.sinusoids[0].amplitude.value = sinusoid_a, f.sinusoids[0].frequency_hz = hz;
  return f;
}

TEST(MarkovTerms, SinusoidVariancesAreThePhaseMeanOfTheSampledEstimator) {
  // A sampled sinusoidal rate A sin(2 pi f t + p) integrated exactly: x_k = -A cos(2 pi f k tau0 + p) / (2 pi f).
  const double A = 1e-5, hz = 0.37;
  const Ieee952Fit f = model_fit({}, 0, 0, A, hz);
  for (std::uint64_t m : {1u, 3u, 10u, 50u})
    for (Stat s : {Stat::avar, Stat::mvar}) {
      double mean = 0;
      constexpr int phases = 64;
      for (int k = 0; k < phases; ++k) {
        const double p = 2 * 3.141592653589793 * k / phases;
        auto x = [&](double i) {
          return -A * std::cos(2 * 3.141592653589793 * hz * i * tau0 + p) / (2 * 3.141592653589793 * hz);
        };
        const double mm = static_cast<double>(m);
        double t = 0;
        const int terms = s == Stat::avar ? 1 : static_cast<int>(m);
        for (int j = 0; j < terms; ++j) t += x(j + 2 * mm) - 2 * x(j + mm) + x(j);
        mean += t * t / (s == Stat::avar ? 2 * mm * mm * tau0 * tau0 : 2 * mm * mm * mm * mm * tau0 * tau0) / phases;
      }
      EXPECT_NEAR(fitted_variance(f, s, m, tau0), mean, 1e-9 * mean) << "m " << m;
    }
}

// A sinusoid's term covariance against the mean over its phase of the terms' product, each term
// formed from the phase x_k = -cos(theta k + p) / theta (a rate sin(theta k + p) integrated
// exactly, one sample a unit of time). Eight phases make the mean exact: the products are
// sinusoids of twice the phase, which eight equally spaced phases average to zero.
TEST(MarkovTerms, SinusoidCovarianceIsThePhaseMeanOfTheTermsProduct) {
  auto term = [](Stat s, long m, long e, double theta, double p) {
    auto x = [&](long k) { return -std::cos(theta * static_cast<double>(k) + p) / theta; };
    double t = 0;
    for (long j = 0; j < (s == Stat::avar ? 1 : m); ++j) t += x(e - j) - 2 * x(e - j - m) + x(e - j - 2 * m);
    return t;
  };
  for (double theta : {3e-3, 0.2, 1.3, 3.0})
    for (Stat sa : {Stat::avar, Stat::mvar})
      for (Stat sb : {Stat::avar, Stat::mvar})
        for (long ma : {1L, 4L})
          for (long mb : {3L, 8L})
            for (long lag : {-9L, 0L, 2L, 31L}) {
              double mean = 0, scale = 0;
              for (int k = 0; k < 8; ++k) {
                const double p = 2 * 3.141592653589793 * k / 8;
                mean += term(sa, ma, 100, theta, p) * term(sb, mb, 100 - lag, theta, p) / 8;
                scale += std::fabs(term(sa, ma, 100, theta, p) * term(sb, mb, 100, theta, p)) / 8;
              }
              EXPECT_NEAR(sinusoid_term_covariance(theta, sa, static_cast<std::uint64_t>(ma), sb,
                                                   static_cast<std::uint64_t>(mb), lag),
                          mean, 1e-9 * scale + 1e-300)
                  << "theta " << theta << " m " << ma << "/" << mb << " lag " << lag;
            }
  EXPECT_EQ(sinusoid_term_covariance(0, Stat::avar, 1, Stat::avar, 1, 0), 0);
  EXPECT_EQ(sinusoid_term_covariance(3.2, Stat::avar, 1, Stat::avar, 1, 0), 0);  // above the Nyquist frequency
}

// sinusoid_pair_sums() against the double sums over every pair of terms, each c from
// sinusoid_term_covariance() and term_covariance() (checked above and in test_noise_model): the
// quadrature over an oscillating c, the flicker noise's reach, and the cut beyond theta m / 2 = 64.
TEST(MarkovTerms, SinusoidPairSumsMatchTheDoubleSumOverEveryPairOfTerms) {
  NoiseSet set;
  set.alpha = {2, 0, -1, -2, 0};
  set.count = 4;
  struct Case {
    Stat sa;
    std::uint64_t ma, stride_a;
    Stat sb;
    std::uint64_t mb, stride_b;
    double theta0, theta1;
  };
  const Case cases[] = {{Stat::avar, 8, 1, Stat::avar, 8, 1, 0.05, 0.7},
                        {Stat::avar, 4, 1, Stat::avar, 32, 2, 0.3, 0.01},
                        {Stat::mvar, 16, 1, Stat::mvar, 16, 1, 0.02, 0.2},
                        {Stat::mvar, 8, 1, Stat::avar, 64, 4, 0.002, 0.05},
                        {Stat::avar, 600, 1, Stat::avar, 600, 1, 0.1, 0.001},
                        {Stat::mvar, 300, 1, Stat::mvar, 300, 1, 0.03, 2.0}};  // 2.0: beyond the cut
  constexpr std::uint64_t n_phase = 3000;
  for (const Case& c : cases) {
    const TermGrid ga = unbroken_grid(c.sa, c.ma, c.stride_a, n_phase), gb = unbroken_grid(c.sb, c.mb, c.stride_b, n_phase);
    const double thetas[] = {c.theta0, c.theta1};
    const SinusoidPairSums got = sinusoid_pair_sums(set, thetas, ga, gb);
    std::map<std::int64_t, double> pairs;
    for (std::uint64_t i = 0; i < ga.n; ++i)
      for (std::uint64_t j = 0; j < gb.n; ++j)
        pairs[static_cast<std::int64_t>(ga.first + i * ga.stride) - static_cast<std::int64_t>(gb.first + j * gb.stride)] +=
            1;
    SinusoidPairSums want;
    std::array<double, 2> own{};  // sum c_s^2: the scale of each sinusoid's sums
    for (const auto& [lag, count] : pairs)
      for (std::size_t r = 0; r < 2; ++r) {
        const double cs = sinusoid_term_covariance(thetas[r], c.sa, c.ma, c.sb, c.mb, lag);
        own[r] += count * cs * cs;
        for (std::size_t t = 0; t < 4; ++t)
          want.cs[r][t] += count * cs * term_covariance(set.alpha[t], c.sa, c.ma, c.sb, c.mb, lag);
      }
    const PairSums noise = pair_sums(set, ga, gb);
    for (std::size_t r = 0; r < 2; ++r)
      for (std::size_t t = 0; t < 4; ++t) {
        const double scale = std::sqrt(own[r] * std::fabs(noise.cc[t][t]));
        if (thetas[r] * static_cast<double>(std::max(c.ma, c.mb)) / 2 > 64) {
          EXPECT_EQ(got.cs[r][t], 0) << "beyond the cut";
          // What the cut leaves out is small beside the sinusoid's own scale (A^2 / 4096 there).
          EXPECT_LE(std::fabs(want.cs[r][t]), 1e-3 * scale) << "m " << c.ma << " cs " << r << t;
          continue;
        }
        EXPECT_NEAR(got.cs[r][t], want.cs[r][t], 1e-3 * scale + 1e-300) << "m " << c.ma << "/" << c.mb << " cs " << r << t;
      }
  }
}

std::vector<FitPoint> exact_points(const Ieee952Fit& model) {
  std::vector<FitPoint> pts;
  for (std::uint64_t m = 1; 3 * m < n_phase; m *= 2)
    for (Stat s : {Stat::avar, Stat::mvar})
      pts.push_back({s, m, 1, unbroken_grid(s, m, 1, n_phase).n, fitted_variance(model, s, m, tau0), 0});
  return pts;
}

TEST(MarkovTerms, FitSelectsAndRecoversAMarkovTermFromItsExactCurve) {
  // White rate noise N plus one Markov term whose Allan hump stands out near 1.89 Tc = 190 s.
  const double N = 4.4e-5, sigma = 2e-5, tc = 100;
  const Ieee952Fit truth = model_fit({0, N, 0, 0, 0}, sigma, tc, 0, 0);
  const auto pts = exact_points(truth);
  std::vector<double> workspace(ieee952_workspace_doubles(pts.size()));
  const Ieee952Fit f = fit_ieee952(pts, {tau0, n_phase, 0, 0.01}, FitCurve::both, workspace);
  ASSERT_TRUE(f.ok()) << f.chi2_per_dof();
  ASSERT_EQ(f.n_markov, 1u);
  EXPECT_NEAR(f.markov[0].tc_s, tc, 0.01 * tc);
  EXPECT_NEAR(f.markov[0].sigma.value, sigma, 0.01 * sigma);
  EXPECT_TRUE(f.markov[0].sigma.resolved);
  EXPECT_NEAR(f.p[1].value, N, 0.01 * N);
  EXPECT_TRUE(f.runner_up.valid);
  EXPECT_LT(f.chosen.criterion, f.runner_up.criterion);
  // Without the selection the five terms alone cannot make the hump: the fit is rejected.
  FitSetup plain{tau0, n_phase, 0, 0.01};
  plain.select_model = false;
  EXPECT_EQ(fit_ieee952(pts, plain, FitCurve::both, workspace).status, FitStatus::rejected);
}

TEST(MarkovTerms, FitAddsNothingToAPowerLawCurve) {
  const Ieee952Fit truth = model_fit({8.0e-7, 4.4e-6, 1.2e-6, 8.0e-8, 0.0}, 0, 0, 0, 0);
  const auto pts = exact_points(truth);
  std::vector<double> workspace(ieee952_workspace_doubles(pts.size()));
  const Ieee952Fit f = fit_ieee952(pts, {tau0, n_phase, 0, 0.01}, FitCurve::both, workspace);
  ASSERT_TRUE(f.ok());
  EXPECT_EQ(f.n_markov, 0u);
  EXPECT_EQ(f.bandwidth_tc_s, 0.0);
  EXPECT_FALSE(f.chosen.bandwidth);
}

}  // namespace
}  // namespace gyrochar
