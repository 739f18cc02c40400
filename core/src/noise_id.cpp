#include "gyrochar/noise_id.hpp"

#include <cmath>

namespace gyrochar {

double Lag1Sums::r1() const {
  if (n < 3 || pairs == 0) return 0.0;
  const double nn = static_cast<double>(n);
  const double mean = sum / nn;
  const double denominator = sum_sq - nn * mean * mean;
  if (!(denominator > 0)) return 0.0;
  const double numerator = sum_lag - mean * (sum_left + sum_right) + static_cast<double>(pairs) * mean * mean;
  return numerator / denominator;
}

double Lag1Sums::variance() const {
  if (n < 2) return 0.0;
  const double nn = static_cast<double>(n);
  const double mean = sum / nn;
  const double ss = sum_sq - nn * mean * mean;
  return ss > 0 ? ss / (nn - 1) : 0.0;
}

void NoiseIdAccumulator::add_ramp(double z) {
  double v[4] = {z, 0, 0, 0};
  for (int d = 1; d <= have_ && d <= 3; ++d) v[d] = v[d - 1] - raw_[d - 1];
  for (int d = 0; d <= have_ && d <= 3; ++d) {
    if (n_[d] == 0) shift_[d] = v[d];
    const double u = v[d] - shift_[d];
    if (linked_[d]) {
      sum_lag_[d] += last_[d] * u;
      ++pairs_[d];
    } else {
      firsts_[d] += u;
    }
    sum_[d] += u;
    sum_sq_[d] += u * u;
    last_[d] = u;
    linked_[d] = true;
    ++n_[d];
  }
  for (int d = 0; d <= have_ && d <= 2; ++d) raw_[d] = v[d];
  if (have_ < 3) ++have_;
}

// Compiled for AVX2 beside the baseline on the x86-64 host (one lane per difference order: the
// same operations in the same order, so the same bits), once elsewhere.
#if defined(__x86_64__) && defined(__linux__) && !defined(__clang__)
__attribute__((target_clones("avx2", "default")))
#endif
void NoiseIdAccumulator::add_run(const std::int64_t* z, std::size_t count, std::size_t step) {
  add_steady(z, count, step);
}

Lag1Estimate lag1_estimate(const NoiseIdAccumulator& acc, int dmin, int dmax) {
  Lag1Estimate out;
  for (int d = dmin; d <= dmax; ++d) {
    const Lag1Sums s = acc.order(d);
    if (s.n < 3) return out;
    const double r1 = s.r1();
    const double delta = r1 / (1.0 + r1);
    if (delta < 0.25 || d == dmax) {
      const double n = static_cast<double>(s.n);
      const double sigma_r1 = (1.0 - r1 * r1) / std::sqrt(n);
      out.valid = true;
      out.p = 2.0 * (d + delta);
      out.sigma = 2.0 * sigma_r1 / ((1.0 + r1) * (1.0 + r1));
      out.points = s.n;
      return out;
    }
  }
  return out;
}

double b1_expected(double n, int mu) {
  switch (mu) {
    case 2: return n * (n + 1) / 6.0;
    case 1: return n / 2.0;
    case 0: return n * std::log(n) / (2.0 * (n - 1) * std::log(2.0));
    case -1: return 1.0;
    case -2: return (n * n - 1.0) / (1.5 * n * (n - 1.0));
    default: return n * (1.0 - std::pow(n, mu)) / (2.0 * (n - 1.0) * (1.0 - std::pow(2.0, mu)));
  }
}

double rn_expected(std::uint64_t m, int alpha) {
  const double n = static_cast<double>(m);
  if (alpha == 2) return 1.0 / n;
  constexpr double pi = 3.14159265358979323846;
  const double avar = (1.038 + 3.0 * std::log(2.0 * pi * 0.5 * n)) / (4.0 * pi * pi);
  const double mvar = 3.0 * std::log(256.0 / 27.0) / (8.0 * pi * pi);
  return mvar / avar;
}

}  // namespace gyrochar
