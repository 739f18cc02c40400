#pragma once
// Power-law noise identification primitives (W. J. Riley and C. A. Greenhall, "Power law noise
// identification using the lag 1 autocorrelation", 2004; NIST SP 1065 section 5.6). Streaming:
// only running sums of a decimated series are kept (about 350 bytes per tau); no heap, no clock.
// Two accumulators read out alike: NoiseIdAccumulator for floating series, and
// IntegerNoiseIdAccumulator, exact, for the decimated phase of counts. estimates.hpp combines them
// over the taus of a curve.
#include <array>
#include <cstddef>
#include <cstdint>

#include "gyrochar/wide.hpp"

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
  /// Adds z[0], z[step], ..., z[(count-1) step], as add() would one by one. O(count), no
  /// allocation.
  void add(const double* z, std::size_t count, std::size_t step) {
    std::size_t k = 0;
    for (; k < count && !(have_ == 3 && linked_[3]); ++k) add_ramp(z[k * step]);
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
  /// Whether the state could have come from at most `max_values` add()s: counts ordered as the
  /// orders nest, every sum finite, the segment's bookkeeping in range (a restored checkpoint,
  /// Characterizer::restore()). Reads the flags as bytes: any byte pattern is safe. O(1).
  bool plausible(std::uint64_t max_values) const;
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
  void add_ramp(double z);                                                   // the first values of a segment, order by order
  void add_run(const std::int64_t* z, std::size_t count, std::size_t step);  // add_steady(), SIMD-compiled
  void add_run(const double* z, std::size_t count, std::size_t step);
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
  Lanes last_{};              // last shifted value of each order in this segment
  Lanes raw_{};               // last unshifted value of orders 0..2 in this segment (the differences' base)
  Counts n_{};
  Counts pairs_{};
  bool linked_[4] = {false, false, false, false};  // order d's next value pairs with last_[d]
  int have_ = 0;                                   // values of this segment seen so far (capped at 3)
};

/// The same sums for an integer series (the decimated phase of counts), exact: every sum is an
/// integer kept modulo 2^128, and order() centres them exactly (on the integer nearest the mean)
/// before the one rounding to double, so its read-out does not depend on how the values arrived.
/// It keeps no lag products: within a segment, sum v_i v_{i+1} = (2 sum v^2 - v_first^2 - v_last^2
/// - sum (v_{i+1} - v_i)^2) / 2 and the sum of a difference telescopes to v_last - v_first, so it
/// keeps the sum of the series, the sums of squares of orders 0..4, and the first and last value
/// of each order per segment. Exact as long as every difference of order 1..4 fits in int64 and
/// each centred sum of squares stays below 2^127 (for counts: |x| < 2^63 and m^3 rate^2 n bounded).
class IntegerNoiseIdAccumulator {
 public:
  /// Adds the next value. O(1), no allocation.
  void add(std::int64_t z) { add_exact(z); }
  /// Adds z[0], z[step], ..., z[(count-1) step], as add() would one by one. `step_bound` bounds
  /// |z[k] - z[k-1]| when known (0: unknown); with it, runs whose differences provably fit in 28 bits
  /// are summed in 64-bit partial sums. O(count), no allocation.
  void add(const std::int64_t* z, std::size_t count, std::size_t step, std::uint64_t step_bound);
  /// A gap: the next value starts a new segment; no difference or pair spans it.
  void reset_segment();
  std::uint64_t points() const { return n_[0]; }
  /// Whether the state could have come from at most `max_values` add()s: n_ of order j + 1 at
  /// most that of order j, the segment's point count in range (a restored checkpoint,
  /// Characterizer::restore()). The sums are integers modulo 2^128: any value is safe. O(1).
  bool plausible(std::uint64_t max_values) const;
  /// The sums of difference order d (0..3), centred on the integer nearest their mean.
  Lag1Sums order(int d) const;

 private:
  void add_exact(std::int64_t z);
  bool add_run(const std::int64_t* z, std::size_t count, std::size_t step, std::uint64_t step_bound);
  std::int64_t last_value(int d) const;  // order d's value at the newest point (have_ > d)
  std::array<std::int64_t, 4> last_{};   // the segment's last points, newest first
  std::array<Int128, 5> sum_sq_{};       // sums of squares of orders 0..4
  Int128 sum_{};                         // sum of the series (order 0)
  std::array<Int128, 4> firsts_{};       // per order: sum of each segment's first value
  std::array<Int128, 4> lasts_{};        // ... of each closed segment's last value
  std::array<Int128, 4> ends_sq_{};      // ... of those values squared
  std::array<std::uint64_t, 5> n_{};     // values of orders 0..4
  std::uint8_t have_ = 0;                // points of this segment (capped at 5)
};

/// What noise identification reads of a decimated series: per difference order d = 0..3 the
/// number of values and their lag-1 autocorrelation, and the variance of the first differences.
struct Lag1Summary {
  std::array<std::uint64_t, 4> n{};
  std::array<double, 4> r1{};
  double variance1 = 0;
};
/// Either accumulator's summary. O(1), no allocation.
template <class Accumulator>
Lag1Summary summarize(const Accumulator& acc) {
  Lag1Summary s;
  for (int d = 0; d < 4; ++d) {
    const Lag1Sums o = acc.order(d);
    s.n[static_cast<std::size_t>(d)] = o.n;
    s.r1[static_cast<std::size_t>(d)] = o.r1();
    if (d == 1) s.variance1 = o.variance();
  }
  return s;
}

/// The lag-1 rule: difference the series (from order dmin) until delta = r1 / (1 + r1) < 0.25 or
/// d = dmax; then p = 2 (d + delta) estimates 2 - alpha, so alpha = 2 - round(p). sigma is the
/// standard error of p, from the large-sample variance of r1, (1 - rho^2)^2 / n.
struct Lag1Estimate {
  bool valid = false;  // false with fewer than 3 values at the order reached
  double p = 0;
  double sigma = 0;
  std::uint64_t points = 0;  // values of the series the estimate rests on
};
Lag1Estimate lag1_estimate(const Lag1Summary& series, int dmin, int dmax);

/// Barnes' expected B1 ratio (standard variance of n frequency averages over the Allan variance)
/// for the exponent mu of AVAR ~ tau^mu. O(1).
double b1_expected(double n, int mu);

/// R(n) = MVAR/AVAR expected for white PM (alpha 2: 1/m) and flicker PM (alpha 1) with the
/// cut-off f_h = 1/(2 tau0). O(1).
double rn_expected(std::uint64_t m, int alpha);

}  // namespace gyrochar
