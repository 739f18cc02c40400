#include "sim_closed_forms.hpp"

#include <cmath>

#include "units.hpp"

namespace gyrochar {

namespace {

using real = long double;

// Below this n tau0 / Tc the closed forms lose more than 1e-14 to cancellation (MVAR's relative
// error in long double: 6e-15 at 0.1, 1e-13 at 0.05, 1e-10 at 0.01); the exact O(n) sum takes over.
constexpr real closed_form_min_x = 0.1L;

struct Ar1 {
  real phi, e, u, one_minus_phi2;  // exp(-a), 1 - phi, 1 - phi^n, 1 - phi^2; a = tau0 / Tc
};

Ar1 ar1(double tau0_s, double tc_s, std::uint64_t n) {
  const real a = static_cast<real>(tau0_s) / static_cast<real>(tc_s);
  return {std::exp(-a), -std::expm1(-a), -std::expm1(-static_cast<real>(n) * a), -std::expm1(-2 * a)};
}

// E[(sum_{t=1}^{length} w(t) y_t)^2] / sigma^2 for the stationary AR(1) y, as the sum of squares
// g_1^2 + (1 - phi^2) sum_{t>=2} g_t^2 with g_t = w(t) + phi g_{t+1} (sim_closed_forms.hpp).
template <class Weight>
real ar1_weighted_variance(const Ar1& p, std::uint64_t length, Weight w) {
  real g = 0, sum = 0;
  for (std::uint64_t t = length; t > 1; --t) {
    g = w(t) + p.phi * g;
    sum += g * g;
  }
  g = w(1) + p.phi * g;
  return g * g + p.one_minus_phi2 * sum;
}

}  // namespace

double markov_avar(double sigma2, double tau0_s, double tc_s, std::uint64_t n) {
  const Ar1 p = ar1(tau0_s, tc_s, n);
  const real nn = static_cast<real>(n);
  if (nn * static_cast<real>(tau0_s) >= closed_form_min_x * static_cast<real>(tc_s))
    return static_cast<double>(sigma2 * (nn * (1 + p.phi) / p.e - p.phi * p.u * (2 + p.u) / (p.e * p.e)) / (nn * nn));
  // Weights: -1 on the first n rates, +1 on the next n.
  const real sum = ar1_weighted_variance(p, 2 * n, [n](std::uint64_t t) { return t <= n ? real{-1} : real{1}; });
  return static_cast<double>(sigma2 * sum / (2 * nn * nn));
}

double markov_mvar(double sigma2, double tau0_s, double tc_s, std::uint64_t n) {
  const Ar1 p = ar1(tau0_s, tc_s, n);
  const real nn = static_cast<real>(n), n4 = nn * nn * nn * nn;
  if (nn * static_cast<real>(tau0_s) >= closed_form_min_x * static_cast<real>(tc_s)) {
    const real e = p.e, phi = p.phi, u = p.u;
    const real e2 = e * e;
    const real sum = nn * (nn * nn + 1) * (1 + phi) / e - 6 * nn * phi / e2 - 12 * nn * phi * phi / (e2 * e) +
                     2 * phi * phi * u * (6 + 3 * u + u * u) / (e2 * e2);
    return static_cast<double>(sigma2 * sum / (2 * n4));
  }
  // Weights on the 3n - 1 rates: the triangle c(i) = min(i + 1, 2n - 1 - i) on i = 0 .. 2n - 2,
  // subtracted from rate i + 1 and added to rate i + n + 1.
  const auto triangle = [n](std::uint64_t i) -> real {
    return i + 1 <= n ? static_cast<real>(i + 1) : i <= 2 * n - 2 ? static_cast<real>(2 * n - 1 - i) : real{0};
  };
  const real sum = ar1_weighted_variance(p, 3 * n - 1, [&](std::uint64_t t) {
    return (t > n ? triangle(t - 1 - n) : real{0}) - triangle(t - 1);
  });
  return static_cast<double>(sigma2 * sum / (2 * n4));
}

double sinusoid_avar(double amplitude, double frequency_hz, double tau_s) {
  const double x = units::pi * frequency_hz * tau_s, s = std::sin(x);
  const double ratio = s * s / x;  // sin^2(pi f tau) / (pi f tau)
  return amplitude * amplitude * ratio * ratio;
}

double sinusoid_mvar(double amplitude, double frequency_hz, double tau0_s, std::uint64_t n) {
  const double nn = static_cast<double>(n), x = units::pi * frequency_hz * tau0_s * nn;
  const double s = std::sin(x), s0 = std::sin(units::pi * frequency_hz * tau0_s);
  return amplitude * amplitude * s * s * s * s * s * s / (x * x * nn * nn * s0 * s0);
}

}  // namespace gyrochar
