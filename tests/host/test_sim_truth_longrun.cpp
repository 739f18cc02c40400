// The simulator's truth on long runs and many seeds (label "long": the host suite runs it, the
// sanitizer build does not). Same oracles and acceptance as test_sim_truth.cpp (closed forms of
// IEEE Std 952 Annex C; the exact EDF, the seed spread or the quantization bound; p = 1e-4 per
// comparison), plus: the EDF itself checked against the spread over seeds, the bias-instability
// floor at the default band, the symptom of an old bias-instability bias (ARW 0.005 deg/sqrt(h) + B 0.05 deg/h, 4 h at
// tau0 0.1 s) on the simulator's side, and the departures of non-white quantization. Each test
// prints the figures docs/metrology.md quotes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "host/sim_truth_support.hpp"

namespace gyrochar {
namespace {

using namespace sim_truth;

double avar_quantization_and_arw(const SimOptions& o, double tau) { return avar_white_angle(o, tau) + avar_arw(o, tau); }

TEST(SimTruthLong, WhiteAngleTermsOn2To24Samples) {
  SimOptions o;
  std::printf("quantization, white angle noise q = pulse / sqrt(2) (a random pulse per sample): 3 Q^2 / tau^2\n");
  o.white_angle_arcsec = 1 / std::sqrt(2.0);
  expect_consistent(simulate(o, 1u << 24, 1u << 16), o, avar_white_angle, 64, true);
  std::printf("white angle noise q = 10 pulses: 3 (q^2 + pulse^2 / 12) / tau^2\n");
  o.white_angle_arcsec = 10;
  expect_consistent(simulate(o, 1u << 24, 1u << 16), o, avar_white_angle, 64, true);
}

TEST(SimTruthLong, AngleRandomWalkOn2To24Samples) {
  SimOptions o;
  std::printf("quantization under ARW of one pulse per sample: 3 (pulse^2 / 12) / tau^2 + N^2 / tau\n");
  o.arw_deg_per_sqrt_h = 1.0 / 60 / std::sqrt(o.tau0_s);
  expect_consistent(simulate(o, 1u << 24, 1u << 18), o, avar_quantization_and_arw, 64, true);
  std::printf("ARW N = 0.1 deg/sqrt(h), pulses 0.25 arcsec: N^2 / tau + 3 (pulse^2 / 12) / tau^2\n");
  o.arw_deg_per_sqrt_h = 0.1;
  o.pulse_arcsec = 0.25;
  o.seed = 2;  // another realization (seed 1 would scale the same random walk)
  expect_consistent(simulate(o, 1u << 24, 1u << 18), o, avar_quantization_and_arw, 64, true);
}

TEST(SimTruthLong, RateRandomWalkOn2To23Samples) {
  // Pulses of 1e-9 arcsec: quantization at most sqrt(2) pulse / tau, 1e-7 of the deviation.
  SimOptions o;
  o.rate_deg_per_h = 0;
  o.rrw_deg_per_h_sqrt_h = 1;
  o.pulse_arcsec = 1e-9;
  std::printf("RRW K = 1 deg/h/sqrt(h): K^2 tau / 3\n");
  expect_consistent(simulate(o, 1u << 23, 1u << 17), o, avar_rrw, 64, true);
}

TEST(SimTruthLong, EdfAgreesWithTheSpreadOverSeeds) {
  // The tolerance of the single-run tests rests on the exact EDF: here 64 seeds of 2^16 samples
  // check it. Over seeds, AVAR_hat has variance 2 AVAR^2 / EDF; the sample variance s^2 of 64
  // estimates then follows (2 AVAR^2 / EDF) chi2_63 / 63, and the mean AVAR_hat is within
  // t_63 s / 8 of the closed form.
  struct Case {
    const char* name;
    SimOptions o;
    ClosedForm closed;
  };
  std::vector<Case> cases(3);
  cases[0] = {"white PM (q = 10 pulses)", SimOptions{}, avar_white_angle};
  cases[0].o.white_angle_arcsec = 10;
  cases[1] = {"white FM (ARW 0.1 deg/sqrt(h), 0.25 arcsec pulses)", SimOptions{}, avar_quantization_and_arw};
  cases[1].o.arw_deg_per_sqrt_h = 0.1;
  cases[1].o.pulse_arcsec = 0.25;
  cases[2] = {"random-walk FM (RRW 1 deg/h/sqrt(h))", SimOptions{}, avar_rrw};
  cases[2].o.rate_deg_per_h = 0;
  cases[2].o.rrw_deg_per_h_sqrt_h = 1;
  cases[2].o.pulse_arcsec = 1e-9;
  const std::uint64_t n = 1u << 16, seeds = 64;
  const std::vector<std::uint64_t> ms = octaves(1024);
  const boost::math::chi_squared chi2(static_cast<double>(seeds - 1));
  const double low = boost::math::quantile(chi2, p_false / 2) / static_cast<double>(seeds - 1);
  const double high = boost::math::quantile(chi2, 1 - p_false / 2) / static_cast<double>(seeds - 1);
  for (Case& c : cases) {
    std::vector<std::vector<double>> avar(ms.size());
    std::uint64_t terms_at[16] = {};
    for (std::uint64_t seed = 1; seed <= seeds; ++seed) {
      c.o.seed = seed;
      const Measured r = simulate(c.o, n, ms.back());
      for (std::size_t i = 0; i < ms.size(); ++i) {
        avar[i].push_back(r.avar_dph2(i));
        terms_at[i] = r.avar.terms(i);
      }
    }
    std::printf("%s, %llu seeds of %llu samples: observed / predicted variance of AVAR_hat\n", c.name,
                static_cast<unsigned long long>(seeds), static_cast<unsigned long long>(n));
    for (std::size_t i = 0; i < ms.size(); i += 2) {
      const oracle::Spread s = oracle::spread(avar[i]);
      const double truth = c.closed(c.o, static_cast<double>(ms[i]) * c.o.tau0_s);
      const double edf = oracle::avar_edf(levels(c.o), ms[i], terms_at[i]);
      const double ratio = s.sd * s.sd / (2 * truth * truth / edf);
      std::printf("  m %5llu  EDF %10.1f  variance ratio %.3f (accepted %.3f .. %.3f)  mean / closed %.5f\n",
                  static_cast<unsigned long long>(ms[i]), edf, ratio, low, high, s.mean / truth);
      EXPECT_TRUE(ratio >= low && ratio <= high) << c.name << " m=" << ms[i];
      EXPECT_NEAR(s.mean, truth, s.half_width(p_false)) << c.name << " m=" << ms[i];
    }
  }
}

// Mean AVAR over seeds at the octaves up to m_max.
std::vector<oracle::Spread> over_seeds(SimOptions o, std::uint64_t seeds, std::uint64_t n, std::uint64_t m_max) {
  std::vector<std::vector<double>> per_tau(octaves(m_max).size());
  for (std::uint64_t seed = 1; seed <= seeds; ++seed) {
    o.seed = seed;
    const Measured r = simulate(o, n, m_max);
    for (std::size_t i = 0; i < r.avar.size(); ++i) per_tau[i].push_back(r.avar_dph2(i));
  }
  std::vector<oracle::Spread> s;
  for (const auto& v : per_tau) s.push_back(oracle::spread(v));
  return s;
}

void check_flicker(const SimOptions& o, std::uint64_t seeds, std::uint64_t n) {
  const std::vector<oracle::Spread> s = over_seeds(o, seeds, n, n / 4);
  const double floor_avar = std::pow(flicker_floor * o.bias_deg_per_h, 2);
  std::printf("B %g deg/h, bias time %g s, tau0 %g s: %llu seeds of %llu samples; ADEV / (0.664 B)\n", o.bias_deg_per_h,
              o.bias_time_s, o.tau0_s, static_cast<unsigned long long>(seeds), static_cast<unsigned long long>(n));
  for (std::size_t i = 0; i < s.size(); ++i) {
    const std::uint64_t m = std::uint64_t{1} << i;
    const double tau = static_cast<double>(m) * o.tau0_s;
    const double model = oracle::flicker_model_avar(o.bias_deg_per_h, o.tau0_s, o.bias_time_s, m);
    // The standard uncertainty of the ratio of deviations, from the seed spread of the AVAR mean.
    const double u = s[i].sd / std::sqrt(static_cast<double>(seeds)) / (2 * s[i].mean);
    std::printf("  m %8llu  tau %10.1f s  measured %.4f +- %.4f  model %.4f\n", static_cast<unsigned long long>(m), tau,
                std::sqrt(s[i].mean / floor_avar), u * std::sqrt(s[i].mean / floor_avar), std::sqrt(model / floor_avar));
    EXPECT_NEAR(s[i].mean, model, s[i].half_width(p_false)) << "m=" << m;
    if (m >= 4 && tau <= 0.059 * o.bias_time_s) {
      const double band = tau <= 0.017 * o.bias_time_s ? 0.003 : 0.01;
      EXPECT_NEAR(s[i].mean, floor_avar, s[i].half_width(p_false) + 2 * band * floor_avar) << "m=" << m;
    }
  }
}

TEST(SimTruthLong, BiasInstabilityFloorAtTheDefaultBand) {
  SimOptions o;
  o.tau0_s = 0.1;
  o.rate_deg_per_h = 0;
  o.bias_deg_per_h = 0.05;
  o.pulse_arcsec = 1e-7;
  check_flicker(o, 32, 1u << 17);
}

TEST(SimTruthLong, BiasInstabilityRollsOffBelowTheBand) {
  SimOptions o;
  o.rate_deg_per_h = 0;
  o.bias_deg_per_h = 0.05;
  o.bias_time_s = 100;
  o.pulse_arcsec = 1e-8;
  check_flicker(o, 32, 1u << 18);
}

TEST(SimTruthLong, ArwPlusBiasInstabilityFourHoursAtTenthSecond) {
  // The simulator's side of that symptom (the fit returned B about 0.105-0.111 deg/h): 16
  // seeds of gyrochar-sim --duration 14400 --tau0 0.1 --arw 0.005 --bias-instability 0.05 (earth
  // rate, 1 arcsec pulses). Oracle: 3 Q^2 / tau^2 + N^2 / tau + (0.664 B)^2 with Q = 1/sqrt(12)
  // arcsec, wherever the quantization is white at lag m: the angle random walk spreads the angle
  // by N sqrt(m tau0) = 0.095 sqrt(m) arcsec over m samples, a pulse from m = 111 on (below,
  // the steady earth rate's periodic pattern shows: printed, not judged). The band's model
  // departure is allowed as in check_flicker. Then B read off the simulator's own curve,
  // B = sqrt(AVAR - N^2 / tau - 3 Q^2 / tau^2) / 0.664 over tau 400 .. 1638 s.
  SimOptions o;
  o.tau0_s = 0.1;
  o.arw_deg_per_sqrt_h = 0.005;
  o.bias_deg_per_h = 0.05;
  const std::uint64_t seeds = 16, n = 144000;
  const std::vector<oracle::Spread> s = over_seeds(o, seeds, n, 1u << 14);
  std::printf("ARW 0.005 deg/sqrt(h) + B 0.05 deg/h, 4 h at tau0 0.1 s, %llu seeds: ADEV (deg/h)\n",
              static_cast<unsigned long long>(seeds));
  double b_sum = 0, b_var = 0;
  for (std::size_t i = 0; i < s.size(); ++i) {
    const std::uint64_t m = std::uint64_t{1} << i;
    const double tau = static_cast<double>(m) * o.tau0_s;
    const double white = avar_white_angle(o, tau) + avar_arw(o, tau);
    const double closed = white + std::pow(flicker_floor * o.bias_deg_per_h, 2);
    const double u = s[i].sd / std::sqrt(static_cast<double>(seeds)) / (2 * s[i].mean);
    std::printf("  m %6llu  tau %7.1f s  measured %.5f +- %.5f  closed form %.5f  ratio %.4f\n",
                static_cast<unsigned long long>(m), tau, std::sqrt(s[i].mean), u * std::sqrt(s[i].mean), std::sqrt(closed),
                std::sqrt(s[i].mean / closed));
    if (m >= 128) {
      const double band = tau <= 0.017 * o.bias_time_s ? 0.003 : 0.01;
      const double flicker = std::pow(flicker_floor * o.bias_deg_per_h, 2);
      EXPECT_NEAR(s[i].mean, closed, s[i].half_width(p_false) + 2 * band * flicker) << "m=" << m;
    }
    if (tau >= 400 && tau <= 1700) {  // B from the floor: the white terms are 26 % .. 8 % of AVAR here
      const double b = std::sqrt(s[i].mean - white) / flicker_floor;
      const double u_b = s[i].sd / std::sqrt(static_cast<double>(seeds)) / (2 * (s[i].mean - white)) * b;
      std::printf("    B from the curve: %.4f +- %.4f deg/h\n", b, u_b);
      b_sum += b / (u_b * u_b);
      b_var += 1 / (u_b * u_b);
      const double half = s[i].half_width(p_false) / (2 * (s[i].mean - white)) * b;    // Student t, 15 dof
      EXPECT_NEAR(b, o.bias_deg_per_h, half + 0.003 * o.bias_deg_per_h) << "m=" << m;  // + the band's 0.3 %
    }
  }
  std::printf(
      "  B read off the simulator's curve (weighted over the three taus, correlated): %.4f +- %.4f deg/h "
      "(truth 0.05)\n",
      b_sum / b_var, 1 / std::sqrt(b_var));
}

TEST(SimTruthLong, SteadyRateBelowAPulsePerSampleQuantizesPeriodically) {
  // Earth rate 15.041 deg/h, 1 arcsec pulses, tau0 0.01 s, ARW 0.003 deg/sqrt(h): ADEV over the
  // closed form sqrt(3 Q^2 / tau^2 + N^2 / tau). The pattern fades once the angle random walk
  // spreads the angle by a pulse over the lag, N sqrt(m tau0) >= 1 arcsec: m >= 3086; from
  // m = 4096 the closed form must hold (seed spread); below, the figures are what the
  // documentation quotes (test_sim_truth.cpp checks the first five).
  SimOptions o;
  o.arw_deg_per_sqrt_h = 0.003;
  const std::uint64_t seeds = 16, n = 1u << 20;
  const std::vector<oracle::Spread> s = over_seeds(o, seeds, n, 1u << 14);
  std::printf("earth rate, 1 arcsec pulses, tau0 0.01 s, ARW 0.003 deg/sqrt(h), %llu seeds of 2^20 samples\n",
              static_cast<unsigned long long>(seeds));
  for (std::size_t i = 0; i < s.size(); ++i) {
    const std::uint64_t m = std::uint64_t{1} << i;
    const double tau = static_cast<double>(m) * o.tau0_s;
    const double closed = avar_white_angle(o, tau) + avar_arw(o, tau);
    const double ratio = std::sqrt(s[i].mean / closed);
    const double u = s[i].sd / std::sqrt(static_cast<double>(seeds)) / (2 * s[i].mean) * ratio;
    std::printf("  m %6llu  tau %7.2f s  ADEV / closed form %.4f +- %.1e\n", static_cast<unsigned long long>(m), tau, ratio,
                u);
    if (m >= 4096) {
      EXPECT_NEAR(s[i].mean, closed, s[i].half_width(p_false)) << "m=" << m;
    }
  }
}

TEST(SimTruthLong, DitherAloneWhitensQuantizationOnlyRoughly) {
  // A deterministic run (no random term): 5 arcsec of dither at 437.3 Hz sampled every 0.01 s
  // (0.373 cycle per sample after aliasing, up to 9 pulses per sample), earth rate, 1 arcsec
  // pulses. The quantization's part, AVAR - the sampled dither's exact AVAR, over
  // 3 (pulse^2 / 12) / tau^2: printed, and bounded by the documented worst departure.
  SimOptions o;
  o.dither_arcsec = 5;
  o.dither_hz = 437.3;
  ASSERT_TRUE(quantization_expected_white(o));
  const std::uint64_t n = 1u << 22;
  const Measured r = simulate(o, n, 1024);
  double worst = 0;
  std::printf("dither 5 arcsec at 437.3 Hz, tau0 0.01 s, earth rate, 1 arcsec pulses, 2^22 samples\n");
  for (std::size_t i = 0; i < r.avar.size(); ++i) {
    const double tau = r.tau_s(i);
    const double dither = dither_avar_sampled(o.dither_arcsec, o.dither_hz, o.tau0_s, r.avar.m(i), n);
    const double quantization = avar_white_angle(o, tau);
    const double part = (r.avar_dph2(i) - dither) / quantization;
    const double total = std::sqrt(r.avar_dph2(i) / (dither + quantization));
    std::printf("  m %5llu  dither / quantization AVAR %9.3g  quantization part / closed form %.3f  ADEV / closed %.4f\n",
                static_cast<unsigned long long>(r.avar.m(i)), dither / quantization, part, total);
    worst = std::max(worst, std::fabs(total - 1));
  }
  EXPECT_LT(worst, 0.10);  // documented: up to 9.5 % where the sampled dither nearly repeats
}

}  // namespace
}  // namespace gyrochar
