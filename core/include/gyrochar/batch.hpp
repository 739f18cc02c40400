#pragma once
// The batch path of the exact counts statistics: the sums of one tau over phase points the caller
// holds, O(N) per tau, for the offline analyzer when it keeps the record anyway (fully overlapped
// taus up to N/4 need the record's last 3N/4 points: the pyramid's history would hold them too).
//
// It produces what Characterizer<CountArith> keeps for a tau, to the last bit: the same
// TauResult (overlapping and non-overlapped sums, term counts, out-of-range terms, the sticky
// overflow flag) and the same exact noise sums (IntegerNoiseIdAccumulator), so the same
// extractors (estimates.hpp) read it. Terms are formed where the characterizer forms them: newest point e a multiple of the
// tau's stride (stride_of()), within one segment (a gap starts a new one), decimated points at
// the multiples of m.
//
// The record. Each segment is a span of residuals r from an integer line, x_j = x0 + slope j + r_j
// (modulo 2^64; the true x_j fits in int64), so that int32 residuals can hold a long record of
// counts (a gyro's phase strays little from its mean rate) in 4 bytes a point; int64 otherwise.
// Every term is a difference of order 2 or more, in which the line cancels.
//
// The kernel, per tau m and segment, for N points:
//   - AVAR a_e = x[e] - 2x[e-m] + x[e-2m] and HVAR h_e = a_e - a_{e-m} straight from r (SIMD);
//   - MVAR t_e = P[e+1] - 3P[e+1-m] + 3P[e+1-2m] - P[e+1-3m] as a running sum: t_e - t_{e-1} = h_e
//     (the MVAR term sums m consecutive AVAR terms), its first value from three prefix sums of r;
//   - all in modular 64-bit arithmetic: exact when every term fits in int64, proved from the
//     segment's spread D (largest minus smallest increment): |a| <= m D, |h| <= 2 m D,
//     |t| <= m^2 D (characterizer.hpp's terms_fit()); a tau that fails the bound takes the
//     checked path, point by point, exactly as the characterizer does (out-of-range terms counted);
//   - squares summed over chunks of 256 terms in 64-bit partial sums of the low 32-bit halves,
//     exact when the OR of the chunk's magnitudes is below 2^b with 2b + bit_width(n) <= 64
//     (block_kernel.hpp's squares_exact()), else summed again term by term in 128 bits;
//   - on x86-64 with AVX2 (checked at run time), int32 residuals and every term taken: the three
//     terms of a chunk in AVX2 by hand (one vpmuldq squares four terms), the MVAR running sum
//     four terms a step (t_e = t_{e-4} + h_e + h_{e-1} + h_{e-2} + h_{e-3}).
// The non-overlapped sums and the noise sums take the decimated points, O(N/m).
//
// No allocation, no exceptions; the caller owns the record.
#include <cstddef>
#include <cstdint>
#include <span>

#include "gyrochar/characterizer.hpp"
#include "gyrochar/noise_id.hpp"
#include "gyrochar/wide.hpp"

namespace gyrochar {

/// One segment of held phase points: x_j = x0 + slope * j + r[j] (modulo 2^64) for j = 0 ..
/// r.size() - 1, point j having the global index first_e + j. `spread` bounds the terms: the
/// largest minus the smallest increment x_{j+1} - x_j of the segment (0 with fewer than two
/// points); a spread that is too small breaks exactness, one too large only costs speed.
template <class R>
struct PhaseSegment {
  std::span<const R> r;
  std::int64_t x0 = 0;
  std::int64_t slope = 0;
  std::uint64_t first_e = 0;
  std::uint64_t spread = 0;
};

/// The term stride of averaging factor m with stride factor S, as the characterizer's pyramid
/// forms it: 1 for m <= S, else the smallest power of two 2^L with S 2^L >= m. O(log m).
constexpr std::uint64_t stride_of(std::uint64_t m, std::uint32_t stride_factor) {
  std::uint64_t stride = 1;
  while (std::uint64_t{stride_factor} * stride < m) stride *= 2;
  return stride;
}

/// The largest minus the smallest increment r[j+1] - r[j] (the slope cancels), for
/// PhaseSegment::spread. O(n), no allocation.
template <class R>
std::uint64_t increment_spread(std::span<const R> r) {
  if (r.size() < 2) return 0;
  std::int64_t lo = std::int64_t{r[1]} - r[0], hi = lo;
  for (std::size_t j = 2; j < r.size(); ++j) {
    const std::int64_t d = std::int64_t{r[j]} - r[j - 1];
    lo = d < lo ? d : lo;
    hi = d > hi ? d : hi;
  }
  return static_cast<std::uint64_t>(hi) - static_cast<std::uint64_t>(lo);
}

/// The sums of one tau (m, stride) over held segments: what Characterizer<CountArith> keeps for
/// that tau after the same points and gaps. About 400 bytes; no allocation.
class BatchTau {
 public:
  /// m >= 1, stride a power of two that divides m when it is above 1 (see stride_of()).
  BatchTau(std::uint64_t m, std::uint64_t stride);

  /// Adds the terms and decimated points of the next segment (a gap separates it from the one
  /// before). O(n) for n points: a few operations a point. Never fails.
  void add_segment(const PhaseSegment<std::int32_t>& segment);
  void add_segment(const PhaseSegment<std::int64_t>& segment);

  /// The sums, as Characterizer::result() gives them (sum_overflow included). O(1).
  TauResult<UInt128> result() const {
    TauResult<UInt128> r = result_;
    r.sum_overflow = (sticky_ >> 63) != 0;
    return r;
  }
  /// The lag-1 autocorrelation sums of the decimated series, as Characterizer::noise().
  const IntegerNoiseIdAccumulator& noise() const { return noise_; }

 private:
  template <class R>
  void add(const PhaseSegment<R>& segment);
  template <class R>
  void decimate(const PhaseSegment<R>& segment, bool fits, bool terms);
  template <class R>
  void checked_terms(const PhaseSegment<R>& segment);

  TauResult<UInt128> result_;
  std::uint64_t sticky_ = 0;  // OR of the sums' high words: bit 63 = a sum reached 2^127
  std::uint64_t segments_ = 0;
  IntegerNoiseIdAccumulator noise_;
};

}  // namespace gyrochar
