#include "gyrochar/noise_id.hpp"

#include <cmath>
#include <cstring>
#include <initializer_list>

#if defined(__aarch64__) && defined(__ARM_NEON)
#include <arm_neon.h>
#define GYROCHAR_NOISE_NEON 1
#endif

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

#if defined(__x86_64__) && defined(__linux__) && !defined(__clang__)
__attribute__((target_clones("avx2", "default")))
#endif
void NoiseIdAccumulator::add_run(const double* z, std::size_t count, std::size_t step) {
  add_steady(z, count, step);
}

Lag1Estimate lag1_estimate(const Lag1Summary& series, int dmin, int dmax) {
  Lag1Estimate out;
  for (int d = dmin; d <= dmax; ++d) {
    const auto k = static_cast<std::size_t>(d);
    if (series.n[k] < 3) return out;
    const double r1 = series.r1[k];
    const double delta = r1 / (1.0 + r1);
    if (delta < 0.25 || d == dmax) {
      const double n = static_cast<double>(series.n[k]);
      const double sigma_r1 = (1.0 - r1 * r1) / std::sqrt(n);
      out.valid = true;
      out.p = 2.0 * (d + delta);
      out.sigma = 2.0 * sigma_r1 / ((1.0 + r1) * (1.0 + r1));
      out.points = series.n[k];
      return out;
    }
  }
  return out;
}

// ---------------------------------------------------------------------------------------------
// IntegerNoiseIdAccumulator. All arithmetic is modular (64-bit values, 128-bit sums), which is
// exact whenever the true value fits.

namespace {
Int128 square_of(std::int64_t v) {
  const UInt128 s = square(v);
  return {s.lo, s.hi};
}
}  // namespace

// Order d's value at the newest point: the d-th difference of the last d + 1 points.
std::int64_t IntegerNoiseIdAccumulator::last_value(int d) const {
  const auto l0 = static_cast<std::uint64_t>(last_[0]), l1 = static_cast<std::uint64_t>(last_[1]);
  const auto l2 = static_cast<std::uint64_t>(last_[2]), l3 = static_cast<std::uint64_t>(last_[3]);
  switch (d) {
    case 0: return last_[0];
    case 1: return static_cast<std::int64_t>(l0 - l1);
    case 2: return static_cast<std::int64_t>(l0 - 2 * l1 + l2);
    default: return static_cast<std::int64_t>(l0 - 3 * l1 + 3 * l2 - l3);
  }
}

void IntegerNoiseIdAccumulator::add_exact(std::int64_t z) {
  const auto v = static_cast<std::uint64_t>(z), l0 = static_cast<std::uint64_t>(last_[0]);
  const auto l1 = static_cast<std::uint64_t>(last_[1]), l2 = static_cast<std::uint64_t>(last_[2]);
  const auto l3 = static_cast<std::uint64_t>(last_[3]);
  const std::int64_t d[5] = {z, static_cast<std::int64_t>(v - l0), static_cast<std::int64_t>(v - 2 * l0 + l1),
                             static_cast<std::int64_t>(v - 3 * l0 + 3 * l1 - l2),
                             static_cast<std::int64_t>(v - 4 * l0 + 6 * l1 - 4 * l2 + l3)};
  sum_ = sum_ + widen(z);
  const unsigned orders = have_ < 4 ? have_ : 4;  // order j needs j earlier points
  for (unsigned j = 0; j <= orders; ++j) {
    const Int128 sq = square_of(d[j]);
    sum_sq_[j] = sum_sq_[j] + sq;
    ++n_[j];
    if (j < 4 && j == have_) {  // the segment's first value of order j
      firsts_[j] = firsts_[j] + widen(d[j]);
      ends_sq_[j] = ends_sq_[j] + sq;
    }
  }
  last_ = {z, last_[0], last_[1], last_[2]};
  if (have_ < 5) ++have_;
}

void IntegerNoiseIdAccumulator::add(const std::int64_t* z, std::size_t count, std::size_t step, std::uint64_t step_bound) {
  std::size_t k = 0;
  for (; k < count && have_ < 5; ++k) add_exact(z[k * step]);
  constexpr std::size_t run = 64;
  while (k < count) {
    const std::size_t n = count - k < run ? count - k : run;
    if (!add_run(z + k * step, n, step, step_bound)) {
      for (std::size_t i = 0; i < n; ++i) add_exact(z[(k + i) * step]);
    }
    k += n;
  }
}

namespace {

// A run's sums over w[i], i = from .. end - 1 (w[i-4 .. i-1] valid): s0 = sum of v0 = w - base, q[k] =
// sum of vk^2 for the differences of order k, each value formed in 32-bit modular arithmetic.
struct RunSums {
  std::int64_t s0 = 0;
  std::int64_t q[5] = {};
};
[[gnu::always_inline]] inline void run_sums(const std::uint32_t* w, std::size_t from, std::size_t end, std::uint32_t base,
                                            RunSums& r) {
  for (std::size_t i = from; i < end; ++i) {
    const auto v0 = static_cast<std::int32_t>(w[i] - base);
    const auto v1 = static_cast<std::int32_t>(w[i] - w[i - 1]);
    const auto v2 = static_cast<std::int32_t>(w[i] - 2 * w[i - 1] + w[i - 2]);
    const auto v3 = static_cast<std::int32_t>(w[i] - 3 * w[i - 1] + 3 * w[i - 2] - w[i - 3]);
    const auto v4 = static_cast<std::int32_t>(w[i] - 4 * w[i - 1] + 6 * w[i - 2] - 4 * w[i - 3] + w[i - 4]);
    r.s0 += v0;
    r.q[0] += std::int64_t{v0} * v0;
    r.q[1] += std::int64_t{v1} * v1;
    r.q[2] += std::int64_t{v2} * v2;
    r.q[3] += std::int64_t{v3} * v3;
    r.q[4] += std::int64_t{v4} * v4;
  }
}

#if defined(GYROCHAR_NOISE_NEON)
// Four values a step: the differences of each order from those of the order below at the four
// values and the four before (no multiplies), every square by smlal/smlal2.
RunSums run_sums_neon(const std::uint32_t* w, std::size_t n, std::uint32_t base) {
  const std::size_t end = 4 + n / 4 * 4;
  const uint32x4_t b = vdupq_n_u32(base);
  int64x2_t s0 = vdupq_n_s64(0), q0 = s0, q1 = s0, q2 = s0, q3 = s0, q4 = s0;
  const auto square = [](int64x2_t& q, uint32x4_t v) {
    const int32x4_t s = vreinterpretq_s32_u32(v);
    q = vmlal_high_s32(vmlal_s32(q, vget_low_s32(s), vget_low_s32(s)), s, s);
  };
  for (std::size_t i = 4; i < end; i += 4) {
    const uint32x4_t w0 = vld1q_u32(w + i), w1 = vld1q_u32(w + i - 1), w2 = vld1q_u32(w + i - 2);
    const uint32x4_t w3 = vld1q_u32(w + i - 3), w4 = vld1q_u32(w + i - 4);
    const uint32x4_t v0 = vsubq_u32(w0, b);
    const uint32x4_t d0 = vsubq_u32(w0, w1), d1 = vsubq_u32(w1, w2), d2 = vsubq_u32(w2, w3), d3 = vsubq_u32(w3, w4);
    const uint32x4_t e0 = vsubq_u32(d0, d1), e1 = vsubq_u32(d1, d2), e2 = vsubq_u32(d2, d3);
    const uint32x4_t f0 = vsubq_u32(e0, e1), f1 = vsubq_u32(e1, e2);
    s0 = vpadalq_s32(s0, vreinterpretq_s32_u32(v0));
    square(q0, v0);
    square(q1, d0);
    square(q2, e0);
    square(q3, f0);
    square(q4, vsubq_u32(f0, f1));
  }
  RunSums r{vaddvq_s64(s0), {vaddvq_s64(q0), vaddvq_s64(q1), vaddvq_s64(q2), vaddvq_s64(q3), vaddvq_s64(q4)}};
  run_sums(w, end, 4 + n, base, r);
  return r;
}
#endif

}  // namespace

// Up to 64 values of a segment with at least 5 points. With |z[k] - z[k-1]| <= B, every difference
// of order j <= 4 is at most 8B and z[k] - base (base: the point before the run) at most 64B, so
// when 64B < 2^28 they are computed exactly in 32-bit modular arithmetic from the points' low
// words, and the squares of n <= 64 of them (each below 2^56) add up exactly in 64 bits. Order 0
// comes from sum (base + w)^2 = n base^2 + 2 base sum w + sum w^2. Returns false (nothing changed)
// when the bound does not hold. Compiled for AVX2 beside the baseline on the x86-64 host (integer
// sums: the same bits either way); GCC vectorizes the loop with NEON on aarch64.
#if defined(__x86_64__) && defined(__linux__) && !defined(__clang__)
__attribute__((target_clones("avx2", "default")))
#endif
bool IntegerNoiseIdAccumulator::add_run(const std::int64_t* z, std::size_t n, std::size_t step, std::uint64_t step_bound) {
  if (step_bound == 0 || step_bound >= (std::uint64_t{1} << 22)) return false;
  std::uint32_t w[4 + 64];
  for (std::size_t i = 0; i < 4; ++i) w[i] = static_cast<std::uint32_t>(last_[3 - i]);
  for (std::size_t i = 0; i < n; ++i) w[4 + i] = static_cast<std::uint32_t>(z[i * step]);
  const std::uint32_t base = w[3];
#if defined(GYROCHAR_NOISE_NEON)
  const RunSums r = run_sums_neon(w, n, base);
#else
  RunSums r;
  run_sums(w, 4, n + 4, base, r);
#endif
  const std::int64_t s0 = r.s0, q0 = r.q[0], q1 = r.q[1], q2 = r.q[2], q3 = r.q[3], q4 = r.q[4];
  const std::int64_t b = last_[0];
  const auto count = static_cast<std::uint64_t>(n);
  sum_ = sum_ + mul_signed(b, static_cast<std::int64_t>(count)) + widen(s0);
  const Int128 cross = mul_signed(b, s0);
  sum_sq_[0] = sum_sq_[0] + mul_mod(square_of(b), static_cast<std::int64_t>(count)) + cross + cross + widen(q0);
  sum_sq_[1] = sum_sq_[1] + widen(q1);
  sum_sq_[2] = sum_sq_[2] + widen(q2);
  sum_sq_[3] = sum_sq_[3] + widen(q3);
  sum_sq_[4] = sum_sq_[4] + widen(q4);
  for (auto& v : n_) v += count;
  if (n >= 4) {
    for (std::size_t i = 0; i < 4; ++i) last_[i] = z[(n - 1 - i) * step];
  } else {
    for (std::size_t i = 4; i-- > 0;) last_[i] = i >= n ? last_[i - n] : z[(n - 1 - i) * step];
  }
  return true;
}

void IntegerNoiseIdAccumulator::reset_segment() {
  for (int d = 0; d < 4 && d < have_; ++d) {
    const std::int64_t v = last_value(d);
    lasts_[static_cast<std::size_t>(d)] = lasts_[static_cast<std::size_t>(d)] + widen(v);
    ends_sq_[static_cast<std::size_t>(d)] = ends_sq_[static_cast<std::size_t>(d)] + square_of(v);
  }
  have_ = 0;
}

// Centred on q (the integer nearest the mean), for the k segments holding values of order d:
//   sum (v - q)^2 = S2 - 2 q S1 + n q^2, and likewise the first and last values;
//   sum over pairs of (v_i - q)(v_{i+1} - q) = (2 sum (v - q)^2 - sum of the end values' squares
//   - S2 of order d + 1) / 2; left (right) values: all but each segment's last (first).
bool IntegerNoiseIdAccumulator::plausible(std::uint64_t max_values) const {
  if (have_ > 5 || n_[0] > max_values || have_ > n_[0]) return false;
  for (std::size_t j = 0; j + 1 < n_.size(); ++j) {
    if (n_[j + 1] > n_[j]) return false;
  }
  return true;
}

Lag1Sums IntegerNoiseIdAccumulator::order(int d) const {
  const auto k = static_cast<std::size_t>(d);
  Lag1Sums out;
  out.n = n_[k];
  out.pairs = n_[k + 1];
  if (out.n == 0) return out;
  const bool open = have_ > d;  // this segment has a value of order d
  const Int128 open_last = open ? widen(last_value(d)) : Int128{};
  const Int128 firsts = firsts_[k], lasts = lasts_[k] + open_last;
  const Int128 ends_sq = ends_sq_[k] + (open ? square_of(last_value(d)) : Int128{});
  Int128 s1 = sum_;
  if (d > 0) s1 = lasts_[k - 1] + (have_ >= d ? widen(last_value(d - 1)) : Int128{}) - firsts_[k - 1];
  const std::uint64_t segments = n_[k] - n_[k + 1];
  const auto q = static_cast<std::int64_t>(std::llround(to_double(s1) / static_cast<double>(out.n)));
  const Int128 sum = s1 - mul_signed(q, static_cast<std::int64_t>(out.n));
  // sum (v - q)^2 = S2 - 2 q S1 + n q^2 = S2 - q (S1 + sum), as sum = S1 - n q.
  const Int128 q_times = mul_mod(s1 + sum, q);
  const Int128 sum_sq = sum_sq_[k] - q_times;
  // The end values: F + E - 2 k q of them centred, and their squares Q - q (F + E + centred).
  const Int128 ends = firsts + lasts - mul_signed(q, 2 * static_cast<std::int64_t>(segments));
  const Int128 ends_centred_sq = ends_sq - mul_mod(firsts + lasts + ends, q);
  const Int128 twice_lag = sum_sq + sum_sq - ends_centred_sq - sum_sq_[k + 1];
  out.shift = static_cast<double>(q);
  out.sum = to_double(sum);
  out.sum_sq = to_double(UInt128{sum_sq.lo, sum_sq.hi});
  out.sum_lag = 0.5 * to_double(twice_lag);
  out.sum_left = to_double(sum - (lasts - mul_signed(q, static_cast<std::int64_t>(segments))));
  out.sum_right = to_double(sum - (firsts - mul_signed(q, static_cast<std::int64_t>(segments))));
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

bool NoiseIdAccumulator::plausible(std::uint64_t max_values) const {
  std::uint8_t linked[4];
  std::memcpy(linked, linked_, sizeof linked);  // as bytes: a restored flag may be any byte
  if (have_ < 0 || have_ > 3 || n_[0] > max_values) return false;
  for (int d = 0; d < 4; ++d) {
    if (linked[d] > 1 || pairs_[d] > n_[d] || (d > 0 && n_[d] > n_[d - 1])) return false;
    for (const Lanes* lane : {&shift_, &sum_, &sum_sq_, &sum_lag_, &firsts_, &lasts_, &last_, &raw_}) {
      if (!std::isfinite((*lane)[d])) return false;
    }
  }
  return true;
}

}  // namespace gyrochar
