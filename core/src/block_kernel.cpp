#include "gyrochar/block_kernel.hpp"

#include "gyrochar/term_kernel.hpp"

#if defined(__x86_64__) && defined(__linux__) && defined(__GNUC__) && !defined(__clang__)
#include <immintrin.h>
#define GYROCHAR_KERNEL_AVX2 1
#elif defined(__aarch64__) && defined(__ARM_NEON)
#include <arm_neon.h>
#define GYROCHAR_KERNEL_NEON 1
#endif

namespace gyrochar {
namespace {

// v XOR sign(v): |v| for v >= 0, |v| - 1 below, so every |v| <= 2^bit_width of an OR of them.
// One shifted operand on Arm, a compare and an XOR with SIMD.
inline std::uint64_t fold(std::uint64_t v) { return v ^ static_cast<std::uint64_t>(static_cast<std::int64_t>(v) >> 63); }
// The square of v's low 32-bit half taken as signed (one multiply-add on Arm): v^2 when v fits in int32.
inline std::uint64_t low_square(std::uint64_t v) {
  const auto low = static_cast<std::int32_t>(static_cast<std::uint32_t>(v));
  return static_cast<std::uint64_t>(std::int64_t{low} * low);
}

// The points' phase at ages 0, m, 2m, 3m, and the low words of their P (unused by the running sum).
struct Ages {
  const std::int64_t *x0, *x1, *x2, *x3;
  const std::uint64_t *p0, *p1, *p2, *p3;
};

// Terms of points from .. n-1, one at a time. Running: t is t_{from-1} and becomes t_{n-1}.
template <bool Running>
void proved_points(std::size_t from, std::size_t n, const Ages& g, std::uint64_t& t, ProvedSums& s, std::int64_t* avar_out,
                   std::int64_t* hvar_out) {
  for (std::size_t j = from; j < n; ++j) {
    const auto u0 = static_cast<std::uint64_t>(g.x0[j]), u1 = static_cast<std::uint64_t>(g.x1[j]);
    const auto u2 = static_cast<std::uint64_t>(g.x2[j]), u3 = static_cast<std::uint64_t>(g.x3[j]);
    const std::uint64_t a = term::avar(u0, u1, u2);
    const std::uint64_t h = term::hvar(a, u1, u2, u3);
    if constexpr (Running) {
      t += h;
    } else {
      t = term::mvar(g.p0[j], g.p1[j], g.p2[j], g.p3[j]);
    }
    avar_out[j] = static_cast<std::int64_t>(a);
    hvar_out[j] = static_cast<std::int64_t>(h);
    s.avar += low_square(a);
    s.hvar += low_square(h);
    s.mvar += low_square(t);
  }
}

#if defined(GYROCHAR_KERNEL_AVX2)
[[gnu::target("avx2")]] inline __m256i load(const std::int64_t* p) {
  return _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p));
}
[[gnu::target("avx2")]] inline __m256i load(const std::uint64_t* p) {
  return _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p));
}
// Four points a step, in registers: one vpmuldq squares four low halves. The running sum advances
// four terms a step, t_j = t_{j-4} + h_j + h_{j-1} + h_{j-2} + h_{j-3}, the window from lane shifts
// of this step's and the last step's HVAR terms (taken as 0 before point 0, with every lane of the
// first t_{j-4} equal to t_{-1}).
template <bool Running>
[[gnu::target("avx2")]] ProvedSums proved_avx2(std::size_t n, const Ages& g, std::uint64_t t, std::int64_t* avar_out,
                                               std::int64_t* hvar_out) {
  const std::size_t n4 = n / 4 * 4;
  __m256i sa = _mm256_setzero_si256(), sh = sa, st = sa, h_last = sa, pair_last = sa;
  __m256i tv = _mm256_set1_epi64x(static_cast<std::int64_t>(t));
  for (std::size_t j = 0; j < n4; j += 4) {
    const __m256i u0 = load(g.x0 + j), u1 = load(g.x1 + j), u2 = load(g.x2 + j), u3 = load(g.x3 + j);
    const __m256i d2 = _mm256_sub_epi64(u1, u2);
    const __m256i av = _mm256_sub_epi64(_mm256_sub_epi64(u0, u1), d2);
    const __m256i hv = _mm256_sub_epi64(av, _mm256_sub_epi64(d2, _mm256_sub_epi64(u2, u3)));
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(avar_out + j), av);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(hvar_out + j), hv);
    if constexpr (Running) {
      const __m256i h_back1 = _mm256_alignr_epi8(hv, _mm256_permute2x128_si256(h_last, hv, 0x21), 8);
      const __m256i pair = _mm256_add_epi64(hv, h_back1);  // h_j + h_{j-1}
      tv = _mm256_add_epi64(tv, _mm256_add_epi64(pair, _mm256_permute2x128_si256(pair_last, pair, 0x21)));
      h_last = hv;
      pair_last = pair;
    } else {
      const __m256i d = _mm256_sub_epi64(load(g.p2 + j), load(g.p1 + j));
      tv = _mm256_add_epi64(_mm256_sub_epi64(load(g.p0 + j), load(g.p3 + j)), _mm256_add_epi64(d, _mm256_add_epi64(d, d)));
    }
    sa = _mm256_add_epi64(sa, _mm256_mul_epi32(av, av));
    sh = _mm256_add_epi64(sh, _mm256_mul_epi32(hv, hv));
    st = _mm256_add_epi64(st, _mm256_mul_epi32(tv, tv));
  }
  alignas(32) std::uint64_t qa[4], qh[4], qt[4];
  _mm256_store_si256(reinterpret_cast<__m256i*>(qa), sa);
  _mm256_store_si256(reinterpret_cast<__m256i*>(qh), sh);
  _mm256_store_si256(reinterpret_cast<__m256i*>(qt), st);
  ProvedSums s{qa[0] + qa[1] + qa[2] + qa[3], qt[0] + qt[1] + qt[2] + qt[3], qh[0] + qh[1] + qh[2] + qh[3]};
  if (Running && n4 > 0) t = static_cast<std::uint64_t>(_mm256_extract_epi64(tv, 3));
  proved_points<Running>(n4, n, g, t, s, avar_out, hvar_out);
  return s;
}
#elif defined(GYROCHAR_KERNEL_NEON)
// Four points a step in two-lane vectors: the low halves of four terms packed by one uzp1 and
// squared by smlal and smlal2. The running sum t_j = t_{j-1} + h_j by a lane shift of h.
template <bool Running>
ProvedSums proved_neon(std::size_t n, const Ages& g, std::uint64_t t, std::int64_t* avar_out, std::int64_t* hvar_out) {
  const std::size_t n4 = n / 4 * 4;
  const int64x2_t zero = vdupq_n_s64(0);
  int64x2_t sa = zero, sh = zero, st = zero, carry = vdupq_n_s64(static_cast<std::int64_t>(t));
  const auto terms = [&](std::size_t j, int64x2_t& av, int64x2_t& hv, int64x2_t& tv) {
    const int64x2_t u0 = vld1q_s64(g.x0 + j), u1 = vld1q_s64(g.x1 + j), u2 = vld1q_s64(g.x2 + j), u3 = vld1q_s64(g.x3 + j);
    const int64x2_t d2 = vsubq_s64(u1, u2);
    av = vsubq_s64(vsubq_s64(u0, u1), d2);
    hv = vsubq_s64(av, vsubq_s64(d2, vsubq_s64(u2, u3)));
    vst1q_s64(avar_out + j, av);
    vst1q_s64(hvar_out + j, hv);
    if constexpr (Running) {  // (t_{j-1} + h_j, t_{j-1} + h_j + h_{j+1})
      tv = vaddq_s64(carry, vaddq_s64(hv, vextq_s64(zero, hv, 1)));
      carry = vdupq_laneq_s64(tv, 1);
    } else {
      const uint64x2_t d = vsubq_u64(vld1q_u64(g.p2 + j), vld1q_u64(g.p1 + j));
      tv = vreinterpretq_s64_u64(
          vaddq_u64(vsubq_u64(vld1q_u64(g.p0 + j), vld1q_u64(g.p3 + j)), vaddq_u64(d, vaddq_u64(d, d))));
    }
  };
  const auto square = [](int64x2_t& sum, int64x2_t lo, int64x2_t hi) {
    const int32x4_t low = vuzp1q_s32(vreinterpretq_s32_s64(lo), vreinterpretq_s32_s64(hi));
    sum = vmlal_s32(sum, vget_low_s32(low), vget_low_s32(low));
    sum = vmlal_high_s32(sum, low, low);
  };
  for (std::size_t j = 0; j < n4; j += 4) {
    int64x2_t a0, h0, t0, a1, h1, t1;
    terms(j, a0, h0, t0);
    terms(j + 2, a1, h1, t1);
    square(sa, a0, a1);
    square(sh, h0, h1);
    square(st, t0, t1);
  }
  ProvedSums s{static_cast<std::uint64_t>(vaddvq_s64(sa)), static_cast<std::uint64_t>(vaddvq_s64(st)),
               static_cast<std::uint64_t>(vaddvq_s64(sh))};
  if (Running && n4 > 0) t = static_cast<std::uint64_t>(vgetq_lane_s64(carry, 0));
  proved_points<Running>(n4, n, g, t, s, avar_out, hvar_out);
  return s;
}
#endif

template <bool Running>
ProvedSums proved(std::size_t n, const Ages& g, std::uint64_t t, std::int64_t* avar_out, std::int64_t* hvar_out) {
#if defined(GYROCHAR_KERNEL_AVX2)
  if (__builtin_cpu_supports("avx2")) return proved_avx2<Running>(n, g, t, avar_out, hvar_out);
#endif
#if defined(GYROCHAR_KERNEL_NEON)
  return proved_neon<Running>(n, g, t, avar_out, hvar_out);
#else
  ProvedSums s;
  proved_points<Running>(0, n, g, t, s, avar_out, hvar_out);
  return s;
#endif
}

}  // namespace

ProvedSums proved_terms(std::size_t n, const std::int64_t* x0, const std::int64_t* x1, const std::int64_t* x2,
                        const std::int64_t* x3, const std::uint64_t* p0, const std::uint64_t* p1, const std::uint64_t* p2,
                        const std::uint64_t* p3, std::int64_t* avar_out, std::int64_t* hvar_out) {
  return proved<false>(n, {x0, x1, x2, x3, p0, p1, p2, p3}, 0, avar_out, hvar_out);
}

ProvedSums proved_running_terms(std::size_t n, const std::int64_t* x0, const std::int64_t* x1, const std::int64_t* x2,
                                const std::int64_t* x3, std::uint64_t t_first, std::int64_t* avar_out,
                                std::int64_t* hvar_out) {
  if (n == 0) return {};
  // t_{-1} = t_0 - h_0 (modulo 2^64, like every term here).
  const auto u0 = static_cast<std::uint64_t>(x0[0]), u1 = static_cast<std::uint64_t>(x1[0]);
  const auto u2 = static_cast<std::uint64_t>(x2[0]), u3 = static_cast<std::uint64_t>(x3[0]);
  const std::uint64_t t = t_first - term::hvar(term::avar(u0, u1, u2), u1, u2, u3);
  return proved<true>(n, {x0, x1, x2, x3, nullptr, nullptr, nullptr, nullptr}, t, avar_out, hvar_out);
}

// One definition, compiled twice on the x86-64 host (AVX2 and the baseline), the loader picking
// the one the processor runs; the board's and the microcontroller's builds compile it once.
#if defined(__x86_64__) && defined(__linux__) && !defined(__clang__)
__attribute__((target_clones("avx2", "default")))
#endif
BlockTerms
block_terms(std::size_t n, const std::int64_t* __restrict x0, const std::int64_t* __restrict x1,
            const std::int64_t* __restrict x2, const std::int64_t* __restrict x3, const std::uint64_t* __restrict p0,
            const std::uint64_t* __restrict p1, const std::uint64_t* __restrict p2, const std::uint64_t* __restrict p3,
            std::int64_t* __restrict avar_out, std::int64_t* __restrict hvar_out, std::int64_t* __restrict mvar_out) {
  std::uint64_t bits_a = 0, bits_m = 0, bits_h = 0, sum_a = 0, sum_m = 0, sum_h = 0;
  for (std::size_t j = 0; j < n; ++j) {
    // Modular arithmetic: exact whenever the true value fits in int64.
    const auto u0 = static_cast<std::uint64_t>(x0[j]), u1 = static_cast<std::uint64_t>(x1[j]);
    const auto u2 = static_cast<std::uint64_t>(x2[j]), u3 = static_cast<std::uint64_t>(x3[j]);
    const std::uint64_t a = term::avar(u0, u1, u2);
    const std::uint64_t h = term::hvar(a, u1, u2, u3);
    const std::uint64_t t = term::mvar(p0[j], p1[j], p2[j], p3[j]);
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
