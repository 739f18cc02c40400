#pragma once
// The expected overlapping AVAR of the simulator's bias-instability model, computed exactly from
// the model as documented (gyro_sim.hpp, docs/metrology.md), independently of its implementation:
// a sum of stationary AR(1) rates r_k (variance s2 = B^2 ln 2 / pi, coefficient phi = exp(-a),
// a = 2 pi f tau0, corners f = 0.34 / tau0, halving down to the first at or below
// 1 / (2 pi bias_time)), each held over its tau0 interval.
// For one AR(1): with the phase in units of rate x tau0, x_k = sum_{i<k} r_i, the structure
// function is V(n) = E[(x_{j+n} - x_j)^2] = s2 (n + 2 S(n)), S(n) = sum_{l=1}^{n-1} (n - l) phi^l,
// and a term D = x[j+2m] - 2x[j+m] + x[j] = (increment over m) - (previous increment) has
// E[D^2] = 4 V(m) - V(2m) = s2 (2 T(2m) - 8 T(m)), T(n) = sum_{l=1}^{n-1} (n - l)(1 - phi^l)
// (substitute phi^l = 1 - (1 - phi^l); the n and n^2 parts cancel). AVAR = E[D^2] / (2 m^2).
// T(n) in closed form, n(n-1)/2 - [n phi (1 - phi) - phi (1 - phi^n)] / (1 - phi)^2, cancels
// catastrophically when n a is small: there the Taylor series in a to 4th order is used (error
// (n a)^5 relative, below 1e-15 for n a < 1e-3); long double throughout (checked against the
// direct sum to 1e-12 over n = 2 .. 10^6, a = 1e-9 .. 1).
#include <cmath>
#include <cstdint>
#include <vector>

namespace gyrochar::oracle {

inline long double ar1_t(std::uint64_t n, long double a) {
  if (n < 2) return 0;
  const long double N = static_cast<long double>(n);
  if (N * a < 1e-3L) {
    const long double M = N - 1;  // sums over l = 1 .. M of l^k: P1 .. P5
    const long double p1 = M * (M + 1) / 2, p2 = M * (M + 1) * (2 * M + 1) / 6, p3 = p1 * p1;
    const long double p4 = M * (M + 1) * (2 * M + 1) * (3 * M * M + 3 * M - 1) / 30;
    const long double p5 = M * M * (M + 1) * (M + 1) * (2 * M * M + 2 * M - 1) / 12;
    const long double s1 = N * p1 - p2, s2 = N * p2 - p3, s3 = N * p3 - p4, s4 = N * p4 - p5;  // sum (n-l) l^k
    return a * s1 - a * a / 2 * s2 + a * a * a / 6 * s3 - a * a * a * a / 24 * s4;
  }
  const long double e = -std::expm1(-a), phi = std::exp(-a), en = -std::expm1(-N * a);
  return N * (N - 1) / 2 - (N * phi * e - phi * en) / (e * e);
}

/// Expected AVAR at m of a stationary AR(1) rate of variance s2 and coefficient exp(-a), held over
/// each sample: in the rate's unit squared.
inline double ar1_avar(double s2, double a, std::uint64_t m) {
  const long double mm = static_cast<long double>(m);
  return static_cast<double>(s2 * (2 * ar1_t(2 * m, a) - 8 * ar1_t(m, a)) / (2 * mm * mm));
}

/// The corners (Hz) of the documented flicker band.
inline std::vector<double> flicker_band_hz(double tau0_s, double bias_time_s) {
  const double pi = 3.14159265358979323846;
  std::vector<double> f;
  for (double c = 0.34 / tau0_s;; c *= 0.5) {
    f.push_back(c);
    if (c <= 1.0 / (2 * pi * bias_time_s)) break;
  }
  return f;
}

/// Expected AVAR at m of the simulator's bias instability B (rate unit of B, squared).
inline double flicker_model_avar(double b, double tau0_s, double bias_time_s, std::uint64_t m) {
  const double pi = 3.14159265358979323846;
  const double s2 = b * b * std::log(2.0) / pi;
  double avar = 0;
  for (double f : flicker_band_hz(tau0_s, bias_time_s)) avar += ar1_avar(s2, 2 * pi * f * tau0_s, m);
  return avar;
}

}  // namespace gyrochar::oracle
