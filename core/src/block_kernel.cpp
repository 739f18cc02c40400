#include "gyrochar/block_kernel.hpp"

namespace gyrochar {
namespace {

// v XOR sign(v): |v| for v >= 0, |v| - 1 below, so every |v| <= 2^bit_width of an OR of them.
// One shifted operand on Arm, a compare and an XOR with SIMD.
inline std::uint64_t fold(std::uint64_t v) {
  return v ^ static_cast<std::uint64_t>(static_cast<std::int64_t>(v) >> 63);
}
// The square of v's low 32-bit half taken as signed (one multiply-add on Arm): v^2 when v fits in int32.
inline std::uint64_t low_square(std::uint64_t v) {
  const auto low = static_cast<std::int32_t>(static_cast<std::uint32_t>(v));
  return static_cast<std::uint64_t>(std::int64_t{low} * low);
}

}  // namespace

// One definition, compiled twice on the x86-64 host (AVX2 and the baseline), the loader picking
// the one the processor runs; the board's and the microcontroller's builds compile it once.
#if defined(__x86_64__) && defined(__linux__) && !defined(__clang__)
__attribute__((target_clones("avx2", "default")))
#endif
BlockTerms block_terms(std::size_t n, const std::int64_t* __restrict x0, const std::int64_t* __restrict x1, const std::int64_t* __restrict x2,
                       const std::int64_t* __restrict x3, const std::uint64_t* __restrict p0, const std::uint64_t* __restrict p1,
                       const std::uint64_t* __restrict p2, const std::uint64_t* __restrict p3, std::int64_t* __restrict avar_out,
                       std::int64_t* __restrict hvar_out, std::int64_t* __restrict mvar_out) {
  std::uint64_t bits_a = 0, bits_m = 0, bits_h = 0, sum_a = 0, sum_m = 0, sum_h = 0;
  for (std::size_t j = 0; j < n; ++j) {
    // Modular arithmetic: exact whenever the true value fits in int64.
    const auto u0 = static_cast<std::uint64_t>(x0[j]), u1 = static_cast<std::uint64_t>(x1[j]);
    const auto u2 = static_cast<std::uint64_t>(x2[j]), u3 = static_cast<std::uint64_t>(x3[j]);
    const std::uint64_t a = (u0 - u1) - (u1 - u2);
    const std::uint64_t h = a - ((u1 - u2) - (u2 - u3));
    const std::uint64_t d = p2[j] - p1[j];
    const std::uint64_t t = (p0[j] - p3[j]) + (d + d + d);
    avar_out[j] = static_cast<std::int64_t>(a);
    hvar_out[j] = static_cast<std::int64_t>(h);
    mvar_out[j] = static_cast<std::int64_t>(t);
    bits_a |= fold(a);
    bits_m |= fold(t);
    bits_h |= fold(h);
    sum_a += low_square(a);
    sum_m += low_square(t);
    sum_h += low_square(h);
  }
  return {{bits_a, sum_a}, {bits_m, sum_m}, {bits_h, sum_h}};
}

#if defined(__x86_64__) && defined(__linux__) && !defined(__clang__)
__attribute__((target_clones("avx2", "default")))
#endif
void every_other(const std::uint64_t* __restrict from, std::uint64_t* __restrict to, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) to[i] = from[2 * i];
}

#if defined(__x86_64__) && defined(__linux__) && !defined(__clang__)
__attribute__((target_clones("avx2", "default")))
#endif
void difference_range(const std::int64_t* __restrict x, std::size_t n, std::int32_t& lo, std::int32_t& hi) {
  std::int32_t smallest = lo, largest = hi;
  for (std::size_t k = 1; k < n; ++k) {
    const auto d = static_cast<std::int32_t>(static_cast<std::uint32_t>(x[k]) - static_cast<std::uint32_t>(x[k - 1]));
    smallest = d < smallest ? d : smallest;
    largest = d > largest ? d : largest;
  }
  lo = smallest;
  hi = largest;
}

}  // namespace gyrochar
