// gyrochar-sim's Gauss-Markov and sinusoidal rate terms (--markov, --sinusoid): their exact AVAR and
// MVAR (tests/oracle/sim_closed_forms.hpp) and the simulator against them, each term alone.
// docs/metrology.md ("The simulator and its conventions") has the derivations and the figures.
//
// Oracles, never a hand-picked tolerance:
// - the closed forms: the defining double sums over each term's weights on the rates, the weights
//   built here by summing the estimators' definitions term by term (Gauss-Markov:
//   sum_{t,t'} w_t w_t' phi^|t-t'| sigma^2), and the average over a grid of phases of the sampled
//   sinusoid's squared terms (exact: they are trigonometric polynomials of degree 2 in the phase),
//   in long double, to the rounding of those sums; Zhang's published AVAR (Metrologia 45, 2008), the
//   flicker oracle's independent AR(1) AVAR (oracle/flicker_markov.hpp), the white-rate limit and
//   the continuous limit of IEEE Std 952 Annex C;
// - the simulator, measured with the estimators' definitions in exact integers
//   (oracle/brute_force.hpp): a Gauss-Markov term, the mean over 16 seeds against its exact
//   expectation (Student t on the seed spread, p = 1e-4 two-sided per comparison); a sinusoid, one
//   run against the closed form within one phase's largest departure 1 / (M |sin(2 pi f tau0)|)
//   (M terms: the mean of cos^2 over M steps of 2 pi f tau0). Both widened by the quantization's
//   effect on a deviation, at most sqrt(2) pulse / tau whatever its pattern (test_sim_truth.cpp).
// Units: rates and deviations in deg/h (= arcsec/s).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "gyro_sim.hpp"
#include "host/sim_truth_support.hpp"
#include "oracle/brute_force.hpp"
#include "oracle/sim_closed_forms.hpp"
#include "sim_truth.hpp"

namespace gyrochar {
namespace {

using namespace sim_truth;
using real = long double;

// --- the closed forms against their definitions -------------------------------------------------

// The weights of one term on the rates y_1, y_2, ... (the phase x[i] = tau0 sum_{k<=i} y_k, in units
// of tau0), summed from the estimators' definitions: AVAR x[2n] - 2x[n] + x[0]; MVAR
// sum_{i=0}^{n-1} x[i+2n] - 2x[i+n] + x[i].
std::vector<real> phase_weights_on_rates(const std::vector<std::pair<std::uint64_t, int>>& phase_terms,
                                         std::uint64_t rates) {
  std::vector<real> w(rates, 0);
  for (const auto& [i, c] : phase_terms)
    for (std::uint64_t k = 1; k <= i; ++k) w[k - 1] += c;  // x[i] holds y_1 .. y_i
  return w;
}
std::vector<real> avar_weights(std::uint64_t n) { return phase_weights_on_rates({{2 * n, 1}, {n, -2}, {0, 1}}, 2 * n); }
std::vector<real> mvar_weights(std::uint64_t n) {
  std::vector<std::pair<std::uint64_t, int>> terms;
  for (std::uint64_t i = 0; i < n; ++i) terms.insert(terms.end(), {{i + 2 * n, 1}, {i + n, -2}, {i, 1}});
  return phase_weights_on_rates(terms, 3 * n - 1);
}
// sum_{t,t'} w_t w_t' phi^|t-t'| with phi = exp(-a), as -sum w_t w_t' (1 - phi^|t-t'|): the weights
// sum to 0, and 1 - phi^d from expm1 keeps small a exact.
real double_sum(const std::vector<real>& w, real a) {
  real s = 0;
  for (std::size_t t = 0; t < w.size(); ++t)
    for (std::size_t u = 0; u < w.size(); ++u) s += w[t] * w[u] * std::expm1(-a * static_cast<real>(t > u ? t - u : u - t));
  return s;
}

constexpr double tau0 = 0.01;

TEST(SimClosedForms, MarkovIsTheDefiningDoubleSum) {
  // Both branches: the closed forms (n tau0 >= 0.1 Tc) and the O(n) sum of squares below, from a
  // nearly white rate (Tc = tau0 / 1000) to Tc = 10^7 tau0, around the switch (Tc = 10 n tau0).
  // Measured worst relative difference: printed (1.4e-14); accepted below 1e-13, what
  // sim_closed_forms.hpp promises.
  double worst = 0;
  std::uint64_t worst_n = 0;
  double worst_tc = 0;
  for (std::uint64_t n : {1u, 2u, 3u, 5u, 16u, 100u}) {
    const std::vector<real> wa = avar_weights(n), wm = mvar_weights(n);
    const double nn = static_cast<double>(n);
    for (double tc_over_tau0 : {1e-3, 0.3, 1.0, 7.0, 9.999 * nn, 10.001 * nn, 1e2, 1e4, 1e7}) {
      const double tc = tc_over_tau0 * tau0;
      const real a = static_cast<real>(tau0) / static_cast<real>(tc);
      const double avar = static_cast<double>(double_sum(wa, a) / (2 * nn * nn));
      const double mvar = static_cast<double>(double_sum(wm, a) / (2 * nn * nn * nn * nn));
      EXPECT_NEAR(markov_avar(1.0, tau0, tc, n), avar, 1e-13 * avar) << "n=" << n << " Tc/tau0=" << tc_over_tau0;
      EXPECT_NEAR(markov_mvar(1.0, tau0, tc, n), mvar, 1e-13 * mvar) << "n=" << n << " Tc/tau0=" << tc_over_tau0;
      const double d = std::max(std::fabs(markov_avar(1.0, tau0, tc, n) / avar - 1),
                                std::fabs(markov_mvar(1.0, tau0, tc, n) / mvar - 1));
      if (d > worst) {
        worst = d;
        worst_n = n;
        worst_tc = tc_over_tau0;
      }
      if (n == 1) {  // one term: MVAR is AVAR
        EXPECT_NEAR(markov_mvar(1.0, tau0, tc, 1), avar, 1e-12 * avar);
      }
    }
  }
  std::printf("closed forms against the double sums: worst relative difference %.2e (n %llu, Tc %g tau0)\n", worst,
              static_cast<unsigned long long>(worst_n), worst_tc);
}

TEST(SimClosedForms, MarkovAgreesWithZhangTheFlickerOracleAndItsLimits) {
  for (std::uint64_t n : {1u, 2u, 7u, 64u, 1000u}) {
    for (double tc : {0.003, 0.05, 1.0, 30.0}) {
      const double avar = markov_avar(2.5, tau0, tc, n);
      // Zhang's AVAR of an AR(1) y_k = phi y_{k-1} + e_k, whose s^2 is the innovation variance
      // Var(e) = sigma^2 (1 - phi^2): with the stationary sigma^2 it is 1 / (1 - phi^2) too large
      // (50 at Tc = 100 tau0). Evaluated where it does not cancel (n tau0 >= 0.5 Tc).
      const real phi = std::exp(-static_cast<real>(tau0 / tc)), nn = static_cast<real>(n);
      const real zhang = (nn - 3 * phi - nn * phi * phi + 4 * std::pow(phi, nn + 1) - std::pow(phi, 2 * nn + 1)) /
                         (nn * nn * (1 - phi) * (1 - phi) * (1 - phi * phi));
      if (nn * tau0 >= 0.5 * tc) {
        EXPECT_NEAR(avar, static_cast<double>(2.5L * (1 - phi * phi) * zhang), 1e-12 * avar) << "n=" << n << " Tc=" << tc;
      }
      // The flicker oracle's AR(1) held over each sample, derived through T(n) (its own Taylor
      // branch for small n a): the same model.
      EXPECT_NEAR(avar, oracle::ar1_avar(2.5, tau0 / tc, n), 1e-11 * avar) << "n=" << n << " Tc=" << tc;
    }
    // Tc far below tau0: a white rate of variance sigma^2 per sample, AVAR sigma^2 / n and MVAR
    // sigma^2 (n^2 + 1) / (2 n^3) (the white-FM ratio).
    const double nn = static_cast<double>(n);
    EXPECT_DOUBLE_EQ(markov_avar(2.5, tau0, 1e-9, n), 2.5 / nn);
    EXPECT_DOUBLE_EQ(markov_mvar(2.5, tau0, 1e-9, n), 2.5 * (nn * nn + 1) / (2 * nn * nn * nn));
  }
  // Tc = 10^6 tau0: the continuous limits at x = tau / Tc, IEEE Std 952 Annex C's
  // AVAR = sigma^2 (2x - 3 + 4 e^-x - e^-2x) / x^2 (q_c^2 = 2 sigma^2 / Tc) and
  // MVAR = sigma^2 (x^3 - 6x + u (6 + 3u + u^2)) / x^4, u = 1 - e^-x, within O(tau0 / Tc).
  const double tc = 1e6 * tau0;
  for (double x : {0.01, 0.1, 1.0, 1.8926178, 10.0}) {
    const auto n = static_cast<std::uint64_t>(std::llround(x * tc / tau0));
    const double u = -std::expm1(-x);
    const double avar = (2 * x - 3 + 4 * std::exp(-x) - std::exp(-2 * x)) / (x * x);
    const double mvar = (x * x * x - 6 * x + u * (6 + 3 * u + u * u)) / (x * x * x * x);
    EXPECT_NEAR(markov_avar(1.0, tau0, tc, n), avar, 1e-5 * avar) << "x=" << x;
    EXPECT_NEAR(markov_mvar(1.0, tau0, tc, n), mvar, 1e-5 * mvar) << "x=" << x;
  }
  // The ADEV peak: 0.61736 sigma = 0.43654 q_c sqrt(Tc) at tau = 1.8926 Tc (the maximum of the
  // continuous form, found by Newton's method on its derivative).
  const auto peak = static_cast<std::uint64_t>(1.8926178 * tc / tau0);
  EXPECT_NEAR(std::sqrt(markov_avar(1.0, tau0, tc, peak)), 0.617364, 1e-5);
  for (double s : {0.99, 1.01})
    EXPECT_LT(markov_avar(1.0, tau0, tc, static_cast<std::uint64_t>(s * static_cast<double>(peak))),
              markov_avar(1.0, tau0, tc, peak));
}

TEST(SimClosedForms, SinusoidIsTheAverageOverItsPhase) {
  // The sampled angle -(A / (2 pi f)) cos(2 pi f k tau0 + phi0) (the exact integral of the rate),
  // its AVAR and MVAR terms at j = 0, squared and averaged over 8 phases 2 pi i / 8 (exact for a
  // trigonometric polynomial of degree 2). Accepted, on the deviations: 1e-12 relative, plus the
  // rounding of the phase points here, each off by at most (A / (2 pi f)) (|argument| + 1) 2^-62
  // (the long double argument and cosine), which the second differences do not cancel: 4 points'
  // worth on an AVAR term, 4n on an MVAR term (it matters near the zeros of sin(pi f tau)).
  const real amplitude = 3;
  for (double f_tau0 : {0.001, 0.0123, 0.25, 0.4999}) {
    const real f = static_cast<real>(f_tau0 / tau0);
    for (std::uint64_t n : {1u, 2u, 3u, 10u, 64u}) {
      real avar = 0, mvar = 0;
      for (int i = 0; i < 8; ++i) {
        const real phi0 = 2 * static_cast<real>(pi) * i / 8;
        const auto x = [&](std::uint64_t k) {
          return -amplitude / (2 * static_cast<real>(pi) * f) *
                 std::cos(2 * static_cast<real>(pi) * f * static_cast<real>(k) * tau0 + phi0);
        };
        avar += std::pow(x(2 * n) - 2 * x(n) + x(0), 2) / 8;
        real term = 0;
        for (std::uint64_t k = 0; k < n; ++k) term += x(k + 2 * n) - 2 * x(k + n) + x(k);
        mvar += term * term / 8;
      }
      const real tau = static_cast<real>(n) * tau0, nn = static_cast<real>(n);
      avar /= 2 * tau * tau;
      mvar /= 2 * nn * nn * tau * tau;
      const double a = static_cast<double>(amplitude), fd = static_cast<double>(f), td = static_cast<double>(tau);
      const double point = a / (2 * pi * fd) * (2 * pi * fd * 3 * td + 2 * pi + 1) * 0x1p-62;
      const double dev_a = std::sqrt(static_cast<double>(avar)), dev_m = std::sqrt(static_cast<double>(mvar));
      EXPECT_NEAR(std::sqrt(sinusoid_avar(a, fd, td)), dev_a, 1e-12 * dev_a + 4 * point / (std::sqrt(2.0) * td))
          << "f tau0 " << f_tau0 << " n=" << n;
      EXPECT_NEAR(std::sqrt(sinusoid_mvar(a, fd, tau0, n)), dev_m,
                  1e-12 * dev_m + 4 * static_cast<double>(n) * point / (std::sqrt(2.0) * static_cast<double>(n) * td))
          << "f tau0 " << f_tau0 << " n=" << n;
    }
  }
}

// --- the simulator against them ------------------------------------------------------------------

// n counts of a simulation; AVAR and MVAR in (deg/h)^2 at the octaves up to m_max, with their term
// counts, from the phase (the sum of the counts) in exact integers.
struct Curves {
  std::vector<std::uint64_t> m, avar_terms, mvar_terms;
  std::vector<double> avar, mvar;
};
Curves measure(const SimOptions& o, std::uint64_t n, std::uint64_t m_max) {
  GyroSimulator sim(gyro_parameters(o));
  std::vector<std::int64_t> x(n + 1, 0);
  for (std::uint64_t k = 0; k < n; ++k) x[k + 1] = x[k] + sim.next_count();
  Curves c;
  const double w2 = o.pulse_arcsec * o.pulse_arcsec;
  for (std::uint64_t m : octaves(m_max)) {
    const oracle::Exact e = oracle::brute_force(x, m, 1);
    const double tau = static_cast<double>(m) * o.tau0_s, mm = static_cast<double>(m);
    c.m.push_back(m);
    c.avar_terms.push_back(e.n[0]);
    c.mvar_terms.push_back(e.n[1]);
    c.avar.push_back(static_cast<double>(e.sum[0]) / (2.0 * static_cast<double>(e.n[0]) * tau * tau) * w2);
    c.mvar.push_back(static_cast<double>(e.sum[1]) / (2.0 * static_cast<double>(e.n[1]) * mm * mm * tau * tau) * w2);
  }
  return c;
}

// Whether sqrt(value) lies in [sqrt(low) - bound, sqrt(high) + bound]: a variance interval whose
// deviations may be off by `bound` either way.
bool within(double value, double low, double high, double bound) {
  const double dev = std::sqrt(value);
  return dev >= std::sqrt(std::max(low, 0.0)) - bound && dev <= std::sqrt(high) + bound;
}

TEST(SimMarkov, EachTermAloneFollowsItsExactAvarAndMvar) {
  // sigma = 1 deg/h, tau0 0.01 s, no input rate, pulses of 1e-9 arcsec (quantization bound 1.4e-7
  // deg/h at tau0, 1e-6 of the deviation), 16 seeds of 2^17 samples (22 min), octaves up to 2^13
  // (82 s). Tc = 0.003 s (phi = 0.036: a nearly white rate), 1 s (the ADEV peak at 1.9 s inside),
  // 30 s (close to a rate random walk up to 3 s; peak at 57 s). At Tc = 1 s the continuous form
  // (IEEE Std 952 Annex C), whose AVAR is 33 % low at tau0 and 11 % at 2 tau0, must be excluded there: the
  // simulator holds the rate over each sample, as stated.
  // Each Tc has its own 16 seeds (the same seeds would give the three the same innovations).
  const std::uint64_t n = 1u << 17, m_max = 1u << 13;
  std::uint64_t seed = 0;
  for (double tc : {0.003, 1.0, 30.0}) {
    SimOptions o;
    o.rate_deg_per_h = 0;
    o.pulse_arcsec = 1e-9;
    o.markov = {{1.0, tc}};
    std::vector<std::vector<double>> avar(octaves(m_max).size()), mvar(avar.size());
    for (int run = 0; run < 16; ++run) {
      o.seed = ++seed;
      const Curves c = measure(o, n, m_max);
      for (std::size_t i = 0; i < c.m.size(); ++i) {
        avar[i].push_back(c.avar[i]);
        mvar[i].push_back(c.mvar[i]);
      }
    }
    std::printf("Tc %g s: m, ADEV / exact (+- seed spread of the mean), MDEV / exact\n", tc);
    for (std::size_t i = 0; i < avar.size(); ++i) {
      const std::uint64_t m = std::uint64_t{1} << i;
      const double tau = static_cast<double>(m) * o.tau0_s, bound = std::sqrt(2.0) * o.pulse_arcsec / tau;
      const double want_a = markov_avar(1.0, o.tau0_s, tc, m), want_m = markov_mvar(1.0, o.tau0_s, tc, m);
      const oracle::Spread sa = oracle::spread(avar[i]), sm = oracle::spread(mvar[i]);
      const double ha = sa.half_width(p_false), hm = sm.half_width(p_false);
      EXPECT_TRUE(within(want_a, sa.mean - ha, sa.mean + ha, bound))
          << "Tc " << tc << " m=" << m << " AVAR " << sa.mean << " +- " << ha << " exact " << want_a;
      EXPECT_TRUE(within(want_m, sm.mean - hm, sm.mean + hm, bound))
          << "Tc " << tc << " m=" << m << " MVAR " << sm.mean << " +- " << hm << " exact " << want_m;
      std::printf("  %5llu  %.5f(%.5f)  %.5f(%.5f)\n", static_cast<unsigned long long>(m), std::sqrt(sa.mean / want_a),
                  sa.sd / std::sqrt(16.0) / (2 * want_a), std::sqrt(sm.mean / want_m),
                  sm.sd / std::sqrt(16.0) / (2 * want_m));
      if (tc == 1.0 && m <= 2) {
        const double x = tau / tc, continuous = (2 * x - 3 + 4 * std::exp(-x) - std::exp(-2 * x)) / (x * x);
        EXPECT_FALSE(within(continuous, sa.mean - ha, sa.mean + ha, bound)) << "m=" << m;
      }
    }
  }
}

TEST(SimSinusoid, EachTermAloneFollowsItsClosedForm) {
  // A = 10 deg/h, tau0 0.01 s, no input rate, pulses of 1e-6 arcsec, 2^16 samples, octaves up to
  // 2^13. f tau0 = 0.1234567 (incommensurate), 0.4, 0.49 (near the Nyquist frequency), 0.003 (a
  // period of 333 samples). Tolerance: one phase's departure 1 / (M |sin(2 pi f tau0)|) relative,
  // the quantization bound sqrt(2) pulse / tau, and the double rounding of the accumulated angle
  // (at most 2^-52 of its largest value, A / (pi f), per sample, 65536 samples: 1e-11 of A / f). At
  // f tau0 = 0.4 a rate held over each sample at its value at the interval's start would show
  // 1 / sinc^2(0.4 pi) = 1.75 times the AVAR: excluded wherever the closed form dwarfs the
  // tolerance.
  const std::uint64_t n = 1u << 16;
  for (double f_tau0 : {0.1234567, 0.4, 0.49, 0.003}) {
    SimOptions o;
    o.rate_deg_per_h = 0;
    o.pulse_arcsec = 1e-6;
    o.sinusoids = {{10.0, f_tau0 / o.tau0_s}};
    const double a = 10.0, f = f_tau0 / o.tau0_s;
    const double sin_b = std::fabs(std::sin(2 * pi * f_tau0));
    const double rounding = static_cast<double>(n) * 0x1p-52 * a / (pi * f);
    const Curves c = measure(o, n, 1u << 13);
    double worst_a = 0, worst_m = 0;  // largest |deviation / closed form - 1| where the closed form dwarfs the bound
    for (std::size_t i = 0; i < c.m.size(); ++i) {
      const double tau = static_cast<double>(c.m[i]) * o.tau0_s;
      const double bound = std::sqrt(2.0) * (o.pulse_arcsec + rounding) / tau;
      const double want_a = sinusoid_avar(a, f, tau), want_m = sinusoid_mvar(a, f, o.tau0_s, c.m[i]);
      const double ra = 1 / (static_cast<double>(c.avar_terms[i]) * sin_b),
                   rm = 1 / (static_cast<double>(c.mvar_terms[i]) * sin_b);
      EXPECT_TRUE(within(c.avar[i], want_a * (1 - ra), want_a * (1 + ra), bound))
          << "f tau0 " << f_tau0 << " m=" << c.m[i] << " ADEV " << std::sqrt(c.avar[i]) << " closed " << std::sqrt(want_a);
      EXPECT_TRUE(within(c.mvar[i], want_m * (1 - rm), want_m * (1 + rm), bound))
          << "f tau0 " << f_tau0 << " m=" << c.m[i] << " MDEV " << std::sqrt(c.mvar[i]) << " closed " << std::sqrt(want_m);
      if (std::sqrt(want_a) > 100 * bound) worst_a = std::max(worst_a, std::fabs(std::sqrt(c.avar[i] / want_a) - 1));
      if (std::sqrt(want_m) > 100 * bound) worst_m = std::max(worst_m, std::fabs(std::sqrt(c.mvar[i] / want_m) - 1));
      if (f_tau0 == 0.4 && std::sqrt(want_a) > 100 * bound) {
        const double s = std::sin(pi * f_tau0) / (pi * f_tau0), held = want_a / (s * s);
        EXPECT_FALSE(within(c.avar[i], held * (1 - ra), held * (1 + ra), bound)) << "m=" << c.m[i];
      }
    }
    std::printf("f tau0 %g: ADEV within %.1e of the closed form, MDEV within %.1e (where it dwarfs the bound)\n", f_tau0,
                worst_a, worst_m);
  }
}

TEST(SimRateTerms, TheOtherTermsKeepTheirRandomStream) {
  // Oracle: the run without the new terms. Every other term on, with their own draws; a
  // Gauss-Markov term of 1e-300 deg/h and a sinusoid of amplitude 0 change no count, so the first
  // stream is untouched (the terms draw from their own). And the terms' own draws follow the seed:
  // the same seed repeats a run, another changes it.
  SimOptions o;
  o.white_angle_arcsec = 0.3;
  o.arw_deg_per_sqrt_h = 0.01;
  o.rrw_deg_per_h_sqrt_h = 0.1;
  o.bias_deg_per_h = 0.05;
  o.bias_time_s = 500;
  o.dither_arcsec = 7;
  o.dither_hz = 437.3;
  o.seed = 12345;
  SimOptions with = o;
  with.markov = {{1e-300, 10}, {1e-300, 0.02}};
  with.sinusoids = {{0, 1}};
  SimRun plain(o), added(with);
  for (std::uint64_t k = 0; k < (1u << 16); ++k) ASSERT_EQ(plain.next_count(), added.next_count()) << k;
  SimOptions terms;
  terms.rate_deg_per_h = 0;
  terms.pulse_arcsec = 1e-6;
  terms.markov = {{1, 10}};
  terms.sinusoids = {{10, 3}};
  const auto counts = [](const SimOptions& s) {
    SimRun run(s);
    std::vector<std::int64_t> c(1000);
    for (auto& v : c) v = run.next_count();
    return c;
  };
  EXPECT_EQ(counts(terms), counts(terms));
  SimOptions other = terms;
  other.seed = 2;
  EXPECT_NE(counts(terms), counts(other));
  other = terms;
  other.markov.clear();  // the sinusoid alone: its phase comes from the seed too
  const std::vector<std::int64_t> first = counts(other);
  other.seed = 2;
  EXPECT_NE(counts(other), first);
}

}  // namespace
}  // namespace gyrochar
