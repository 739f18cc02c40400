#pragma once
// Power-law noise identification primitives (W. J. Riley and C. A. Greenhall, "Power law noise
// identification using the lag 1 autocorrelation", 2004; NIST SP 1065 section 5.6). Streaming:
// only running sums of a decimated series are kept (about 300 bytes per tau); no heap, no clock.
// estimates.hpp combines them over the taus of a curve.
#include <cstddef>
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
    if (have_ == 3 && linked_[3]) {
      add_steady(&z, 1, 1);
    } else {
      add_ramp(z);
    }
  }
  /// Adds z[0], z[step], ..., z[(count-1) step] (integer phase points), as add() would one by one.
  /// O(count), no allocation.
  void add(const std::int64_t* z, std::size_t count, std::size_t step) {
    std::size_t k = 0;
    for (; k < count && !(have_ == 3 && linked_[3]); ++k) add_ramp(static_cast<double>(z[k * step]));
    if (k < count) add_run(z + k * step, count - k, step);
  }
  /// A gap: the next value starts a new segment; no difference or pair spans it.
  void reset_segment() {
    have_ = 0;
    for (int d = 0; d < 4; ++d) {
      if (linked_[d]) lasts_[d] += last_[d];
      linked_[d] = false;
    }
  }
  std::uint64_t points() const { return n_[0]; }
  /// The sums of difference order d (0..3).
  Lag1Sums order(int d) const {
    // Every value but the last of each segment is a left one; every value but the first, a right one.
    const double left = sum_[d] - lasts_[d] - (linked_[d] ? last_[d] : 0.0);
    return {n_[d], pairs_[d], shift_[d], sum_[d], sum_sq_[d], sum_lag_[d], left, sum_[d] - firsts_[d]};
  }

 private:
  // Generic vectors (GCC and Clang): SIMD where the target has it, scalar code elsewhere. The
  // alignment is explicit: the AVX2 clone of add_run() must agree with the baseline on it.
  using Lanes = double __attribute__((vector_size(4 * sizeof(double)), aligned(4 * sizeof(double))));
  void add_ramp(double z);  // the first values of a segment, order by order
  void add_run(const std::int64_t* z, std::size_t count, std::size_t step);  // add_steady(), SIMD-compiled
  // Every order has a previous value in this segment: the four advance together.
  template <class T>
  void add_steady(const T* z, std::size_t count, std::size_t step) {
    Lanes last = last_, sum = sum_, sum_sq = sum_sq_, sum_lag = sum_lag_;
    const Lanes shift = shift_;
    double r0 = raw_[0], r1 = raw_[1], r2 = raw_[2];
    for (std::size_t k = 0; k < count; ++k) {
      const double d0 = static_cast<double>(z[k * step]);
      const double d1 = d0 - r0;
      const double d2 = d1 - r1;
      const double d3 = d2 - r2;
      r0 = d0, r1 = d1, r2 = d2;
      const Lanes u = Lanes{d0, d1, d2, d3} - shift;
      sum_lag += last * u;
      sum += u;
      sum_sq += u * u;
      last = u;
    }
    raw_ = Lanes{r0, r1, r2, 0};
    last_ = last, sum_ = sum, sum_sq_ = sum_sq, sum_lag_ = sum_lag;
    n_ += count;
    pairs_ += count;
  }
  using Counts = std::uint64_t __attribute__((vector_size(4 * sizeof(std::uint64_t)), aligned(4 * sizeof(std::uint64_t))));
  Lanes shift_{}, sum_{}, sum_sq_{}, sum_lag_{};
  Lanes firsts_{}, lasts_{};  // sums of the first and of the last value of each (closed) segment
  Lanes last_{};  // last shifted value of each order in this segment
  Lanes raw_{};   // last unshifted value of orders 0..2 in this segment (the differences' base)
  Counts n_{};
  Counts pairs_{};
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
