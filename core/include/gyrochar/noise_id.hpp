#pragma once
// Power-law noise identification primitives (W. J. Riley and C. A. Greenhall, "Power law noise
// identification using the lag 1 autocorrelation", 2004; NIST SP 1065 section 5.6). Streaming:
// only running sums of a decimated series are kept (about 300 bytes per tau); no heap, no clock.
// estimates.hpp combines them over the taus of a curve.
#include <cstdint>

namespace gyrochar {

/// Lag-1 autocorrelation of a series from running sums, values shifted by the first one: the
/// read-out of one difference order of a NoiseIdAccumulator.
struct Lag1Sums {
  std::uint64_t n = 0, pairs = 0;
  double shift = 0, sum = 0, sum_sq = 0;            // of v = z - shift (shift: the first value)
  double sum_lag = 0, sum_left = 0, sum_right = 0;  // over adjacent pairs (v_i, v_i+1)
  /// r1 = sum (z_i - mean)(z_{i+1} - mean) / sum (z_i - mean)^2; 0 with fewer than 3 values.
  double r1() const;
  /// Standard (n-1) variance of the values; 0 with fewer than 2.
  double variance() const;
};

/// Fed with the decimated phase series z_k = x[k m] (relative to any fixed reference): keeps the
/// lag-1 sums of the series and of its first, second and third differences. The four orders
/// advance in lockstep, one lane each of small vectors, so that a value costs a handful of vector
/// operations; every lane performs exactly the operations, in the order, of a scalar running sum.
class NoiseIdAccumulator {
 public:
  /// Adds the next value. O(1), no allocation.
  void add(double z) {
    if (have_ == 3 && linked_[3]) {  // steady state: every order has a previous value
      Lanes v{z, 0, 0, 0};
      v[1] = v[0] - raw_[0];
      v[2] = v[1] - raw_[1];
      v[3] = v[2] - raw_[2];
      raw_ = v;
      const Lanes u = v - shift_;
      sum_lag_ += last_ * u;
      sum_left_ += last_;
      sum_right_ += u;
      sum_ += u;
      sum_sq_ += u * u;
      last_ = u;
      for (int d = 0; d < 4; ++d) {
        ++n_[d];
        ++pairs_[d];
      }
      return;
    }
    add_ramp(z);
  }
  /// A gap: the next value starts a new segment; no difference or pair spans it.
  void reset_segment() {
    have_ = 0;
    for (bool& l : linked_) l = false;
  }
  std::uint64_t points() const { return n_[0]; }
  /// The sums of difference order d (0..3).
  Lag1Sums order(int d) const {
    return {n_[d], pairs_[d], shift_[d], sum_[d], sum_sq_[d], sum_lag_[d], sum_left_[d], sum_right_[d]};
  }

 private:
  // Generic vectors (GCC and Clang): SIMD where the target has it, scalar code elsewhere.
  using Lanes = double __attribute__((vector_size(4 * sizeof(double))));
  void add_ramp(double z);  // the first values of a segment, order by order
  Lanes shift_{}, sum_{}, sum_sq_{}, sum_lag_{}, sum_left_{}, sum_right_{};
  Lanes last_{};  // last shifted value of each order in this segment
  Lanes raw_{};   // last unshifted value of orders 0..2 in this segment (the differences' base)
  std::uint64_t n_[4] = {0, 0, 0, 0};
  std::uint64_t pairs_[4] = {0, 0, 0, 0};
  bool linked_[4] = {false, false, false, false};  // order d's next value pairs with last_[d]
  int have_ = 0;  // values of this segment seen so far (capped at 3)
};

/// The lag-1 rule: difference the series (from order dmin) until delta = r1 / (1 + r1) < 0.25 or
/// d = dmax; then p = 2 (d + delta) estimates 2 - alpha, so alpha = 2 - round(p). sigma is the
/// standard error of p, from the large-sample variance of r1, (1 - rho^2)^2 / n.
struct Lag1Estimate {
  bool valid = false;  // false with fewer than 3 values at the order reached
  double p = 0;
  double sigma = 0;
  std::uint64_t points = 0;  // values of the series the estimate rests on
};
Lag1Estimate lag1_estimate(const NoiseIdAccumulator& acc, int dmin, int dmax);

/// Barnes' expected B1 ratio (standard variance of n frequency averages over the Allan variance)
/// for the exponent mu of AVAR ~ tau^mu. O(1).
double b1_expected(double n, int mu);

/// R(n) = MVAR/AVAR expected for white PM (alpha 2: 1/m) and flicker PM (alpha 1) with the
/// cut-off f_h = 1/(2 tau0). O(1).
double rn_expected(std::uint64_t m, int alpha);

}  // namespace gyrochar
