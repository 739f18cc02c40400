#pragma once
// The overlapping terms of the exact counts paths at one point, written once: the characterizer's
// block kernel (block_kernel.cpp), the batch path (batch.cpp: its scalar loops and the scalar
// tails of its AVX2 and AVX-512 loops) and the decimated series of both take them from here.
// stat.hpp defines the terms; the SIMD loops spell the same operations lane by lane.
//
// Phase words u0, u1, u2, u3 are x at ages 0, m, 2m, 3m, and p0..p3 the low words of P there, as
// 64-bit words: the arithmetic is modulo 2^64, so each term is exact whenever its true value fits
// in int64 (the callers prove or check that). Always inlined: the per-sample path keeps its code.
// term::avar(), term::hvar() and term::mvar() name the statistic whose term they form.
#include <cstdint>

namespace gyrochar::term {

/// AVAR term a = x0 - 2 x1 + x2, modulo 2^64.
[[gnu::always_inline]] constexpr std::uint64_t avar(std::uint64_t u0, std::uint64_t u1, std::uint64_t u2) {
  return (u0 - u1) - (u1 - u2);
}

/// HVAR term h = x0 - 3 x1 + 3 x2 - x3 from the AVAR term a at the same point, modulo 2^64.
[[gnu::always_inline]] constexpr std::uint64_t hvar(std::uint64_t a, std::uint64_t u1, std::uint64_t u2, std::uint64_t u3) {
  return a - ((u1 - u2) - (u2 - u3));
}

/// MVAR term t = P0 - 3 P1 + 3 P2 - P3 from the low words of P, modulo 2^64.
[[gnu::always_inline]] constexpr std::uint64_t mvar(std::uint64_t p0, std::uint64_t p1, std::uint64_t p2, std::uint64_t p3) {
  const std::uint64_t d = p2 - p1;
  return (p0 - p3) + (d + d + d);
}

}  // namespace gyrochar::term
