#pragma once
// IEEE Std 952 gyro error model fitted to a whole Allan or modified Allan variance curve by
// weighted least squares on the variance (not by reading slopes). Freestanding, fixed size.
//
// Model (tau in s; rate in any unit r/s, angle unit r):
//   AVAR(tau) = 3 Q^2 / tau^2 + N^2 / tau + (2 ln 2 / pi) B^2 + K^2 tau / 3 + R^2 tau^2 / 2
//   MVAR(tau) = 3 Q^2 tau0 / tau^3 + N^2 (m^2 + 1) / (2 m^2 tau) + 0.2977 B^2 + 11 K^2 tau / 40
//               + R^2 tau^2 / 2,    m = tau / tau0
// (design brief section 3). Q in r, N in r/s^0.5, B in r/s, K in r/s^1.5, R in r/s^2.
// The five coefficients Q^2 .. R^2 are fitted at once, weights from the EDF of each point
// (var(sigma^2) = 2 sigma^4 / edf, sigma^2 from the model, iterated); a coefficient the data
// cannot support (it would go negative) is dropped and the rest refitted: it is "not resolved".
#include <array>
#include <cstddef>
#include <span>

namespace gyrochar {

struct VariancePoint {
  double tau_s = 0;     // averaging time
  double variance = 0;  // AVAR or MVAR in (r/s)^2
  double edf = 0;       // equivalent degrees of freedom; points with edf <= 0 are skipped
};

enum class Ieee952Curve { avar, mvar };

struct Ieee952Parameter {
  double value = 0;        // Q, N, B, K or R in the units above
  double uncertainty = 0;  // standard uncertainty, same unit
  bool resolved = false;
};

struct Ieee952Fit {
  std::array<Ieee952Parameter, 5> p{};  // Q, N, B, K, R
  double chi2_per_dof = 0;              // of the final weighted fit; about 1 when the model fits
  std::size_t points = 0;               // points used
  bool ok = false;                      // false: fewer usable points than resolved terms
};

/// Fits the model to `points` (any order). tau0_s is needed for the MVAR curve. O(points), no
/// allocation, never fails hard.
Ieee952Fit fit_ieee952(std::span<const VariancePoint> points, Ieee952Curve curve, double tau0_s = 1.0);

/// The model variance at tau for parameters {Q, N, B, K, R} (same units as fit_ieee952).
double ieee952_variance(const std::array<double, 5>& qnbkr, double tau_s, Ieee952Curve curve, double tau0_s = 1.0);

}  // namespace gyrochar
