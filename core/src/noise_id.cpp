#include "gyrochar/noise_id.hpp"

#include <cmath>

namespace gyrochar {

void Lag1Sums::add(double z) {
  if (n == 0) shift = z;
  const double v = z - shift;
  if (linked) {
    sum_lag += last * v;
    sum_left += last;
    sum_right += v;
    ++pairs;
  }
  sum += v;
  sum_sq += v * v;
  last = v;
  linked = true;
  ++n;
}

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

void NoiseIdAccumulator::add(double z) {
  double v[4] = {z, 0, 0, 0};
  for (int d = 1; d <= have_ && d <= 3; ++d) v[d] = v[d - 1] - last_[d - 1];
  for (int d = 0; d <= have_ && d <= 3; ++d) order_[d].add(v[d]);
  for (int d = 0; d <= have_ && d <= 2; ++d) last_[d] = v[d];
  if (have_ < 3) ++have_;
}

void NoiseIdAccumulator::reset_segment() {
  have_ = 0;
  for (Lag1Sums& o : order_) o.unlink();
}

namespace {

double b1_theory(double n, int mu) {  // Barnes: expected B1 for n averages and exponent mu
  switch (mu) {
    case 2: return n * (n + 1) / 6.0;
    case 1: return n / 2.0;
    case 0: return n * std::log(n) / (2.0 * (n - 1) * std::log(2.0));
    case -1: return 1.0;
    case -2: return (n * n - 1.0) / (1.5 * n * (n - 1.0));
    default: return n * (1.0 - std::pow(n, mu)) / (2.0 * (n - 1.0) * (1.0 - std::pow(2.0, mu)));
  }
}

double rn_theory(std::uint64_t m, int alpha) {  // MVAR/AVAR for white PM and flicker PM, f_h = 1/(2 tau0)
  const double n = static_cast<double>(m);
  if (alpha == 2) return 1.0 / n;
  constexpr double pi = 3.14159265358979323846;
  const double avar = (1.038 + 3.0 * std::log(2.0 * pi * 0.5 * n)) / (4.0 * pi * pi);
  const double mvar = 3.0 * std::log(256.0 / 27.0) / (8.0 * pi * pi);
  return mvar / avar;
}

}  // namespace

NoiseId identify_noise(const NoiseIdAccumulator& acc, const NoiseIdInput& in) {
  NoiseId out;
  if (acc.points() >= 30) {
    const int dmin = in.frequency_data ? 1 : 0;
    for (int d = dmin; d <= in.dmax; ++d) {
      const double r1 = acc.order(d).r1();
      const double delta = r1 / (1.0 + r1);
      if (delta < 0.25 || d == in.dmax) {
        out.alpha = 2 - static_cast<int>(std::lround(2.0 * delta)) - 2 * d;
        out.method = NoiseIdMethod::lag1;
        break;
      }
    }
  } else {
    // B1: variance of the m-averaged frequency (first differences of the decimated phase).
    // Against the overlapping AVAR, as Stable32 does (with the non-overlapped one its choices on
    // the Keysight 53230A set are not reproduced at m = 8192).
    const Lag1Sums& y = acc.order(1);
    // With fewer than 3 averages every B1(N, mu) is 1: B1 cannot choose, so say so.
    if (y.n < 3 || !(in.avar > 0)) return out;
    const double scale = static_cast<double>(in.m) * in.tau0_s;
    const double b1 = y.variance() / (scale * scale) / in.avar;
    const double n = static_cast<double>(y.n);
    // Candidates from white PM down: (alpha, mu); pick the one whose B1 the measured value is
    // nearest to on a log scale (boundaries at the geometric means).
    static constexpr int alphas[] = {2, 0, -1, -2};
    static constexpr int mus[] = {-2, -1, 0, 1};
    int pick = 3;
    for (int k = 0; k < 3; ++k) {
      const double boundary = std::sqrt(b1_theory(n, mus[k]) * b1_theory(n, mus[k + 1]));
      if (b1 < boundary) {
        pick = k;
        break;
      }
    }
    out.alpha = alphas[pick];
    out.method = NoiseIdMethod::b1;
    if (out.alpha == 2 && in.avar > 0 && in.mvar > 0) {
      const double rn = in.mvar / in.avar;
      const double boundary = std::sqrt(rn_theory(in.m, 2) * rn_theory(in.m, 1));
      out.alpha = rn < boundary ? 2 : 1;
      out.method = NoiseIdMethod::b1_rn;
    }
  }
  const int lowest = in.dmax == 3 ? -4 : -2;
  if (out.alpha < lowest) out.alpha = lowest;
  if (out.alpha > 2) out.alpha = 2;
  return out;
}

}  // namespace gyrochar
