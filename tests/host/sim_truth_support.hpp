#pragma once
// Shared by test_sim_truth.cpp and test_sim_truth_longrun.cpp: a simulation measured with the
// brute-force overlapping AVAR, the IEEE Std 952 closed forms (the oracles) in gyrochar-sim's
// command-line units, the noise levels for the exact EDF, and the sampled dither's exact AVAR.
// Deviations are in deg/h, which is arcsec/s.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "gyro_sim.hpp"
#include "oracle/avar_edf.hpp"
#include "oracle/chi2_check.hpp"
#include "oracle/flicker_markov.hpp"
#include "oracle/overlapping_avar.hpp"
#include "sim_truth.hpp"

namespace gyrochar::sim_truth {

constexpr double p_false = 1e-4;  // two-sided false-alarm probability of each statistical comparison
constexpr double pi = units::pi;
inline const double flicker_floor = std::sqrt(2 * std::log(2.0) / pi);  // 0.664: ADEV floor / B

inline std::vector<std::uint64_t> octaves(std::uint64_t m_max) {
  std::vector<std::uint64_t> m;
  for (std::uint64_t v = 1; v <= m_max; v *= 2) m.push_back(v);
  return m;
}

// n counts of a simulation, measured at the octaves up to m_max; AVAR in (arcsec/s)^2 = (deg/h)^2.
struct Measured {
  oracle::OverlappingAvar avar;
  double pulse_arcsec, tau0_s;
  double avar_dph2(std::size_t i) const { return avar.avar(i, tau0_s) * pulse_arcsec * pulse_arcsec; }
  double tau_s(std::size_t i) const { return static_cast<double>(avar.m(i)) * tau0_s; }
};

inline Measured simulate(const SimOptions& o, std::uint64_t n, std::uint64_t m_max) {
  GyroSimulator sim(gyro_parameters(o));
  Measured r{oracle::OverlappingAvar(octaves(m_max)), o.pulse_arcsec, o.tau0_s};
  for (std::uint64_t k = 0; k < n; ++k) r.avar.add(sim.next_count());
  return r;
}

// Noise levels for the EDF, in pulses^2 (the white PM of the quantization and white angle noise,
// the white FM of the angle random walk, the random-walk FM).
inline oracle::NoiseLevels levels(const SimOptions& o) {
  const double w = o.pulse_arcsec;
  const double arw_arcsec = 60 * o.arw_deg_per_sqrt_h;    // deg/sqrt(h) = 60 arcsec/sqrt(s)
  const double rrw_arcsec = o.rrw_deg_per_h_sqrt_h / 60;  // deg/h/sqrt(h) = arcsec/s/(60 sqrt(s))
  return {(o.white_angle_arcsec * o.white_angle_arcsec + w * w / 12) / (w * w), arw_arcsec * arw_arcsec * o.tau0_s / (w * w),
          rrw_arcsec * rrw_arcsec * o.tau0_s * o.tau0_s * o.tau0_s / (w * w)};
}

// Closed forms (IEEE Std 952 Annex C), AVAR in (deg/h)^2 at tau in s, from the CLI units.
inline double avar_white_angle(const SimOptions& o, double tau) {  // 3 Q^2 / tau^2, Q^2 = q^2 + w^2 / 12
  return 3 * (o.white_angle_arcsec * o.white_angle_arcsec + o.pulse_arcsec * o.pulse_arcsec / 12) / (tau * tau);
}
inline double avar_arw(const SimOptions& o, double tau) {  // N^2 / tau
  const double n = 60 * o.arw_deg_per_sqrt_h;
  return n * n / tau;
}
inline double avar_rrw(const SimOptions& o, double tau) {  // K^2 tau / 3
  const double k = o.rrw_deg_per_h_sqrt_h / 60;
  return k * k * tau / 3;
}

// Checks a stochastic term at every octave with at least n_per_m_min m phase points: the closed
// form inside the estimate's 1 - p interval (exact EDF). With `print`, a table of
// m, tau, ADEV, closed form, their ratio and the ratio's standard uncertainty 1 / sqrt(2 EDF).
using ClosedForm = double (*)(const SimOptions&, double);
inline void expect_consistent(const Measured& r, const SimOptions& o, ClosedForm closed, std::uint64_t n_per_m_min = 64,
                              bool print = false) {
  for (std::size_t i = 0; i < r.avar.size(); ++i) {
    if (r.avar.terms(i) < n_per_m_min * r.avar.m(i)) continue;
    const double tau = r.tau_s(i), truth = closed(o, tau);
    const double edf = oracle::avar_edf(levels(o), r.avar.m(i), r.avar.terms(i));
    const oracle::Range range = oracle::chi2_range(r.avar_dph2(i), edf, p_false);
    EXPECT_TRUE(range.contains(truth)) << "m=" << r.avar.m(i) << " ADEV " << std::sqrt(r.avar_dph2(i)) << " closed form "
                                       << std::sqrt(truth) << " interval " << std::sqrt(range.low) << " .. "
                                       << std::sqrt(range.high) << " (EDF " << edf << ")";
    if (print)
      std::printf("  m %7llu  tau %9.3f s  ADEV %.6g  closed %.6g  ratio %.5f +- %.5f\n",
                  static_cast<unsigned long long>(r.avar.m(i)), tau, std::sqrt(r.avar_dph2(i)), std::sqrt(truth),
                  std::sqrt(r.avar_dph2(i) / truth), 1 / std::sqrt(2 * edf));
  }
}

// The dither at the sample instants, x_k = A sin(b k), b = 2 pi f tau0 (x_0 = 0 as the counts'
// phase). With c = m b the term is x[j+2m] - 2x[j+m] + x[j] = -4 A sin^2(c/2) sin(b j + c), so over
// the M = N - 2m + 1 terms of N counts
//   AVAR_M = (4 A^2 sin^4(pi f tau) / tau^2) [1 - cos(2c + (M-1) b) sin(M b) / (M sin b)]
// (the mean of sin^2(b j + c) over j), exactly; when sin b = 0 the bracket is 1 - cos 2c.
// As M grows it tends to 4 A^2 sin^4(pi f tau) / tau^2, within 1 / (M |sin b|) relative.
inline double dither_avar_sampled(double a, double f, double tau0, std::uint64_t m, std::uint64_t n_counts) {
  const double b = 2 * pi * f * tau0, c = static_cast<double>(m) * b, tau = static_cast<double>(m) * tau0;
  const double big_m = static_cast<double>(n_counts - 2 * m + 1);
  const double s = std::sin(pi * f * tau);
  const double bracket = std::fabs(std::sin(b)) < 1e-9  // b a multiple of pi: sin^2(b j + c) = sin^2 c
                             ? 1 - std::cos(2 * c)
                             : 1 - std::cos(2 * c + (big_m - 1) * b) * std::sin(big_m * b) / (big_m * std::sin(b));
  return 4 * a * a * s * s * s * s / (tau * tau) * bracket;
}

}  // namespace gyrochar::sim_truth
