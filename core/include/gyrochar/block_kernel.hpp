#pragma once
// The block kernel of the exact counts path: the overlapping Allan, modified Allan and Hadamard
// terms of one tau over a block of consecutive phase points, and their sums of squares in 64-bit
// partial sums whose exactness is proved per block: from the block's largest term (block_terms()),
// or beforehand from the segment's increment spread (proved_terms(), proved_running_terms(),
// which then form no bound at all: the usual case of a gyro).
//
// Inputs are the phase points at ages 0, m, 2m and 3m of each of the n newest points (x as
// int64, P as its low 64-bit word): the caller gathers them from its history. Terms are formed in
// modular 64-bit arithmetic, which is exact whenever the true term fits in int64 (the caller
// proves that from the input bounds, characterizer.hpp). Each square is the signed square of the
// term's low 32-bit half, a widening multiply SIMD units have: GCC vectorizes the loop with SSE2
// and AVX2 on x86-64 (chosen at run time on the host) and with NEON on aarch64 (smull, smlal);
// Cortex-M runs it scalar (one smlal per square).
// squares_exact() tells whether a partial sum equals the exact sum of squares.
#include <bit>
#include <cstddef>
#include <cstdint>

namespace gyrochar {

/// One statistic's block: the OR of the terms XOR their sign (|term| for term >= 0, |term| - 1
/// below: every |term| <= 2^bit_width of the OR) and the sum of the squares of their low 32-bit
/// halves taken as signed, modulo 2^64.
struct BlockSquares {
  std::uint64_t magnitude_bits = 0;
  std::uint64_t sum = 0;
};

/// Terms of the n newest points of a block (index j = 0..n-1).
struct BlockTerms {
  BlockSquares avar, mvar, hvar;
};

/// The n newest points' terms: x_k[j], p_k[j] are the phase point and its P (P_{e+1}, low word)
/// at age k m of point j. Writes the terms to avar_out[j], hvar_out[j] and mvar_out[j] (the
/// decimated series reuses them; a partial sum that is not exact is summed again from them).
/// O(n), no allocation, cannot fail.
BlockTerms block_terms(std::size_t n, const std::int64_t* x0, const std::int64_t* x1, const std::int64_t* x2,
                       const std::int64_t* x3, const std::uint64_t* p0, const std::uint64_t* p1, const std::uint64_t* p2,
                       const std::uint64_t* p3, std::int64_t* avar_out, std::int64_t* hvar_out, std::int64_t* mvar_out);

/// The sums of the squares of a block's terms when the caller has proved beforehand that every
/// |term| <= bound with squares_exact({bound}, n) (characterizer.hpp's proved_small(): |a| <= m D,
/// |h| <= 2 m D, |t| <= m^2 D for the segment's increment spread D). Each term then fits in int32,
/// so the sums of the squares of the terms' low halves are the exact sums and no bound is formed.
struct ProvedSums {
  std::uint64_t avar = 0, mvar = 0, hvar = 0;
};
/// As block_terms() under that proof: the sums of squares, the AVAR and HVAR terms to avar_out[j]
/// and hvar_out[j] (the decimated series reads them). AVX2 on the x86-64 host (chosen at run
/// time), NEON on aarch64, scalar elsewhere; the same bits on every path. O(n), cannot fail.
ProvedSums proved_terms(std::size_t n, const std::int64_t* x0, const std::int64_t* x1, const std::int64_t* x2,
                        const std::int64_t* x3, const std::uint64_t* p0, const std::uint64_t* p1, const std::uint64_t* p2,
                        const std::uint64_t* p3, std::int64_t* avar_out, std::int64_t* hvar_out);
/// The same for consecutive phase points (a level-0 tau) without their P: the MVAR term as the
/// running sum t_j = t_{j-1} + h_j (t sums m consecutive AVAR terms) from t_first, the term of
/// point 0, which the caller forms from P.
ProvedSums proved_running_terms(std::size_t n, const std::int64_t* x0, const std::int64_t* x1, const std::int64_t* x2,
                                const std::int64_t* x3, std::uint64_t t_first, std::int64_t* avar_out,
                                std::int64_t* hvar_out);

/// Folds the differences x[k] - x[k-1], k = 1..n-1, into lo (the smallest) and hi (the largest),
/// each taken from the low 32-bit words: exact when every difference fits in int32. O(n).
void difference_range(const std::int64_t* x, std::size_t n, std::int32_t& lo, std::int32_t& hi);

/// to[i] = from[2 i] for i < n (the points of the next level up); the arrays do not overlap. O(n).
void every_other(const std::uint64_t* from, std::uint64_t* to, std::size_t n);

/// True when s.sum is the exact sum of the n squared terms: every |term| <= 2^b with 2b + bit_width(n)
/// <= 64, so each term fits in int32 (its low half is itself) and n squares of at most 2^2b stay
/// below 2^64.
constexpr bool squares_exact(const BlockSquares& s, std::size_t n) {
  return 2 * std::bit_width(s.magnitude_bits) + std::bit_width(n) <= 64;
}

}  // namespace gyrochar
