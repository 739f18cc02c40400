// The batch path of the exact counts statistics (see batch.hpp).
#include "gyrochar/batch.hpp"

#include <bit>

#include "gyrochar/assert.hpp"
#include "gyrochar/term_kernel.hpp"

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#include <immintrin.h>
#define GYROCHAR_BATCH_AVX2 1
#endif

namespace gyrochar {
namespace {

constexpr std::size_t chunk = 256;  // terms per partial sum

// A chunk's squares in one 64-bit word: every term's low 32-bit half squared as a signed value,
// and a bound on the terms, the OR of v XOR sign(v) (|v| <= 2^bit_width of it). Both are SIMD
// operations on every target (a signed 32x32->64 multiply), and the sum is exact when
// exact() says so.
struct Squares {
  std::uint64_t bound = 0;
  std::uint64_t sum = 0;
  void add(std::int64_t v) {
    bound |= static_cast<std::uint64_t>(v ^ (v >> 63));
    const auto low = static_cast<std::int32_t>(v);
    sum += static_cast<std::uint64_t>(std::int64_t{low} * low);
  }
  // Every |v| <= 2^b with 2b + bit_width(n) <= 64: each v fits in int32 (its low half is itself)
  // and n squares of at most 2^2b stay below 2^64.
  bool exact(std::size_t n) const { return 2 * std::bit_width(bound) + std::bit_width(n) <= 64; }
};

template <class R>
inline std::uint64_t word(R v) {
  return static_cast<std::uint64_t>(static_cast<std::int64_t>(v));
}

// The overlapping sums of one tau (index: SumKind avar 0, mvar 1, hvar 2) while a segment runs.
struct Totals {
  UInt128 sum[3];
  std::uint64_t n[3];
  std::uint64_t sticky;
  void add(int k, std::int64_t v) {
    sticky |= add_high_word(sum[k], square(v));
    ++n[k];
  }
};

// The terms of a chunk, newest points x0[0 .. n): AVAR, and HVAR when `hvar`, with their squares.
struct ChunkSquares {
  Squares a, h;
};
template <class R>
[[gnu::always_inline]] inline ChunkSquares avar_hvar(const R* __restrict x0, std::size_t m, std::size_t n, bool hvar,
                                                     std::int64_t* __restrict a, std::int64_t* __restrict h) {
  ChunkSquares sq;
  for (std::size_t j = 0; j < n; ++j) {
    const std::uint64_t u1 = word(x0[j - m]), u2 = word(x0[j - 2 * m]);
    const std::uint64_t au = term::avar(word(x0[j]), u1, u2);
    const auto av = static_cast<std::int64_t>(au);
    a[j] = av;
    sq.a.add(av);
    if (hvar) {
      const auto hv = static_cast<std::int64_t>(term::hvar(au, u1, u2, word(x0[j - 3 * m])));
      h[j] = hv;
      sq.h.add(hv);
    }
  }
  return sq;
}

// A chunk's squares v[0 .. n) with their partial sum s: s when it is exact, else term by term
// in 128 bits.
inline void add_exact(Totals& tot, int k, std::size_t n, const Squares& s) {
  tot.sticky |= add_high_word(tot.sum[k], UInt128{s.sum, 0});
  tot.n[k] += n;
}
inline void add_chunk(Totals& tot, int k, const std::int64_t* v, std::size_t n, const Squares& s) {
  if (s.exact(n)) {
    add_exact(tot, k, n, s);
  } else {
    for (std::size_t j = 0; j < n; ++j) tot.add(k, v[j]);
  }
}
[[gnu::always_inline]] inline Squares squares(const std::int64_t* __restrict v, std::size_t n) {
  Squares s;
  for (std::size_t j = 0; j < n; ++j) s.add(v[j]);
  return s;
}

// Strided taus: the chunk's terms at first, first + step, ... only.
inline void add_selected(Totals& tot, int k, const std::int64_t* v, std::size_t n, std::size_t first, std::size_t step) {
  for (std::size_t j = first; j < n; j += step) tot.add(k, v[j]);
}

// t[j] = t[j-1] + h[j] from t[-1] = previous, in four independent runs (a quarter each, started
// from the quarters' sums) so that the additions overlap. Returns t[n-1].
[[gnu::always_inline]] inline std::uint64_t running_sum(const std::int64_t* __restrict h, std::int64_t* __restrict t,
                                                        std::size_t n, std::uint64_t previous) {
  const std::size_t q = n / 4;
  std::uint64_t s0 = 0, s1 = 0, s2 = 0;
  for (std::size_t j = 0; j < q; ++j) {
    s0 += static_cast<std::uint64_t>(h[j]);
    s1 += static_cast<std::uint64_t>(h[q + j]);
    s2 += static_cast<std::uint64_t>(h[2 * q + j]);
  }
  std::uint64_t c0 = previous, c1 = previous + s0, c2 = c1 + s1, c3 = c2 + s2;
  for (std::size_t j = 0; j < q; ++j) {
    c0 += static_cast<std::uint64_t>(h[j]);
    c1 += static_cast<std::uint64_t>(h[q + j]);
    c2 += static_cast<std::uint64_t>(h[2 * q + j]);
    c3 += static_cast<std::uint64_t>(h[3 * q + j]);
    t[j] = static_cast<std::int64_t>(c0);
    t[q + j] = static_cast<std::int64_t>(c1);
    t[2 * q + j] = static_cast<std::int64_t>(c2);
    t[3 * q + j] = static_cast<std::int64_t>(c3);
  }
  for (std::size_t j = 4 * q; j < n; ++j) t[j] = static_cast<std::int64_t>(c3 += static_cast<std::uint64_t>(h[j]));
  return c3;
}

// All three terms of a chunk of int32 residuals (s >= 3m), as avar_hvar() and running_sum() form
// them, in AVX2 by hand and in registers: the squares by one signed 32x32->64 multiply (vpmuldq)
// per four terms, where the compiler's vectorization packs and unpacks the low halves; the MVAR
// running sum four terms a step, t_e = t_{e-4} + (h_e + h_{e-1} + h_{e-2} + h_{e-3}), the window
// from lane shifts of this step's and the last step's HVAR terms. Only the squares come out: the
// caller forms the chunk again when one of them is not exact. `previous`: t before the chunk,
// then its last. Chosen at run time (has_avx2()); the x86-64 host's analyzer spends most of its
// time here.
#ifdef GYROCHAR_BATCH_AVX2
struct ChunkSquares3 {
  Squares a, h, t;
};
// The terms from index `from` to n - 1, scalar, after a vector loop stopped there: the scalar tail
// the AVX2 and AVX-512 loops share. t: the running MVAR sum before `from`; returns it at n - 1.
inline std::uint64_t scalar_tail(const std::int32_t* x0, std::size_t m, std::size_t from, std::size_t n, std::uint64_t t,
                                 ChunkSquares3& sq) {
  for (std::size_t j = from; j < n; ++j) {  // as avar_hvar() and running_sum()
    const std::uint64_t u1 = word(x0[j - m]), u2 = word(x0[j - 2 * m]);
    const std::uint64_t a = term::avar(word(x0[j]), u1, u2);
    const std::uint64_t h = term::hvar(a, u1, u2, word(x0[j - 3 * m]));
    t += h;
    sq.a.add(static_cast<std::int64_t>(a));
    sq.h.add(static_cast<std::int64_t>(h));
    sq.t.add(static_cast<std::int64_t>(t));
  }
  return t;
}
// The vectors' bound is the OR of v + 2^27 (modulo 2^64): below 2^28 exactly when every v is in
// [-2^27, 2^27), where the low halves are the terms and 256 squares stay below 2^62. One
// operation fewer a term than Squares' OR of magnitudes; reduce() turns it into Squares' bound
// (2^27 - 1 when in range, else all ones: such a chunk is formed again).
constexpr std::uint64_t square_range = std::uint64_t{1} << 27;
static_assert(chunk <= 1024, "2 * 27 + bit_width(chunk) <= 64");
[[gnu::target("avx2")]] inline void accumulate(__m256i v, __m256i& bound, __m256i& sum) {
  const __m256i offset = _mm256_set1_epi64x(static_cast<std::int64_t>(square_range));
  bound = _mm256_or_si256(bound, _mm256_add_epi64(v, offset));
  sum = _mm256_add_epi64(sum, _mm256_mul_epi32(v, v));
}
[[gnu::target("avx2")]] inline Squares reduce(__m256i bound, __m256i sum) {
  alignas(32) std::uint64_t b[4], q[4];
  _mm256_store_si256(reinterpret_cast<__m256i*>(b), bound);
  _mm256_store_si256(reinterpret_cast<__m256i*>(q), sum);
  const bool in_range = (b[0] | b[1] | b[2] | b[3]) < 2 * square_range;
  return {in_range ? square_range - 1 : ~std::uint64_t{0}, q[0] + q[1] + q[2] + q[3]};
}
[[gnu::target("avx2")]] inline __m256i load4(const std::int32_t* p) {
  return _mm256_cvtepi32_epi64(_mm_loadu_si128(reinterpret_cast<const __m128i*>(p)));
}
[[gnu::target("avx2")]] ChunkSquares3 all_terms_avx2(const std::int32_t* x0, std::size_t m, std::size_t n,
                                                     std::uint64_t& previous) {
  const std::size_t n4 = n / 4 * 4;
  __m256i ba = _mm256_setzero_si256(), sa = ba, bh = ba, sh = ba, bt = ba, st = ba;
  // Before the chunk: no HVAR term (the window counts only this chunk's), t = previous.
  __m256i h_last = _mm256_setzero_si256(), pair_last = h_last;
  __m256i tv = _mm256_set1_epi64x(static_cast<std::int64_t>(previous));
  for (std::size_t j = 0; j < n4; j += 4) {
    const __m256i u0 = load4(x0 + j), u1 = load4(x0 + j - m), u2 = load4(x0 + j - 2 * m), u3 = load4(x0 + j - 3 * m);
    const __m256i d2 = _mm256_sub_epi64(u1, u2);
    const __m256i av = _mm256_sub_epi64(_mm256_sub_epi64(u0, u1), d2);
    const __m256i hv = _mm256_sub_epi64(av, _mm256_sub_epi64(d2, _mm256_sub_epi64(u2, u3)));
    // (h_{j-1}, h_j, h_{j+1}, h_{j+2}) from (h_{j-2}, h_{j-1}, h_j, h_{j+1}) and hv.
    const __m256i h_back1 = _mm256_alignr_epi8(hv, _mm256_permute2x128_si256(h_last, hv, 0x21), 8);
    const __m256i pair = _mm256_add_epi64(hv, h_back1);  // h_e + h_{e-1}
    tv = _mm256_add_epi64(tv, _mm256_add_epi64(pair, _mm256_permute2x128_si256(pair_last, pair, 0x21)));
    h_last = hv;
    pair_last = pair;
    accumulate(av, ba, sa);
    accumulate(hv, bh, sh);
    accumulate(tv, bt, st);
  }
  ChunkSquares3 sq{reduce(ba, sa), reduce(bh, sh), reduce(bt, st)};
  std::uint64_t t = n4 > 0 ? static_cast<std::uint64_t>(_mm256_extract_epi64(tv, 3)) : previous;
  previous = scalar_tail(x0, m, n4, n, t, sq);
  return sq;
}
// The AVAR terms alone (2m <= s < 3m), likewise: their squares only.
[[gnu::target("avx2")]] Squares avar_terms_avx2(const std::int32_t* x0, std::size_t m, std::size_t n) {
  const std::size_t n4 = n / 4 * 4;
  __m256i ba = _mm256_setzero_si256(), sa = ba;
  for (std::size_t j = 0; j < n4; j += 4) {
    const __m256i u0 = load4(x0 + j), u1 = load4(x0 + j - m), u2 = load4(x0 + j - 2 * m);
    accumulate(_mm256_sub_epi64(_mm256_sub_epi64(u0, u1), _mm256_sub_epi64(u1, u2)), ba, sa);
  }
  Squares sq = reduce(ba, sa);
  for (std::size_t j = n4; j < n; ++j) {
    sq.add(static_cast<std::int64_t>(term::avar(word(x0[j]), word(x0[j - m]), word(x0[j - 2 * m]))));
  }
  return sq;
}
// The same with AVX-512 where the processor has it: eight terms a step, the running sum's window
// from three lane shifts (pairs, fours, eights: t_e = t_{e-8} + h_e + ... + h_{e-7}), one bound
// for the three statistics (a chunk whose bound fails is formed again, all three, anyway).
// (GCC 12 takes the AVX-512 intrinsics' deliberately undefined pass-through operand for an
// uninitialized variable.)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#pragma GCC diagnostic ignored "-Wuninitialized"
[[gnu::target("avx512f")]] inline __m512i load8(const std::int32_t* p) {
  return _mm512_cvtepi32_epi64(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(p)));
}
// The lanes' sum modulo 2^64 (the header's _mm512_reduce_add_epi64 adds them as signed: UB on wrap).
[[gnu::target("avx512f")]] inline std::uint64_t lane_sum(__m512i v) {
  alignas(64) std::uint64_t q[8];
  _mm512_store_si512(q, v);
  return q[0] + q[1] + q[2] + q[3] + q[4] + q[5] + q[6] + q[7];
}
[[gnu::target("avx512f")]] ChunkSquares3 all_terms_avx512(const std::int32_t* x0, std::size_t m, std::size_t n,
                                                          std::uint64_t& previous) {
  const std::size_t n8 = n / 8 * 8;
  const __m512i offset = _mm512_set1_epi64(static_cast<std::int64_t>(square_range));
  __m512i bound = _mm512_setzero_si512(), sa = bound, sh = bound, st = bound;
  __m512i h_last = bound, pair_last = bound, four_last = bound;
  __m512i tv = _mm512_set1_epi64(static_cast<std::int64_t>(previous));
  for (std::size_t j = 0; j < n8; j += 8) {
    const __m512i u0 = load8(x0 + j), u1 = load8(x0 + j - m), u2 = load8(x0 + j - 2 * m), u3 = load8(x0 + j - 3 * m);
    const __m512i d2 = _mm512_sub_epi64(u1, u2);
    const __m512i av = _mm512_sub_epi64(_mm512_sub_epi64(u0, u1), d2);
    const __m512i hv = _mm512_sub_epi64(av, _mm512_sub_epi64(d2, _mm512_sub_epi64(u2, u3)));
    const __m512i pair = _mm512_add_epi64(hv, _mm512_alignr_epi64(hv, h_last, 7));         // h_e + h_{e-1}
    const __m512i four = _mm512_add_epi64(pair, _mm512_alignr_epi64(pair, pair_last, 6));  // ... + h_{e-3}
    tv = _mm512_add_epi64(tv, _mm512_add_epi64(four, _mm512_alignr_epi64(four, four_last, 4)));
    h_last = hv;
    pair_last = pair;
    four_last = four;
    const __m512i wa = _mm512_add_epi64(av, offset), wh = _mm512_add_epi64(hv, offset);
    bound = _mm512_ternarylogic_epi64(bound, wa, wh, 0xFE);  // bound | wa | wh
    bound = _mm512_or_si512(bound, _mm512_add_epi64(tv, offset));
    sa = _mm512_add_epi64(sa, _mm512_mul_epi32(av, av));
    sh = _mm512_add_epi64(sh, _mm512_mul_epi32(hv, hv));
    st = _mm512_add_epi64(st, _mm512_mul_epi32(tv, tv));
  }
  const bool in_range = static_cast<std::uint64_t>(_mm512_reduce_or_epi64(bound)) < 2 * square_range;
  const std::uint64_t b = in_range ? square_range - 1 : ~std::uint64_t{0};
  ChunkSquares3 sq{{b, lane_sum(sa)}, {b, lane_sum(sh)}, {b, lane_sum(st)}};
  std::uint64_t t = n8 > 0 ? static_cast<std::uint64_t>(_mm_extract_epi64(_mm512_extracti32x4_epi32(tv, 3), 1)) : previous;
  previous = scalar_tail(x0, m, n8, n, t, sq);
  return sq;
}
#pragma GCC diagnostic pop
// Loads and bit tests once libgcc's start-up has read the processor's features (before main);
// no static of its own, which the threads summing taus would race to initialize.
inline bool has_avx2() { return __builtin_cpu_supports("avx2"); }
inline bool has_avx512() { return __builtin_cpu_supports("avx512f"); }
#endif

// The overlapping terms of tau m (stride a power of two, terms where first_e + s is a multiple of
// it) over the segment r[0 .. size), whose terms are proved to fit in int64: AVAR for s >= 2m,
// MVAR for s >= 3m - 1, HVAR for s >= 3m (s: index in the segment).
template <class R>
[[gnu::always_inline]] inline void overlapping(const R* __restrict r, std::size_t size, std::size_t m, std::uint64_t first_e,
                                               std::uint64_t stride, Totals& tot) {
  alignas(64) std::int64_t a[chunk], h[chunk], t[chunk];
  const auto selected = [&](std::size_t s0) {  // first index of the chunk from s0 with a term
    return static_cast<std::size_t>((stride - (first_e + s0) % stride) % stride);
  };
  const auto step = static_cast<std::size_t>(stride);
  // AVAR alone: 2m <= s < 3m.
  const std::size_t a_end = size < 3 * m ? size : 3 * m;
  for (std::size_t s0 = 2 * m; s0 < a_end; s0 += chunk) {
    const std::size_t n = a_end - s0 < chunk ? a_end - s0 : chunk;
#ifdef GYROCHAR_BATCH_AVX2
    if constexpr (sizeof(R) == 4) {
      if (step == 1 && has_avx2()) {
        const Squares sq = avar_terms_avx2(r + s0, m, n);
        if (sq.exact(n)) {
          add_exact(tot, 0, n, sq);
          continue;
        }
      }
    }
#endif
    const ChunkSquares sq = avar_hvar(r + s0, m, n, false, a, h);
    if (step == 1) {
      add_chunk(tot, 0, a, n, sq.a);
    } else {
      add_selected(tot, 0, a, n, selected(s0), step);
    }
  }
  if (size < 3 * m) return;
  // The first MVAR term, s = 3m - 1: P[3m] - 3 P[2m] + 3 P[m] - P[0] over the residuals (the
  // line's prefix sums are quadratic: their third difference is 0).
  std::uint64_t q1 = 0, q2 = 0, q3 = 0;
  for (std::size_t i = 0; i < m; ++i) q1 += word(r[i]);
  for (std::size_t i = m; i < 2 * m; ++i) q2 += word(r[i]);
  for (std::size_t i = 2 * m; i < 3 * m; ++i) q3 += word(r[i]);
  q2 += q1;
  q3 += q2;
  std::uint64_t tp = q3 - 3 * q2 + 3 * q1;
  if ((first_e + 3 * m - 1) % stride == 0) tot.add(1, static_cast<std::int64_t>(tp));
  // All three: s >= 3m. t_s = t_{s-1} + h_s.
  for (std::size_t s0 = 3 * m; s0 < size; s0 += chunk) {
    const std::size_t n = size - s0 < chunk ? size - s0 : chunk;
#ifdef GYROCHAR_BATCH_AVX2
    if constexpr (sizeof(R) == 4) {
      if (step == 1 && has_avx2()) {
        const std::uint64_t before = tp;
        const ChunkSquares3 sq = has_avx512() ? all_terms_avx512(r + s0, m, n, tp) : all_terms_avx2(r + s0, m, n, tp);
        if (sq.a.exact(n) && sq.h.exact(n) && sq.t.exact(n)) {
          add_exact(tot, 0, n, sq.a);
          add_exact(tot, 2, n, sq.h);
          add_exact(tot, 1, n, sq.t);
          continue;
        }
        tp = before;  // formed again below, summed term by term where needed
      }
    }
#endif
    const ChunkSquares sq = avar_hvar(r + s0, m, n, true, a, h);
    tp = running_sum(h, t, n, tp);
    if (step == 1) {
      add_chunk(tot, 0, a, n, sq.a);
      add_chunk(tot, 2, h, n, sq.h);
      add_chunk(tot, 1, t, n, squares(t, n));
    } else {
      const std::size_t first = selected(s0);
      add_selected(tot, 0, a, n, first, step);
      add_selected(tot, 2, h, n, first, step);
      add_selected(tot, 1, t, n, first, step);
    }
  }
}

// One definition per residual type, compiled twice on the x86-64 host (AVX2 and the baseline,
// chosen by the loader), once elsewhere.
#if defined(__x86_64__) && defined(__linux__) && !defined(__clang__)
#define GYROCHAR_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define GYROCHAR_CLONES
#endif
GYROCHAR_CLONES void overlapping32(const std::int32_t* r, std::size_t size, std::size_t m, std::uint64_t first_e,
                                   std::uint64_t stride, Totals& tot) {
  overlapping(r, size, m, first_e, stride, tot);
}
GYROCHAR_CLONES void overlapping64(const std::int64_t* r, std::size_t size, std::size_t m, std::uint64_t first_e,
                                   std::uint64_t stride, Totals& tot) {
  overlapping(r, size, m, first_e, stride, tot);
}
void overlapping_of(const std::int32_t* r, std::size_t size, std::size_t m, std::uint64_t first_e, std::uint64_t stride,
                    Totals& tot) {
  overlapping32(r, size, m, first_e, stride, tot);
}
void overlapping_of(const std::int64_t* r, std::size_t size, std::size_t m, std::uint64_t first_e, std::uint64_t stride,
                    Totals& tot) {
  overlapping64(r, size, m, first_e, stride, tot);
}

// One chunk of the decimated series v[3 .. 3 + n) (v[0 .. 3): the three points before it): the
// largest |v[k] - v[k-1]| from k = `from` on, computed without overflow checks (the caller has
// proved every difference fits in int64), and, when `terms`, the AVAR terms from first_a and the
// HVAR terms from first_h (0 before them) with their squares.
struct DecimatedChunk {
  std::uint64_t step = 0;
  Squares a, h;
};
GYROCHAR_CLONES DecimatedChunk decimated_chunk(const std::int64_t* v, std::size_t n, std::size_t from, bool terms,
                                               std::size_t first_a, std::size_t first_h, std::int64_t* a, std::int64_t* h) {
  DecimatedChunk c;
  for (std::size_t k = from; k < n; ++k) {
    const std::uint64_t d = static_cast<std::uint64_t>(v[3 + k]) - static_cast<std::uint64_t>(v[2 + k]);
    const std::uint64_t sign = d >> 63;
    const std::uint64_t magnitude = (d ^ (0 - sign)) + sign;
    c.step = magnitude > c.step ? magnitude : c.step;
  }
  if (!terms) return c;
  for (std::size_t k = 0; k < n; ++k) {
    const auto u0 = static_cast<std::uint64_t>(v[3 + k]), u1 = static_cast<std::uint64_t>(v[2 + k]);
    const auto u2 = static_cast<std::uint64_t>(v[1 + k]), u3 = static_cast<std::uint64_t>(v[k]);
    const std::uint64_t av = term::avar(u0, u1, u2);
    a[k] = k >= first_a ? static_cast<std::int64_t>(av) : 0;
    h[k] = k >= first_h ? static_cast<std::int64_t>(term::hvar(av, u1, u2, u3)) : 0;
    c.a.add(a[k]);
    c.h.add(h[k]);
  }
  return c;
}

// The characterizer's terms_fit(): with spread D every term of tau m fits in int64 when
// 2 m^2 D < 2^63.
bool terms_fit(std::uint64_t m, std::uint64_t spread) {
  if (m > (std::uint64_t{1} << 31)) return false;
  return spread <= (~std::uint64_t{0} >> 1) / (2 * m * m);
}

template <class R>
std::int64_t point(const PhaseSegment<R>& s, std::size_t j) {
  return static_cast<std::int64_t>(static_cast<std::uint64_t>(s.x0) + static_cast<std::uint64_t>(s.slope) * j +
                                   word(s.r[j]));
}

}  // namespace

BatchTau::BatchTau(std::uint64_t m, std::uint64_t stride) {
  GYROCHAR_ASSERT(m >= 1);
  GYROCHAR_ASSERT(std::has_single_bit(stride));
  GYROCHAR_ASSERT(stride == 1 || m % stride == 0);
  result_.m = m;
  result_.stride = stride;
}

void BatchTau::add_segment(const PhaseSegment<std::int32_t>& segment) { add(segment); }
void BatchTau::add_segment(const PhaseSegment<std::int64_t>& segment) { add(segment); }

template <class R>
void BatchTau::add(const PhaseSegment<R>& segment) {
  if (segments_++ > 0) noise_.reset_segment();
  const std::uint64_t m = result_.m;
  const bool fits = terms_fit(m, segment.spread);
  // At m = 1 with stride 1 the decimated series is the whole segment: its Allan and Hadamard
  // terms are the overlapping ones, whose sums are taken below instead of forming them twice.
  const bool every_point = m == 1 && result_.stride == 1 && fits;
  decimate(segment, fits, !every_point);
  if (segment.r.size() <= 2 * m) return;  // no term (and m fits in size_t below)
  if (!fits) {
    checked_terms(segment);
    return;
  }
  Totals tot{{result_.sum[0], result_.sum[1], result_.sum[2]}, {result_.n[0], result_.n[1], result_.n[2]}, sticky_};
  overlapping_of(segment.r.data(), segment.r.size(), static_cast<std::size_t>(m), segment.first_e, result_.stride, tot);
  if (every_point)
    for (const SumKind kind : {SumKind::avar, SumKind::hvar}) {
      const auto k = static_cast<std::size_t>(kind);
      const auto d = static_cast<std::size_t>(kind == SumKind::avar ? SumKind::avar_nonoverlapped
                                                                    : SumKind::hvar_nonoverlapped);
      const Int128 segment_sum = Int128{tot.sum[k].lo, tot.sum[k].hi} - Int128{result_.sum[k].lo, result_.sum[k].hi};
      tot.sticky |= add_high_word(result_.sum[d], {segment_sum.lo, segment_sum.hi});
      result_.n[d] += tot.n[k] - result_.n[k];
    }
  for (std::size_t k = 0; k < 3; ++k) {
    result_.sum[k] = tot.sum[k];
    result_.n[k] = tot.n[k];
  }
  sticky_ = tot.sticky;
}

// The decimated series x[k m] of the segment: the non-overlapped Allan and Hadamard sums and the
// noise sums, as Characterizer::decimate() forms them, a chunk of points at a time. When the tau's
// terms fit (they are among the overlapping ones), in modular arithmetic with partial sums of
// squares; otherwise each checked as the characterizer does. Without `terms`, the noise sums only.
template <class R>
void BatchTau::decimate(const PhaseSegment<R>& segment, bool fits, bool terms) {
  const std::uint64_t m = result_.m;
  const std::uint64_t size = segment.r.size();
  std::uint64_t s = (m - segment.first_e % m) % m;
  std::int64_t v[3 + chunk];  // the three points before the chunk, then the chunk
  std::int64_t a[chunk], h[chunk];
  std::uint64_t have = 0;  // points of this segment before the chunk
  const auto avar_d = static_cast<std::size_t>(SumKind::avar_nonoverlapped);
  const auto hvar_d = static_cast<std::size_t>(SumKind::hvar_nonoverlapped);
  // Int32 residuals: x[k m] - x[(k-1) m] = slope m + (a difference of two residuals, below 2^32
  // in magnitude), which fits in int64 when |slope| m <= 2^62: no overflow check needed.
  const std::uint64_t slope = segment.slope < 0 ? std::uint64_t{0} - static_cast<std::uint64_t>(segment.slope)
                                                : static_cast<std::uint64_t>(segment.slope);
  const bool small_steps = sizeof(R) == 4 && m <= (std::uint64_t{1} << 31) && slope <= (std::uint64_t{1} << 31);
  while (s < size) {
    const std::uint64_t left = (size - s + m - 1) / m;
    const auto n = static_cast<std::size_t>(left < chunk ? left : chunk);
    for (std::size_t k = 0; k < n; ++k) v[3 + k] = point(segment, static_cast<std::size_t>(s + k * m));
    s += n * m;
    const std::size_t first_a = have >= 2 ? 0 : static_cast<std::size_t>(2 - have);
    const std::size_t first_h = have >= 3 ? 0 : static_cast<std::size_t>(3 - have);
    const std::size_t from = have > 0 ? 0 : 1;
    DecimatedChunk c;
    if (small_steps) {
      c = decimated_chunk(v, n, from, fits && terms, first_a, first_h, a, h);
    } else {
      c.step = 0;  // the largest |x[k m] - x[(k-1) m]| here (all ones: beyond int64)
      for (std::size_t k = from; k < n; ++k) {
        std::int64_t d = 0;
        const bool wide = __builtin_sub_overflow(v[3 + k], v[2 + k], &d);
        const auto mag = wide    ? ~std::uint64_t{0}
                         : d < 0 ? std::uint64_t{0} - static_cast<std::uint64_t>(d)
                                 : static_cast<std::uint64_t>(d);
        if (mag > c.step) c.step = mag;
      }
      if (fits && terms) {
        const DecimatedChunk t = decimated_chunk(v, n, n, true, first_a, first_h, a, h);
        c.a = t.a;
        c.h = t.h;
      }
    }
    noise_.add(v + 3, n, 1, c.step);
    if (fits && terms) {
      const Squares& sa = c.a;
      const Squares& sh = c.h;
      Totals tot{{result_.sum[avar_d], {}, result_.sum[hvar_d]}, {0, 0, 0}, sticky_};
      if (first_a < n) add_chunk(tot, 0, a + first_a, n - first_a, sa);
      if (first_h < n) add_chunk(tot, 2, h + first_h, n - first_h, sh);
      result_.sum[avar_d] = tot.sum[0];
      result_.sum[hvar_d] = tot.sum[2];
      result_.n[avar_d] += tot.n[0];
      result_.n[hvar_d] += tot.n[2];
      sticky_ = tot.sticky;
    } else if (!fits) {
      for (std::size_t k = 0; k < n; ++k) {
        std::int64_t av = 0, hv = 0;
        if (k >= first_a && CountArith::x_term2(v[3 + k], v[2 + k], v[1 + k], av)) {
          sticky_ |= CountArith::accumulate(result_.sum[avar_d], av);
          ++result_.n[avar_d];
        }
        if (k >= first_h && CountArith::x_terms(v[3 + k], v[2 + k], v[1 + k], v[k], av, hv)) {
          sticky_ |= CountArith::accumulate(result_.sum[hvar_d], hv);
          ++result_.n[hvar_d];
        }
      }
    }
    have += n;
    for (std::size_t k = 0; k < 3; ++k) v[k] = v[n + k];
  }
}

// Point by point, every term checked, as the characterizer's form_terms() (for taus whose terms
// the spread does not prove to fit). P as exact 128-bit prefix sums from the segment's start.
template <class R>
void BatchTau::checked_terms(const PhaseSegment<R>& segment) {
  const std::uint64_t m = result_.m, stride = result_.stride;
  const std::uint64_t size = segment.r.size();
  Int128 p[4];  // P[s + 1 - k m] at point s
  for (std::uint64_t s = 0; s < size; ++s) {
    for (std::uint64_t k = 0; k < 4 && k * m <= s; ++k)
      p[k] = p[k] + widen(point(segment, static_cast<std::size_t>(s - k * m)));
    if (s < 2 * m || (segment.first_e + s) % stride != 0) continue;
    const std::int64_t x0 = point(segment, static_cast<std::size_t>(s));
    const std::int64_t x1 = point(segment, static_cast<std::size_t>(s - m));
    const std::int64_t x2 = point(segment, static_cast<std::size_t>(s - 2 * m));
    std::int64_t a = 0, h = 0, t = 0;
    if (s < 3 * m) {
      if (!CountArith::x_term2(x0, x1, x2, a)) {
        ++result_.out_of_range;
      } else {
        sticky_ |= CountArith::accumulate(result_.sum[0], a);
        ++result_.n[0];
      }
      if (s + 1 != 3 * m) continue;
    } else if (!CountArith::x_terms(x0, x1, x2, point(segment, static_cast<std::size_t>(s - 3 * m)), a, h)) {
      ++result_.out_of_range;
    } else {
      sticky_ |= CountArith::accumulate(result_.sum[0], a);
      ++result_.n[0];
      sticky_ |= CountArith::accumulate(result_.sum[2], h);
      ++result_.n[2];
    }
    if (!CountArith::p_term(p[0], p[1], p[2], p[3], t)) {
      ++result_.out_of_range;
      continue;
    }
    sticky_ |= CountArith::accumulate(result_.sum[1], t);
    ++result_.n[1];
  }
}

}  // namespace gyrochar
