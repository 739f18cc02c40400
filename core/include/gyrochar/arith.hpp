#pragma once
// The characterizer's arithmetic policies: how a phase point, its prefix sum P and the sums of
// squared terms are held, and how the second and third differences are formed.
//
// Arithmetic policies:
//   CountArith  integer counts, exact. x is int64, P is a 128-bit two's complement integer, the sums
//               of squares are unsigned 128-bit. Every term and every sum equals the exact integer
//               computation whatever the run length, as long as (1) |x| < 2^63 (total pulses),
//               (2) each term fits in 63 bits plus sign, (3) each sum of squares stays below 2^127.
//               Each condition is checked: (1) flags the stream, (2) skips the term and counts it in
//               TauResult::out_of_range, (3) sets TauResult::sum_overflow.
//   FloatArith  floating phase (files). Phase points are kept relative to the line through the
//               first two points, frequency increments relative to the first one (differences of
//               order two and more do not change), P is a double-double so the third differences of
//               P do not cancel catastrophically; sums are double.
#include <cstdint>

#include "gyrochar/noise_id.hpp"
#include "gyrochar/wide.hpp"

namespace gyrochar {

struct CountArith {
  struct Entry {
    std::int64_t x = 0;  // phase x_e in pulses
    Int128 p;            // P_{e+1} = sum_{i<=e} x_i
  };
  using X = std::int64_t;
  using Sum = UInt128;
  using Increment = std::int32_t;               // pulses per tau0: the exactness bounds rely on |c| < 2^31
  using NoiseSums = IntegerNoiseIdAccumulator;  // the decimated phase is integer: exact sums
  static constexpr bool exact = true;

  static constexpr Int128 add_prefix(Int128 p, std::int64_t x) { return p + widen(x); }

  /// Second and third differences of x; false when a value does not fit in int64.
  static constexpr bool x_terms(std::int64_t x0, std::int64_t x1, std::int64_t x2, std::int64_t x3, std::int64_t& a,
                                std::int64_t& h) {
    std::int64_t d1 = 0, d2 = 0, d3 = 0, e2 = 0;
    unsigned bad = __builtin_sub_overflow(x0, x1, &d1);
    bad |= __builtin_sub_overflow(x1, x2, &d2);
    bad |= __builtin_sub_overflow(x2, x3, &d3);
    bad |= __builtin_sub_overflow(d1, d2, &a);
    bad |= __builtin_sub_overflow(d2, d3, &e2);
    bad |= __builtin_sub_overflow(a, e2, &h);
    return bad == 0;
  }
  static constexpr bool x_term2(std::int64_t x0, std::int64_t x1, std::int64_t x2, std::int64_t& a) {
    std::int64_t d1 = 0, d2 = 0;
    unsigned bad = __builtin_sub_overflow(x0, x1, &d1);
    bad |= __builtin_sub_overflow(x1, x2, &d2);
    bad |= __builtin_sub_overflow(d1, d2, &a);
    return bad == 0;
  }
  /// Third difference of P; false when it does not fit in int64.
  static constexpr bool p_term(Int128 p0, Int128 p1, Int128 p2, Int128 p3, std::int64_t& t) {
    const Int128 d = (p0 - p3) + ((p2 - p1) + (p2 - p1) + (p2 - p1));
    return narrow(d, t);
  }
  /// sum += v^2; returns a word whose top bit is set when the sum reached 2^127 (see add_high_word).
  static constexpr std::uint64_t accumulate(Sum& sum, std::int64_t v) { return add_high_word(sum, square(v)); }
  static constexpr double to_double(const Sum& s) { return gyrochar::to_double(s); }
};

struct FloatArith {
  /// Double-double: value = hi + lo with |lo| <= ulp(hi)/2.
  struct Prefix {
    double hi = 0.0;
    double lo = 0.0;
  };
  struct Entry {
    double x = 0.0;  // phase relative to the reference line
    Prefix p;        // P_{e+1} relative to the reference line's prefix sums
  };
  using X = double;
  using Sum = double;
  using Increment = double;
  using NoiseSums = NoiseIdAccumulator;
  static constexpr bool exact = false;

  static constexpr Prefix add_prefix(Prefix a, double b) {  // Knuth two-sum, then renormalize
    const double s = a.hi + b;
    const double bb = s - a.hi;
    const double err = (a.hi - (s - bb)) + (b - bb);
    const double lo = a.lo + err;
    const double hi = s + lo;
    return {hi, lo - (hi - s)};
  }
  static constexpr double diff(Prefix a, Prefix b) { return (a.hi - b.hi) + (a.lo - b.lo); }

  static constexpr bool x_terms(double x0, double x1, double x2, double x3, double& a, double& h) {
    a = (x0 - x1) - (x1 - x2);
    h = a - ((x1 - x2) - (x2 - x3));
    return true;
  }
  static constexpr bool x_term2(double x0, double x1, double x2, double& a) {
    a = (x0 - x1) - (x1 - x2);
    return true;
  }
  static constexpr bool p_term(Prefix p0, Prefix p1, Prefix p2, Prefix p3, double& t) {
    t = diff(p0, p3) + 3.0 * diff(p2, p1);
    return true;
  }
  static constexpr std::uint64_t accumulate(Sum& sum, double v) {
    sum += v * v;
    return 0;
  }
  static constexpr double to_double(Sum s) { return s; }
};

}  // namespace gyrochar
