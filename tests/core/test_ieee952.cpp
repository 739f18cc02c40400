// The IEEE-952 generalized least-squares fit. Oracles: the model itself (exact expected curves
// must give their parameters back), and Monte Carlo with points drawn from the multivariate normal
// distribution of the model's own covariance (noise_model.hpp, computed here by pair_sums()
// independently of the fit): the stated uncertainties must then cover the truth about 68 % of the
// time, and chi2/dof average 1. The quantization rules against curves with a known periodic deficit
// or departure.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "gyrochar/ieee952.hpp"
#include "gyrochar/noise_model.hpp"

namespace gyrochar {
namespace {

constexpr double tau0 = 0.01;
constexpr std::uint64_t n_phase = 1u << 20;
constexpr std::uint32_t stride_factor = 8;

// Q N B K R (rad, s), each dominating the curve over about a decade of tau.
// Q/N cross at 0.1 s, N/B at 30 s, B/K at 300 s (IEEE 952's closed forms).
const std::array<double, 5> truth{8.0e-7, 4.4e-6, 1.2e-6, 8.0e-8, 0.0};

std::vector<FitPoint> exact_points(const std::array<double, 5>& p) {
  std::vector<FitPoint> pts;
  for (std::uint64_t m = 1; 3 * m < n_phase; m *= 2) {
    const std::uint64_t stride = m > stride_factor ? m / stride_factor : 1;
    for (Stat s : {Stat::avar, Stat::mvar})
      pts.push_back({s, m, stride, unbroken_grid(s, m, stride, n_phase).n, ieee952_variance(p, s, m, tau0), 0});
  }
  return pts;
}

Ieee952Fit fit(const std::vector<FitPoint>& pts, FitCurve curve, double white_quantization = 0, double model_spread = 0.01) {
  std::vector<double> workspace(ieee952_workspace_doubles(pts.size()));
  return fit_ieee952(pts, {tau0, n_phase, white_quantization, model_spread}, curve, workspace);
}

TEST(Ieee952, ExactCurvesGiveTheirParametersBack) {
  auto p = truth;
  p[4] = 4e-11;  // with a ramp
  for (FitCurve c : {FitCurve::both, FitCurve::avar, FitCurve::mvar}) {
    const Ieee952Fit f = fit(exact_points(p), c);
    ASSERT_TRUE(f.ok()) << name(c) << ": " << name(f.status);
    EXPECT_LT(f.chi2, 1e-12) << name(c);
    for (std::size_t k = 0; k < 5; ++k) {
      EXPECT_TRUE(f.p[k].fitted) << name(c) << " term " << k;
      EXPECT_NEAR(f.p[k].value / p[k], 1.0, 1e-6) << name(c) << " term " << k;
    }
  }
}

TEST(Ieee952, ExactCurvesOfA120HourRunGiveTheirParametersBack) {
  // Oracle: the model itself, on the geometry of a 120 h record at tau0 0.1 s (fully overlapped
  // octave taus, 42 points over 21 octaves): the long-run gyro of the recovery study (Q 1.041
  // arcsec, N 0.002 deg/sqrt(h), B 0.02 deg/h, K 0.05 deg/h/sqrt(h), R 0.01 deg/h/h, in rad and s).
  // The fit of both curves was singular here: the closed-form random-walk and flicker FM
  // covariances of a short modified Allan estimate and a long Allan one had no correct digit left.
  constexpr double tau0_long = 0.1;
  constexpr std::uint64_t n_long = 4320001;
  const std::array<double, 5> p{5.047e-6, 5.818e-7, 9.696e-8, 4.040e-9, 1.347e-11};
  std::vector<FitPoint> pts;
  for (std::uint64_t m = 1; 2 * m < n_long; m *= 2)
    for (Stat s : {Stat::avar, Stat::mvar})
      if (s == Stat::avar || 3 * m < n_long)
        pts.push_back({s, m, 1, unbroken_grid(s, m, 1, n_long).n, ieee952_variance(p, s, m, tau0_long), 0});
  ASSERT_EQ(pts.size(), 43u);  // 42 once the modified Allan point at m = 1 is dropped
  // The three fits share the points' pair sums (the analyzer's cache; on exact points the weights
  // do not move the parameters, so its approximation cannot either).
  std::vector<PairSumCache::Entry> entries(pts.size() * pts.size() + 16);
  PairSumCache cache(entries);
  for (FitCurve c : {FitCurve::both, FitCurve::avar, FitCurve::mvar}) {
    std::vector<double> workspace(ieee952_workspace_doubles(pts.size()));
    const Ieee952Fit f = fit_ieee952(pts, {tau0_long, n_long, 0}, c, workspace, &cache);
    ASSERT_TRUE(f.ok()) << name(c) << ": " << name(f.status);
    EXPECT_LT(f.chi2, 1e-12) << name(c);
    for (std::size_t k = 0; k < 5; ++k) EXPECT_NEAR(f.p[k].value / p[k], 1.0, 1e-6) << name(c) << " term " << k;
  }
}

TEST(Ieee952, ATotalFamilyPointWeighsWithItsOwnVariance) {
  // Oracle: with no model spread and exact points (chi2 = 0), the covariance of the points scales
  // by variance_scale, so every uncertainty scales by its square root.
  const auto exact = exact_points(truth);
  auto scaled = exact;
  for (FitPoint& p : scaled) p.variance_scale = 0.25;
  const Ieee952Fit a = fit(exact, FitCurve::avar, 0, 0.0), b = fit(scaled, FitCurve::avar, 0, 0.0);
  ASSERT_TRUE(a.ok() && b.ok());
  for (std::size_t k = 0; k < 4; ++k) EXPECT_NEAR(b.p[k].uncertainty / a.p[k].uncertainty, 0.5, 1e-6) << k;
  // Only the long taus (where K dominates) more precise: K gains, Q does not.
  auto longer = exact;
  for (FitPoint& p : longer)
    if (p.m >= 4096) p.variance_scale = 0.25;
  const Ieee952Fit c = fit(longer, FitCurve::avar, 0, 0.0);
  ASSERT_TRUE(c.ok());
  EXPECT_LT(c.p[3].uncertainty, 0.8 * a.p[3].uncertainty);
  EXPECT_NEAR(c.p[0].uncertainty / a.p[0].uncertainty, 1.0, 0.01);
}

TEST(Ieee952, TheModelsExactCurveTendsToTheStandardsClosedForm) {
  // At large m the exact expectation is IEEE 952's AVAR (oracle: the closed form in the standard).
  for (std::uint64_t m : {1u << 12, 1u << 16}) {
    const double tau = static_cast<double>(m) * tau0;
    EXPECT_NEAR(ieee952_variance(truth, Stat::avar, m, tau0) / ieee952_avar(truth, tau), 1.0, 1e-5) << m;
  }
}

TEST(Ieee952, AnAbsentTermIsNotResolved) {
  // Oracle: the truth has no rate ramp and no bias instability.
  auto p = truth;
  p[2] = 0;
  const Ieee952Fit f = fit(exact_points(p), FitCurve::both);
  ASSERT_TRUE(f.ok());
  EXPECT_FALSE(f.p[2].resolved);
  EXPECT_FALSE(f.p[4].resolved);
  for (std::size_t k : {0u, 1u, 3u}) EXPECT_TRUE(f.p[k].resolved) << k;
}

TEST(Ieee952, ANegativeUnconstrainedSquareKeepsItsSignInTheSignedRoot) {
  // Oracle: the model is linear in the squares. The exact curve of the truth without K, less the
  // curve of K = 8e-9 (a square of -6.4e-17, which no gyro has), is fitted exactly by the
  // unconstrained estimate K^2 = -6.4e-17: its signed root is -8e-9. The non-negative fit leaves K
  // out, and `unconstrained` (what a verdict judges) is 0 there; the other terms' signed roots are
  // their unconstrained values.
  auto p = truth;
  p[3] = 0;
  std::vector<FitPoint> pts = exact_points(p);
  const std::array<double, 5> k_only{0, 0, 0, 8e-9, 0};
  for (FitPoint& q : pts) q.variance -= ieee952_variance(k_only, q.stat, q.m, tau0);
  const Ieee952Fit f = fit(pts, FitCurve::both);
  ASSERT_TRUE(f.ok()) << name(f.status);
  const Ieee952Parameter& k = f.p[3];
  EXPECT_FALSE(k.fitted);
  EXPECT_GT(k.unconstrained_uncertainty, 0);
  EXPECT_NEAR(k.unconstrained_signed / -8e-9, 1.0, 1e-3);
  EXPECT_EQ(k.unconstrained, 0.0);
  for (std::size_t t : {0u, 1u, 2u}) {
    EXPECT_EQ(f.p[t].unconstrained_signed, f.p[t].unconstrained) << t;
    EXPECT_NEAR(f.p[t].unconstrained / truth[t], 1.0, 1e-3) << t;
  }
}

// Points drawn from N(model, Sigma) with Sigma the exact covariance of the estimates under the
// truth (pair_sums() over the unbroken grids, 2 sum c_t c_u h_t h_u / (n n' norm norm')).
class Draw {
 public:
  Draw(const std::vector<FitPoint>& pts, const std::array<double, 5>& truth)
      : pts_(pts), n_(pts.size()), chol_(n_ * n_, 0.0) {
    NoiseSet set;
    set.alpha = {2, 0, -1, -2};
    set.count = 4;
    const std::array<double, 4> h{truth[0] * truth[0], truth[1] * truth[1] * tau0, truth[2] * truth[2] * tau0 * tau0,
                                  truth[3] * truth[3] * tau0 * tau0 * tau0};
    auto norm = [](const FitPoint& p) {
      const double m = static_cast<double>(p.m);
      return (p.stat == Stat::mvar ? 2 * m * m * m * m : 2 * m * m) * tau0 * tau0;
    };
    std::vector<double> sigma(n_ * n_);
    for (std::size_t i = 0; i < n_; ++i)
      for (std::size_t j = 0; j <= i; ++j) {
        const auto& a = pts[i];
        const auto& b = pts[j];
        const PairSums s = pair_sums(set, unbroken_grid(a.stat, a.m, a.stride, n_phase),
                                     unbroken_grid(b.stat, b.m, b.stride, n_phase));
        double v = 0;
        for (std::size_t t = 0; t < 4; ++t)
          for (std::size_t u = 0; u < 4; ++u) v += 2 * h[t] * h[u] * s.cc[t][u];
        sigma[i * n_ + j] = sigma[j * n_ + i] = v /
                                                (static_cast<double>(a.n) * static_cast<double>(b.n) * norm(a) * norm(b));
      }
    for (std::size_t j = 0; j < n_; ++j) {  // Cholesky
      double d = sigma[j * n_ + j];
      for (std::size_t k = 0; k < j; ++k) d -= chol_[j * n_ + k] * chol_[j * n_ + k];
      EXPECT_GT(d, 0) << "the model's covariance must be positive definite (point " << j << ")";
      chol_[j * n_ + j] = std::sqrt(d);
      for (std::size_t i = j + 1; i < n_; ++i) {
        double s = sigma[i * n_ + j];
        for (std::size_t k = 0; k < j; ++k) s -= chol_[i * n_ + k] * chol_[j * n_ + k];
        chol_[i * n_ + j] = s / chol_[j * n_ + j];
      }
    }
  }
  std::vector<FitPoint> operator()(std::mt19937_64& rng) const {
    std::normal_distribution<double> normal;
    std::vector<double> z(n_);
    for (double& v : z) v = normal(rng);
    auto out = pts_;
    for (std::size_t i = 0; i < n_; ++i)
      for (std::size_t k = 0; k <= i; ++k) out[i].variance += chol_[i * n_ + k] * z[k];
    return out;
  }

 private:
  std::vector<FitPoint> pts_;
  std::size_t n_;
  std::vector<double> chol_;
};

TEST(Ieee952, StatedUncertaintiesCoverTheTruthUnderTheModelsOwnScatter) {
  // Octaves 1 .. 2^8 of 2^20 points: every estimate has an EDF of 1000 or more, so the normal
  // approximation holds, and every two points lie within the fit's band of 8 octaves, so its
  // covariance model is the drawing distribution. (MVAR at m = 1 is AVAR's own estimate: once.)
  // The truth puts all four noises inside that range: Q/N cross at 0.03 s, N/B at 0.3 s, B/K at 1 s.
  const std::array<double, 5> compressed{4.4e-7, 4.4e-6, 1.2e-5, 1.4e-5, 0.0};
  std::vector<FitPoint> pts;
  for (const FitPoint& p : exact_points(compressed))
    if (p.m <= (1u << 8) && !(p.m == 1 && p.stat == Stat::mvar)) pts.push_back(p);
  const Draw draw(pts, compressed);
  const double spread = 1e-3;  // the drawing distribution is the model: next to no model spread
  std::mt19937_64 rng(952);
  // 300 trials natively; under an emulator (the aarch64 preset's qemu, about 17 times the CPU time)
  // a small version of the same study, with bounds widened to the same number of standard errors.
#ifdef GYROCHAR_EMULATED
  const int trials = 60;
#else
  const int trials = 300;
#endif
  std::array<int, 4> within{};
  double chi2_per_dof = 0;
  // The trials share their geometry: the fit's pair sums are computed once, in the cache the
  // analyzer's fit uses too (the drawing covariance above is computed without it).
  std::vector<PairSumCache::Entry> entries(pts.size() * pts.size() + 16);
  PairSumCache cache(entries);
  std::vector<double> workspace(ieee952_workspace_doubles(pts.size()));
  for (int t = 0; t < trials; ++t) {
    const Ieee952Fit f = fit_ieee952(draw(rng), {tau0, n_phase, 0, spread}, FitCurve::both, workspace, &cache);
    ASSERT_TRUE(f.ok()) << name(f.status) << ": chi2 " << f.chi2 << " on " << f.dof << " dof";
    chi2_per_dof += f.chi2_per_dof() / trials;
    // Generalized least squares is linear in the squared parameters: theta = p^2 with its
    // standard uncertainty 2 p u(p) (u(p) = sqrt(u(theta)) where p is 0).
    for (std::size_t k = 0; k < 4; ++k) {
      const Ieee952Parameter& q = f.p[k];
      const double theta = q.value * q.value;
      const double u = q.value > 0 ? 2 * q.value * q.uncertainty : q.uncertainty * q.uncertainty;
      if (std::fabs(theta - compressed[k] * compressed[k]) <= u) ++within[k];
    }
  }
  // A coverage of 68.3 % has a standard error of sqrt(0.683 x 0.317 / trials) (2.7 points at 300
  // trials, 6.0 at 60); bounds at 4 of them.
  const double coverage_se = std::sqrt(0.683 * 0.317 / trials);
  for (std::size_t k = 0; k < 4; ++k) {
    const double coverage = static_cast<double>(within[k]) / trials;
    std::printf("term %zu: %.1f %% within 1 stated sigma (squared parameter), %d trials\n", k, 100 * coverage, trials);
    EXPECT_NEAR(coverage, 0.683, 4 * coverage_se) << "term " << k;
  }
  // chi2/dof would average 1 (sd of the mean of `trials` values with 12 dof: sqrt(2 / 12 / trials),
  // 0.024 at 300, 0.053 at 60); the model spread on the diagonal, small as it is, weighs in the
  // directions where AVAR and MVAR at one tau differ (correlated 0.99 under random-walk FM), so it
  // averages less (measured 0.56 at 300 trials): bounds 0.4 and 1.1 at 300, 3 sd wider at 60.
  const double chi2_widen = 3 * (std::sqrt(2.0 / 12 / trials) - std::sqrt(2.0 / 12 / 300));
  std::printf("mean chi2/dof %.3f\n", chi2_per_dof);
  EXPECT_GT(chi2_per_dof, 0.4 - chi2_widen);
  EXPECT_LT(chi2_per_dof, 1.1 + chi2_widen);
}

TEST(Ieee952, PeriodicQuantizationIsDetectedAndItsTausLeftOut) {
  // A counts curve whose AVAR at m = 1 is 0.6 of the white level 3 Q_w^2 / tau^2 (what a rate of
  // 0.15 pulse per sample gives: 4 min(beta, 1 - beta) with beta = 0.15, docs/metrology.md).
  auto p = truth;
  const double qw = truth[0];
  auto pts = exact_points(p);
  for (FitPoint& pt : pts)
    if (pt.m == 1 && pt.stat == Stat::avar) pt.variance = 0.6 * ieee952_variance({qw, 0, 0, 0, 0}, Stat::avar, 1, tau0);
  const Ieee952Fit f = fit(pts, FitCurve::both, qw);
  EXPECT_FALSE(f.quantization_white);
  EXPECT_GT(f.excluded_below_tau_s[0], tau0);
  EXPECT_FALSE(f.p[0].fitted);
  EXPECT_NEAR(f.p[1].value / truth[1], 1.0, 1e-3);  // N from the taus quantization leaves alone
  // The same curve without the deficit, from pulses half as large (Q = 2 Q_w: white angle noise of
  // half a pulse rms whitens them): white, nothing left out.
  const Ieee952Fit white = fit(exact_points(p), FitCurve::both, qw / 2);
  EXPECT_TRUE(white.quantization_white);
  EXPECT_EQ(white.excluded_below_tau_s[0], 0.0);
  EXPECT_EQ(white.excluded_below_tau_s[1], 0.0);
}

TEST(Ieee952, QuantizationOfAnAngleMovingLessThanAPulseASampleIsNotWhite) {
  // The white model's own curve, but every bit of Q is quantization (Q = Q_w) and N moves the angle
  // by N sqrt(tau0) = 0.16 pulse rms a sample. Oracle: the sawtooth's Fourier series (the comment
  // above quantization_correlated(), docs/metrology.md): the error's lag-1 correlation can reach
  // 0.6 exp(-2 pi^2 0.16^2) = 0.36, far beyond what points this precise allow, so Q is held and its
  // taus left out. Four times the N (0.64 pulse a sample: exp(-2 pi^2 0.41) = 3e-4) stays white.
  const double qw = truth[0];
  const Ieee952Fit f = fit(exact_points(truth), FitCurve::both, qw);
  EXPECT_FALSE(f.quantization_white);
  EXPECT_FALSE(f.p[0].fitted);
  EXPECT_NEAR(f.p[1].value / truth[1], 1.0, 1e-3);
  auto moving = truth;
  moving[1] *= 4;
  const Ieee952Fit white = fit(exact_points(moving), FitCurve::both, qw);
  EXPECT_TRUE(white.quantization_white);
  EXPECT_NEAR(white.p[0].value / truth[0], 1.0, 1e-3);
}

TEST(Ieee952, APatternAboveTheWhiteLevelIsFoundAfterTheFit) {
  // A pattern that never falls below the white level alone: AVAR 1.37 x the model at m = 1 and 0.86 x
  // at m = 2 (ADEV +17 % and -7 %, what 1.5 pulses per sample gave in docs/metrology.md), with
  // white angle noise beyond quantization (Q = 1.5 Q_w) so that the test before the fit passes.
  // Oracle: the truth's N, from the taus quantization leaves alone; without the departure nothing
  // is left out and Q is fitted (1.5 Q_w back).
  const double qw = truth[0] / 1.5;
  auto pts = exact_points(truth);
  for (FitPoint& pt : pts) {
    if (pt.m == 1) pt.variance *= 1.37;
    if (pt.m == 2) pt.variance *= 0.86;
  }
  const Ieee952Fit f = fit(pts, FitCurve::both, qw);
  EXPECT_FALSE(f.quantization_white);
  EXPECT_FALSE(f.p[0].fitted);
  EXPECT_NEAR(f.p[1].value / truth[1], 1.0, 0.01);
  const Ieee952Fit white = fit(exact_points(truth), FitCurve::both, qw);
  EXPECT_TRUE(white.quantization_white);
  EXPECT_NEAR(white.p[0].value / truth[0], 1.0, 1e-3);
}

TEST(Ieee952, AModelThatDoesNotDescribeTheCurveIsRejected) {
  // A bump of 30 % at one decade of tau that no IEEE-952 term can make (oracle: its size, some
  // hundred standard deviations at these EDFs).
  auto pts = exact_points(truth);
  for (FitPoint& p : pts)
    if (p.m >= 64 && p.m <= 512) p.variance *= 1.3;
  const Ieee952Fit f = fit(pts, FitCurve::both);
  EXPECT_EQ(f.status, FitStatus::rejected);
  EXPECT_GT(f.chi2_per_dof(), 2);
}

TEST(Ieee952, TooFewPointsIsSaid) {
  auto pts = exact_points(truth);
  pts.resize(4);
  EXPECT_EQ(fit(pts, FitCurve::both).status, FitStatus::too_few_points);
}

}  // namespace
}  // namespace gyrochar
