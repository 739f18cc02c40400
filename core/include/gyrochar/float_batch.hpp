#pragma once
// The batch path of floating phase: the sums of one tau over phase points the caller holds, O(N)
// per tau, for the offline analyzer's dense tau lists (--taus all on phase or frequency data),
// as batch.hpp is for counts. Characterizer<FloatArith> visits every tau at every point, reading
// its history at three ages per tau; here each tau runs through the record alone, in order, four
// terms a step.
//
// The record is what Characterizer<FloatArith> stages: x_e relative to its reference (the line
// through the first two phase points, line_residual() below, or the first frequency
// increment) and the prefix sums P_{e+1} = x_0 + ... + x_e as the double-double of
// FloatArith::add_prefix(), in two arrays (hi, lo). So every term is the characterizer's to the
// last bit:
//   - AVAR a_e = (x_e - x_{e-m}) - (x_{e-m} - x_{e-2m}) for e >= 2m, HVAR h_e = a_e -
//     ((x_{e-m} - x_{e-2m}) - (x_{e-2m} - x_{e-3m})) for e >= 3m;
//   - MVAR t_e = diff(P_{e+1}, P_{e+1-3m}) + 3 diff(P_{e+1-2m}, P_{e+1-m}) for e >= 3m - 1 (P_0 = 0);
//   - the decimated series x_0, x_m, x_2m, ...: its non-overlapped sums and the noise sums, in
//     the characterizer's order (the same bits).
// The overlapping sums of squares are summed in another order (four partial sums, then combined):
// a sum of n non-negative terms in any order is within (n - 1) u of the exact one (u = 2^-53),
// so the two differ by at most 2 (n - 1) u relative; the deviation by half of it.
//
// One segment (no gap), terms every `stride` points (stride_of() of batch.hpp). No allocation.
//
// float_batch_taus() sums many taus at once with the same bits: a group of fully overlapped taus
// goes through the record a chunk of points at a time, each tau taking its terms from the chunk
// while the chunk's points at its four ages are in the cache, so that a long record (24 bytes a
// point: 24 MB at 10^6) streams from memory once a group, not once a tau; and the AVAR terms of
// 2m <= e < 3m (one running sum each) are summed eight taus side by side.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>

#include "gyrochar/characterizer.hpp"
#include "gyrochar/noise_id.hpp"

namespace gyrochar {

/// Held phase points as Characterizer<FloatArith> stages them: x[e], and p_hi[e] + p_lo[e] =
/// P_{e+1} = x[0] + ... + x[e] (FloatArith::add_prefix from {0, 0}). The three spans have the same
/// size.
struct FloatRecord {
  std::span<const double> x, p_hi, p_lo;
};

/// Phase point k (x) of an input relative to the line through its first two points (x0 and
/// slope, set at k = 0 and k = 1), as Characterizer<FloatArith>::add_phase_point() stages it:
/// x - x0 formed exactly (as hi + lo), the line taken off by one fused multiply-add. O(1).
inline double line_residual(double x, std::uint64_t k, double& x0, double& slope) {
  if (k == 0) x0 = x;
  const double hi = x - x0;
  const double b = hi - x;
  const double lo = (x - (hi - b)) - (x0 + b);
  if (k == 1) slope = hi;
  return std::fma(-static_cast<double>(k), slope, hi) + lo;
}

/// The sums of tau m (terms every `stride` points: 1, or a power of two that divides m) over the
/// record: what Characterizer<FloatArith> keeps for that tau after the same points (see above for
/// the summation order), and the lag-1 sums of its decimated series added to `noise` (a fresh
/// accumulator: Characterizer::noise()). O(N) for N points (O(N / m) for the decimated series).
TauResult<double> float_batch_sums(const FloatRecord& record, std::uint64_t m, std::uint64_t stride,
                                   NoiseIdAccumulator& noise);

/// Taus float_batch_taus() sums together: the record streams from memory once for each such group.
inline constexpr std::size_t float_batch_group = 64;

/// The sums of the taus m[i] with strides stride[i] (as float_batch_sums() takes them), into out[i],
/// and the noise sums of each added to noise[i] (fresh accumulators): each to the last bit what
/// float_batch_sums() gives for that tau (the same terms added in the same order). The fully
/// overlapped taus (stride 1) go through the record float_batch_group at a time, a chunk of points
/// at a time, so that the chunk's points at the ages of all of them come from the cache (consecutive
/// m share most of them); the others one by one. O(N) per tau; about 25 KB of stack, no allocation.
/// The four spans have the same size.
void float_batch_taus(const FloatRecord& record, std::span<const std::uint64_t> m, std::span<const std::uint64_t> stride,
                      std::span<TauResult<double>> out, std::span<NoiseIdAccumulator> noise);

// The same sums from the staged points x alone (8 bytes a point instead of 24), for the offline
// analyzer's held record (phase and frequency data of a known length, every tau rule):
//   - the AVAR and HVAR terms are float_batch_sums()' (the same operations) and each sum of their
//     squares runs in e's order, as the characterizer's: its sums to the last bit;
//   - the MVAR term t_e = sum_{j<m} a_{e-j} (a_k = x_k - 2 x_{k-m} + x_{k-2m}) is the sum of the m
//     AVAR terms as they are rounded for the AVAR sum (A_k = (x_k - x_{k-m}) - (x_{k-m} - x_{k-2m})
//     in doubles, the same bits), summed exactly: t_{3m-1} = A_{2m} + ... + A_{3m-1}, then
//     t_e = t_{e-1} + (A_e - A_{e-m}), where A_e - A_{e-m} rounded is the HVAR term and a two-sum
//     gives its rounding error, both added by a two-sum to a running sum hi + c whose rounding errors
//     c collects (c rounds too: within n u^2 (T + 2A) a step, T the largest |t|, A the largest |A|).
//     Telescoping, the running sum is exactly A_{e-m+1} + ... + A_e but for c's roundings, so over
//     a record of n points the term comes out (hi + c, rounded) within
//         u |t_e| + sum_{j<m} u (|x_k - x_{k-m}| + |x_{k-m} - x_{k-2m}| + |A_k|)_{k=e-j} + n^2 u^2 (T + 2A)
//     of the exact one (u = 2^-53): the middle part is the roundings of its m AVAR terms, each
//     within what the AVAR term itself owes (zero where the two differences are exact, as for
//     points within a factor 2 of each other); for n = 10^7 the last is below 1.3e-18 (T + 2A).
//     No rounding grows with n, as a running sum in doubles would (n u T). A step costs 14 floating
//     additions where the exact third difference in double-double (before) took 33; the prefix-sum
//     form of float_batch_sums() is within a few u of its sums' differences.
// The terms of several fully overlapped taus run side by side in vector lanes, phase_batch_lanes
// taus at a time, each lane's sums in e's order (the same bits as that tau alone). O(N) per tau,
// no allocation.

/// The sums phase_batch_taus() is asked for: bit k for SumKind k (sum_bit()), and noise_sums for
/// the lag-1 sums of the decimated series; a sum not asked for is left 0 with n = 0 (its terms are
/// not formed), the noise accumulators untouched.
constexpr unsigned sum_bit(SumKind k) { return 1u << static_cast<unsigned>(k); }
inline constexpr unsigned all_overlapping_sums = 7;  // AVAR, MVAR, HVAR
inline constexpr unsigned all_sums = 31;             // and the non-overlapped AVAR and HVAR
inline constexpr unsigned noise_sums = 32;

/// Taus phase_batch_taus() sums side by side.
inline constexpr std::size_t phase_batch_lanes = 4;

/// The sums of the taus m[i] with strides stride[i] over the staged points x (as
/// Characterizer<FloatArith> stages them: FloatRecord::x), into out[i], and the noise sums of each
/// added to noise[i] (fresh accumulators). AVAR, HVAR, the non-overlapped and noise sums: the
/// characterizer's to the last bit; MVAR's terms within the bound above. Only the sums of `kinds`
/// (each the same bits as with all of them). O(N) per tau. The four spans (m, stride, out, noise)
/// have the same size.
void phase_batch_taus(std::span<const double> x, std::span<const std::uint64_t> m, std::span<const std::uint64_t> stride,
                      std::span<TauResult<double>> out, std::span<NoiseIdAccumulator> noise,
                      unsigned kinds = all_sums | noise_sums);

}  // namespace gyrochar
