// Exact Theo1 from lag sums; the derivation in docs/total.md, the interface in total_fast.hpp.
#include "gyrochar/total_fast.hpp"

#include <cmath>
#include <numbers>

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#include <immintrin.h>
#endif

namespace gyrochar {
namespace {

using Index = std::size_t;
double as_double(std::uint64_t v) { return static_cast<double>(v); }

// The FFTs below leave the spectrum in bit-reversed order (forward, decimation in frequency) and
// take it back from there (inverse, decimation in time): no reordering pass, and the blocks that
// fit the cache are finished before the next is touched. Products of spectra pair frequency k with
// n - k: `for_each_mirror_pair` gives both positions.
constexpr Index cached = 2048;  // complex values a block keeps in the first-level cache

// The twiddle table (fft_twiddles): the stages len <= whole_up_to whole, exp(2 pi i k / len) at complex
// index len / 2 + k (1 MB: they stay in the second-level cache); each larger stage, up to P, as two
// short lists from which its twiddle k = c fine + j is one complex product: exp(2 pi i j / len) for
// j < fine, then exp(2 pi i c fine / len) for c < len / (2 fine). 2 fine + len / fine doubles a stage
// instead of len: at P = 2^25 the table is 3.2 MB instead of 537 MB (docs/total.md, "The twiddle
// table"). The stages above `whole_up_to` stream from main memory: they also go two in one pass.
constexpr Index whole_up_to = Index{1} << 16;
constexpr Index fine = 256;
// Complex offset of stage len's lists (len > whole_up_to, a power of two).
Index large_stage(Index len) {
  Index at = whole_up_to;
  for (Index s = 2 * whole_up_to; s < len; s *= 2) at += fine + s / (2 * fine);
  return at;
}

// One stage's butterflies on a block of 2 half values, u its first half, t its second; tw the
// stage's twiddles. Forward (decimation in frequency): u + t, (u - t) w^-k. Inverse (in time):
// u + t w^k, u - t w^k.
void forward_butterflies(double* u, double* t, const double* tw, Index half) {
  for (Index k = 0; k < half; ++k) {
    const double ar = u[2 * k], ai = u[2 * k + 1], br = t[2 * k], bi = t[2 * k + 1];
    const double wr = tw[2 * k], wi = -tw[2 * k + 1];
    u[2 * k] = ar + br, u[2 * k + 1] = ai + bi;
    const double dr = ar - br, di = ai - bi;
    t[2 * k] = dr * wr - di * wi, t[2 * k + 1] = dr * wi + di * wr;
  }
}
void inverse_butterflies(double* u, double* t, const double* tw, Index half) {
  for (Index k = 0; k < half; ++k) {
    const double wr = tw[2 * k], wi = tw[2 * k + 1];
    const double br = t[2 * k] * wr - t[2 * k + 1] * wi, bi = t[2 * k] * wi + t[2 * k + 1] * wr;
    t[2 * k] = u[2 * k] - br, t[2 * k + 1] = u[2 * k + 1] - bi;
    u[2 * k] += br, u[2 * k + 1] += bi;
  }
}

// The twiddles of stage len: from the whole stages (len <= whole_up_to) or as the product of the large
// stage's two lists.
struct StageTwiddles {
  const double* at;
  bool large;
  StageTwiddles(const double* table, Index len)
      : at(len <= whole_up_to ? table + len : table + 2 * large_stage(len)), large(len > whole_up_to) {}
  void get(Index k, double& wr, double& wi) const {
    if (!large) {
      wr = at[2 * k], wi = at[2 * k + 1];
      return;
    }
    const double* c = at + 2 * fine + 2 * (k / fine);
    const double* f = at + 2 * (k % fine);
    wr = c[0] * f[0] - c[1] * f[1], wi = c[0] * f[1] + c[1] * f[0];
  }
};

// Two stages in one pass over memory: stage len, then stage len / 2 on both halves, on the quarters'
// values k, k + q, k + 2q, k + 3q (q = len / 4) together, with the twiddles w1 = w^k and w2 =
// w^(k+q) of stage len and v = w^k of stage len / 2 (forward: already conjugated). The same
// operations on the same values as the two passes, in the same order: the same results, half the
// loads and stores (and, for the large stages, half the traffic to main memory).
struct Quad {
  double w1r, w1i, w2r, w2i, vr, vi;
};
inline void forward_quad(double* u0, Index q, const Quad& t) {
  double* u1 = u0 + 2 * q;
  double* u2 = u1 + 2 * q;
  double* u3 = u2 + 2 * q;
  const double a0r = u0[0] + u2[0], a0i = u0[1] + u2[1], e0r = u0[0] - u2[0], e0i = u0[1] - u2[1];
  const double a1r = u1[0] + u3[0], a1i = u1[1] + u3[1], e1r = u1[0] - u3[0], e1i = u1[1] - u3[1];
  const double a2r = e0r * t.w1r - e0i * t.w1i, a2i = e0r * t.w1i + e0i * t.w1r;
  const double a3r = e1r * t.w2r - e1i * t.w2i, a3i = e1r * t.w2i + e1i * t.w2r;
  u0[0] = a0r + a1r, u0[1] = a0i + a1i;
  const double f0r = a0r - a1r, f0i = a0i - a1i;
  u1[0] = f0r * t.vr - f0i * t.vi, u1[1] = f0r * t.vi + f0i * t.vr;
  u2[0] = a2r + a3r, u2[1] = a2i + a3i;
  const double f1r = a2r - a3r, f1i = a2i - a3i;
  u3[0] = f1r * t.vr - f1i * t.vi, u3[1] = f1r * t.vi + f1i * t.vr;
}
inline void inverse_quad(double* u0, Index q, const Quad& t) {
  double* u1 = u0 + 2 * q;
  double* u2 = u1 + 2 * q;
  double* u3 = u2 + 2 * q;
  const double b0r = u1[0] * t.vr - u1[1] * t.vi, b0i = u1[0] * t.vi + u1[1] * t.vr;
  const double b1r = u3[0] * t.vr - u3[1] * t.vi, b1i = u3[0] * t.vi + u3[1] * t.vr;
  const double a0r = u0[0] + b0r, a0i = u0[1] + b0i, a1r = u0[0] - b0r, a1i = u0[1] - b0i;
  const double a2r = u2[0] + b1r, a2i = u2[1] + b1i, a3r = u2[0] - b1r, a3i = u2[1] - b1i;
  const double c0r = a2r * t.w1r - a2i * t.w1i, c0i = a2r * t.w1i + a2i * t.w1r;
  const double c1r = a3r * t.w2r - a3i * t.w2i, c1i = a3r * t.w2i + a3i * t.w2r;
  u0[0] = a0r + c0r, u0[1] = a0i + c0i, u2[0] = a0r - c0r, u2[1] = a0i - c0i;
  u1[0] = a1r + c1r, u1[1] = a1i + c1i, u3[0] = a1r - c1r, u3[1] = a1i - c1i;
}
// The three twiddles of quarter value k.
Quad quad_twiddles(const StageTwiddles& whole, const StageTwiddles& halves, Index k, Index q, bool forward) {
  Quad t;
  whole.get(k, t.w1r, t.w1i);
  whole.get(k + q, t.w2r, t.w2i);
  halves.get(k, t.vr, t.vi);
  if (forward) t.w1i = -t.w1i, t.w2i = -t.w2i, t.vi = -t.vi;  // forward: exp(-2 pi i k / len)
  return t;
}
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
// The same butterflies on x86-64 with AVX2 (checked at run time), two frequencies k and k + 1 at a
// time, a register holding both complex values. Each lane does the scalar code's operations on
// the same values: the product e w as e_r w_r - e_i w_i and e_i w_r + e_r w_i (the scalar code
// adds the same two products the other way round, and a + b = b + a exactly), negated imaginary
// parts by their sign bit, no fused multiply-add. The same bits as the scalar transforms, about
// twice as fast where the block is in the cache.
#define GYROCHAR_FFT_AVX 1
using Pair = __m256d;
[[gnu::target("avx2")]] inline Pair load_pair(const double* p) { return _mm256_loadu_pd(p); }
[[gnu::target("avx2")]] inline void store_pair(double* p, Pair v) { _mm256_storeu_pd(p, v); }
[[gnu::target("avx2")]] inline Pair conjugated(Pair w) { return _mm256_xor_pd(w, _mm256_set_pd(-0.0, 0.0, -0.0, 0.0)); }
[[gnu::target("avx2")]] inline Pair times(Pair e, Pair w) {
  const Pair re = _mm256_mul_pd(e, _mm256_movedup_pd(w));                               // e_r w_r, e_i w_r
  const Pair im = _mm256_mul_pd(_mm256_permute_pd(e, 0x5), _mm256_permute_pd(w, 0xF));  // e_i w_i, e_r w_i
  return _mm256_addsub_pd(re, im);
}
// StageTwiddles::get of k and k + 1 (k even: for a large stage both share the coarse factor).
[[gnu::target("avx2")]] inline Pair twiddle_pair(const StageTwiddles& s, Index k) {
  if (!s.large) return load_pair(s.at + 2 * k);
  const double* c = s.at + 2 * fine + 2 * (k / fine);
  return times(load_pair(s.at + 2 * (k % fine)), _mm256_broadcast_pd(reinterpret_cast<const __m128d*>(c)));
}
// A twiddle pair as times() uses it, split once for all the blocks it multiplies: w_r in both lanes of
// each value, then w_i.
struct Split {
  Pair re, im;
};
[[gnu::target("avx2")]] inline Split split(Pair w) { return {_mm256_movedup_pd(w), _mm256_permute_pd(w, 0xF)}; }
[[gnu::target("avx2")]] inline Pair times(Pair e, const Split& w) {
  return _mm256_addsub_pd(_mm256_mul_pd(e, w.re), _mm256_mul_pd(_mm256_permute_pd(e, 0x5), w.im));
}
struct QuadPair {
  Split w1, w2, v;
};
[[gnu::target("avx2")]] inline QuadPair quad_pair_of(Pair w1, Pair w2, Pair v, bool forward) {
  if (forward) w1 = conjugated(w1), w2 = conjugated(w2), v = conjugated(v);
  return {split(w1), split(w2), split(v)};
}
[[gnu::target("avx2")]] inline QuadPair quad_twiddle_pair(const StageTwiddles& whole, const StageTwiddles& halves, Index k,
                                                          Index q, bool forward) {
  return quad_pair_of(twiddle_pair(whole, k), twiddle_pair(whole, k + q), twiddle_pair(halves, k), forward);
}
struct Values4 {
  Pair x0, x1, x2, x3;
};
[[gnu::target("avx2")]] inline void forward_quad_values(Values4& u, const QuadPair& t) {
  const Pair a0 = _mm256_add_pd(u.x0, u.x2), e0 = _mm256_sub_pd(u.x0, u.x2);
  const Pair a1 = _mm256_add_pd(u.x1, u.x3), e1 = _mm256_sub_pd(u.x1, u.x3);
  const Pair a2 = times(e0, t.w1), a3 = times(e1, t.w2);
  u = {_mm256_add_pd(a0, a1), times(_mm256_sub_pd(a0, a1), t.v), _mm256_add_pd(a2, a3), times(_mm256_sub_pd(a2, a3), t.v)};
}
[[gnu::target("avx2")]] inline void inverse_quad_values(Values4& u, const QuadPair& t) {
  const Pair b0 = times(u.x1, t.v), b1 = times(u.x3, t.v);
  const Pair a0 = _mm256_add_pd(u.x0, b0), a1 = _mm256_sub_pd(u.x0, b0);
  const Pair c0 = times(_mm256_add_pd(u.x2, b1), t.w1), c1 = times(_mm256_sub_pd(u.x2, b1), t.w2);
  u = {_mm256_add_pd(a0, c0), _mm256_add_pd(a1, c1), _mm256_sub_pd(a0, c0), _mm256_sub_pd(a1, c1)};
}
[[gnu::target("avx2")]] inline void quad_pair(double* u0, Index q, const QuadPair& t, bool forward) {
  Values4 u{load_pair(u0), load_pair(u0 + 2 * q), load_pair(u0 + 4 * q), load_pair(u0 + 6 * q)};
  if (forward) forward_quad_values(u, t);
  else inverse_quad_values(u, t);
  store_pair(u0, u.x0), store_pair(u0 + 2 * q, u.x1), store_pair(u0 + 4 * q, u.x2), store_pair(u0 + 6 * q, u.x3);
}
// The pair of stages 4 and 2 (q = 1: each block's four values adjacent), two blocks at a time:
// register j holds value j of one block and of the next, both with the one twiddle of each kind.
[[gnu::target("avx2")]] void smallest_quads_avx2(double* d, Index n, const double* table, bool forward) {
  const Quad s = quad_twiddles(StageTwiddles(table, 4), StageTwiddles(table, 2), 0, 1, forward);
  const QuadPair t = quad_pair_of(_mm256_setr_pd(s.w1r, s.w1i, s.w1r, s.w1i), _mm256_setr_pd(s.w2r, s.w2i, s.w2r, s.w2i),
                                  _mm256_setr_pd(s.vr, s.vi, s.vr, s.vi), false);  // conjugated already
  for (Index i = 0; i < n; i += 8) {
    double* a = d + 2 * i;
    const Pair a01 = load_pair(a), a23 = load_pair(a + 4), b01 = load_pair(a + 8), b23 = load_pair(a + 12);
    Values4 u{_mm256_permute2f128_pd(a01, b01, 0x20), _mm256_permute2f128_pd(a01, b01, 0x31),
              _mm256_permute2f128_pd(a23, b23, 0x20), _mm256_permute2f128_pd(a23, b23, 0x31)};
    if (forward) forward_quad_values(u, t);
    else inverse_quad_values(u, t);
    store_pair(a, _mm256_permute2f128_pd(u.x0, u.x1, 0x20));
    store_pair(a + 4, _mm256_permute2f128_pd(u.x2, u.x3, 0x20));
    store_pair(a + 8, _mm256_permute2f128_pd(u.x0, u.x1, 0x31));
    store_pair(a + 12, _mm256_permute2f128_pd(u.x2, u.x3, 0x31));
  }
}
// The quarter values k in [k0, k1) (both even) of every block of len = 4q values in d[0 .. n).
[[gnu::target("avx2")]] void quads_avx2(double* d, Index n, Index len, const double* table, bool forward, Index k0,
                                        Index k1) {
  const Index q = len / 4;
  const StageTwiddles whole(table, len), halves(table, len / 2);
  for (Index k = k0; k < k1; k += 2) {
    const QuadPair t = quad_twiddle_pair(whole, halves, k, q, forward);
    for (Index i = 0; i < n; i += len) quad_pair(d + 2 * (i + k), q, t, forward);
  }
}
// One stage's butterflies (half even, whole twiddles).
[[gnu::target("avx2")]] void butterflies_avx2(double* u, double* t, const double* tw, Index half, bool forward) {
  for (Index k = 0; k < half; k += 2) {
    const Pair a = load_pair(u + 2 * k), b = load_pair(t + 2 * k), w = load_pair(tw + 2 * k);
    if (forward) {
      store_pair(u + 2 * k, _mm256_add_pd(a, b));
      store_pair(t + 2 * k, times(_mm256_sub_pd(a, b), conjugated(w)));
    } else {
      const Pair c = times(b, w);
      store_pair(t + 2 * k, _mm256_sub_pd(a, c));
      store_pair(u + 2 * k, _mm256_add_pd(a, c));
    }
  }
}
// Read once libgcc's start-up has read the processor's features (before main); no static of its
// own, which the threads would race to initialize.
inline bool fft_avx2() { return __builtin_cpu_supports("avx2"); }
#endif

// One stage's butterflies, forward or inverse, two frequencies at a time where they can be.
void butterflies(double* u, double* t, const double* tw, Index half, bool forward) {
#ifdef GYROCHAR_FFT_AVX
  if (half % 2 == 0 && fft_avx2()) return butterflies_avx2(u, t, tw, half, forward);
#endif
  if (forward) forward_butterflies(u, t, tw, half);
  else inverse_butterflies(u, t, tw, half);
}

// Stage n and n / 2 over the whole of d, where the block does not fit the cache: the quarter values
// k in [k0, k1) of [0, n / 4) (each k's butterflies touch only its own four values).
void forward_two_stages(double* d, Index n, const double* table, Index k0 = 0, Index k1 = ~Index{0}) {
  const Index q = n / 4;
#ifdef GYROCHAR_FFT_AVX
  if (k0 % 2 == 0 && (k1 >= q || k1 % 2 == 0) && q % 2 == 0 && fft_avx2())
    return quads_avx2(d, n, n, table, true, k0, k1 < q ? k1 : q);
#endif
  const StageTwiddles whole(table, n), halves(table, n / 2);
  for (Index k = k0; k < q && k < k1; ++k) forward_quad(d + 2 * k, q, quad_twiddles(whole, halves, k, q, true));
}
void inverse_two_stages(double* d, Index n, const double* table, Index k0 = 0, Index k1 = ~Index{0}) {
  const Index q = n / 4;
#ifdef GYROCHAR_FFT_AVX
  if (k0 % 2 == 0 && (k1 >= q || k1 % 2 == 0) && q % 2 == 0 && fft_avx2())
    return quads_avx2(d, n, n, table, false, k0, k1 < q ? k1 : q);
#endif
  const StageTwiddles whole(table, n), halves(table, n / 2);
  for (Index k = k0; k < q && k < k1; ++k) inverse_quad(d + 2 * k, q, quad_twiddles(whole, halves, k, q, false));
}

// The stages of a block that fits the cache (n <= cached, whole twiddles), two at a time: stage len
// and len / 2 on every block of len values, each pair of twiddles read once for all the blocks
// (the small stages were loops of one, two or four butterflies a call). With an odd number of
// stages, the largest (forward) or the last (inverse) goes alone.
void forward_cached(double* d, Index n, const double* table) {
  Index len = n;
  Index stages = 0;
  for (Index s = n; s >= 2; s /= 2) ++stages;
  if (stages % 2 == 1) {
    butterflies(d, d + n, table + n, n / 2, true);
    len = n / 2;
  }
  for (; len >= 4; len /= 4) {
    const Index q = len / 4;
#ifdef GYROCHAR_FFT_AVX
    if (q % 2 == 0 && fft_avx2()) {
      quads_avx2(d, n, len, table, true, 0, q);
      continue;
    }
    if (q == 1 && n % 8 == 0 && fft_avx2()) {
      smallest_quads_avx2(d, n, table, true);
      continue;
    }
#endif
    const StageTwiddles whole(table, len), halves(table, len / 2);
    for (Index k = 0; k < q; ++k) {
      const Quad t = quad_twiddles(whole, halves, k, q, true);
      for (Index i = 0; i < n; i += len) forward_quad(d + 2 * (i + k), q, t);
    }
  }
}
void inverse_cached(double* d, Index n, const double* table) {
  Index stages = 0;
  for (Index s = n; s >= 2; s /= 2) ++stages;
  Index len = 4;
  for (Index pairs = stages / 2; pairs > 0; --pairs, len *= 4) {
    const Index q = len / 4;
#ifdef GYROCHAR_FFT_AVX
    if (q % 2 == 0 && fft_avx2()) {
      quads_avx2(d, n, len, table, false, 0, q);
      continue;
    }
    if (q == 1 && n % 8 == 0 && fft_avx2()) {
      smallest_quads_avx2(d, n, table, false);
      continue;
    }
#endif
    const StageTwiddles whole(table, len), halves(table, len / 2);
    for (Index k = 0; k < q; ++k) {
      const Quad t = quad_twiddles(whole, halves, k, q, false);
      for (Index i = 0; i < n; i += len) inverse_quad(d + 2 * (i + k), q, t);
    }
  }
  if (stages % 2 == 1) butterflies(d, d + n, table + n, n / 2, false);
}

void forward_bitreversed(double* d, Index n, const double* table) {
  if (n >= 4 * cached) {  // two stages over the whole, then each quarter
    forward_two_stages(d, n, table);
    for (Index i = 0; i < 4; ++i) forward_bitreversed(d + 2 * i * (n / 4), n / 4, table);
    return;
  }
  if (n > cached) {  // one stage over the whole, then each half while it stays in the cache
    const Index half = n / 2;
    butterflies(d, d + 2 * half, table + 2 * half, half, true);
    forward_bitreversed(d, half, table);
    forward_bitreversed(d + 2 * half, half, table);
    return;
  }
  forward_cached(d, n, table);
}

void inverse_from_bitreversed(double* d, Index n, const double* table) {
  if (n >= 4 * cached) {
    for (Index i = 0; i < 4; ++i) inverse_from_bitreversed(d + 2 * i * (n / 4), n / 4, table);
    inverse_two_stages(d, n, table);
    return;
  }
  if (n > cached) {
    const Index half = n / 2;
    inverse_from_bitreversed(d, half, table);
    inverse_from_bitreversed(d + 2 * half, half, table);
    butterflies(d, d + 2 * half, table + 2 * half, half, false);
    return;
  }
  inverse_cached(d, n, table);
}

// The same transforms as rows for a host's threads (rows.hpp): the two stages over the whole in
// two halves of their quarter values, the four quarters each a row. Each butterfly does the same
// operations on the same values as in turn: the same bits. Below 4 cached, in turn.
struct ParallelFft {
  double* d;
  Index n;
  const double* table;
  bool forward;
  void two_stages(std::size_t half) const {
    const Index q = n / 4, k0 = half == 0 ? 0 : q / 2, k1 = half == 0 ? q / 2 : q;
    if (forward) forward_two_stages(d, n, table, k0, k1);
    else inverse_two_stages(d, n, table, k0, k1);
  }
  void quarter(std::size_t i) const {
    double* at = d + 2 * i * (n / 4);
    if (forward) forward_bitreversed(at, n / 4, table);
    else inverse_from_bitreversed(at, n / 4, table);
  }
};
void transform(double* d, Index n, const double* table, bool forward, const RowRunner* runner) {
  if (runner == nullptr || n < 4 * cached) {
    if (forward) forward_bitreversed(d, n, table);
    else inverse_from_bitreversed(d, n, table);
    return;
  }
  ParallelFft job{d, n, table, forward};
  const Rows stages{[](void* c, std::size_t i) { static_cast<ParallelFft*>(c)->two_stages(i); }, &job};
  const Rows quarters{[](void* c, std::size_t i) { static_cast<ParallelFft*>(c)->quarter(i); }, &job};
  if (forward) run_rows(runner, stages, 2);
  run_rows(runner, quarters, 4);
  if (!forward) run_rows(runner, stages, 2);
}

// Calls f(p, q, k) once for every pair of frequencies k and n - k (k = 0 .. n / 2) of a
// bit-reversed spectrum of length n (a power of two, n >= 2), p and q their positions. With 2^b the
// highest bit of p, k = rev(p) and rev(n - k) = (n - 1) ^ rev(k - 1) = p ^ (2^b - 1): the pairs are
// mirror images within each block [2^b, 2^(b+1)), walked from both ends (two streams, where taking
// k in order would touch the whole spectrum at random); p = 0 (k = 0) and p = 1 (k = n / 2) pair
// with themselves.
template <class F>
void for_each_mirror_pair(Index n, F f) {
  f(Index{0}, Index{0}, Index{0});
  f(Index{1}, Index{1}, n / 2);
  for (Index block = 2; block < n; block *= 2) {
    Index k = n / (2 * block);  // rev(block)
    for (Index p = block; p < block + block / 2; ++p) {
      f(p, 3 * block - 1 - p, k);
      Index bit = n >> 1;  // k = rev(p + 1)
      for (; (k & bit) != 0; bit >>= 1) k ^= bit;
      k ^= bit;
    }
  }
}

// Replaces the (bit-reversed) spectrum of a + i b, length n, by that of corr(a, b) (cross = true:
// c(e) = sum_p a[p] b[p+e], real) or of acf(a) + i acf(b) (cross = false). The spectra of the two
// real sequences: A_k = (Z_k + conj Z_{n-k}) / 2, B_k = (Z_k - conj Z_{n-k}) / (2i).
void combine(double* d, Index n, bool cross) {
  if (n < 2) {
    if (cross) d[1] = 0.0;  // a[0] b[0]
    else d[0] = d[0] * d[0], d[1] = d[1] * d[1];
    return;
  }
  for_each_mirror_pair(n, [d, cross](Index k, Index j, Index) {
    const double zr = d[2 * k], zi = d[2 * k + 1], wr = d[2 * j], wi = d[2 * j + 1];
    const double ar = 0.5 * (zr + wr), ai = 0.5 * (zi - wi), br = 0.5 * (zi + wi), bi = -0.5 * (zr - wr);
    if (cross) {  // conj(A) B; at n - k its conjugate
      const double re = ar * br + ai * bi, im = ar * bi - ai * br;
      d[2 * k] = re, d[2 * k + 1] = im;
      d[2 * j] = re, d[2 * j + 1] = -im;
    } else {  // |A|^2 + i |B|^2, the same at n - k
      const double re = ar * ar + ai * ai, im = br * br + bi * bi;
      d[2 * k] = re, d[2 * k + 1] = im;
      d[2 * j] = re, d[2 * j + 1] = im;
    }
  });
}

// Loads a (and b, or zeros) into the FFT buffer of length n, zero-padded.
void load(double* d, Index n, std::span<const double> a, std::span<const double> b) {
  for (Index p = 0; p < n; ++p) {
    d[2 * p] = p < a.size() ? a[p] : 0.0;
    d[2 * p + 1] = p < b.size() ? b[p] : 0.0;
  }
}

// The circular autocorrelation of the real sequence x zero-padded to P (a power of two, P >= 4),
// times P, left at d[0 .. P): one complex FFT pair of half the length (docs/total.md, "The real
// FFT"). The P values d[2j], d[2j+1] are x[2j] + i x[2j+1]; with Z their half-length spectrum,
// E = (Z_k + conj Z_{n-k}) / 2 and O = (Z_k - conj Z_{n-k}) / (2i) are the spectra of the even and
// the odd values, X_k = E + W^k O and X_{k+n} = E - W^k O (W = exp(-2 pi i / P)) the whole one, and
// the autocorrelation's even and odd values come back together as the inverse of
// (S_k + S_{k+n}) + i W^-k (S_k - S_{k+n}), S = |X|^2. The twiddle table is that of length P. The
// transforms' work goes on `runner` (null: in turn), the same bits either way.
void real_autocorrelation(std::span<const double> x, Index P, double* d, const double* table, const RowRunner* runner) {
  const Index n = P / 2;
  for (Index p = 0; p < P; ++p) d[p] = p < x.size() ? x[p] : 0.0;
  transform(d, n, table, true, runner);
  // From Z_k = z and Z_{n-k} = v: E, O, then S_k, S_{k+n} and the inverse's input y at k; W^k =
  // wr + i wi (the table's cos, -sin of pi k / n).
  auto power = [](double zr, double zi, double vr, double vi, double wr, double wi, double& yr, double& yi) {
    const double er = 0.5 * (zr + vr), ei = 0.5 * (zi - vi), or_ = 0.5 * (zi + vi), oi = -0.5 * (zr - vr);
    const double tr = wr * or_ - wi * oi, ti = wr * oi + wi * or_;  // W^k O
    const double plus = (er + tr) * (er + tr) + (ei + ti) * (ei + ti), minus = (er - tr) * (er - tr) + (ei - ti) * (ei - ti);
    const double diff = plus - minus;  // i W^-k diff, W^-k = conj W^k = wr - i wi
    yr = plus + minus + wi * diff, yi = wr * diff;
  };
  // W^k computed, not read: the table's values at k = rev(p) would be n / 2 scattered reads; the
  // expression of fft_twiddles (the same values), and W^{n-k} = -conj W^k.
  const double step = 2.0 * std::numbers::pi / static_cast<double>(P);
  for_each_mirror_pair(n, [&](Index p, Index q, Index k) {
    const double zr = d[2 * p], zi = d[2 * p + 1], vr = d[2 * q], vi = d[2 * q + 1];
    const double c = std::cos(step * static_cast<double>(k)), si = std::sin(step * static_cast<double>(k));
    double yr, yi, ur, ui;
    power(zr, zi, vr, vi, c, -si, yr, yi);
    power(vr, vi, zr, zi, -c, -si, ur, ui);  // at n - k (not written where q = p)
    d[2 * p] = yr, d[2 * p + 1] = yi;
    if (q != p) d[2 * q] = ur, d[2 * q + 1] = ui;
  });
  transform(d, n, table, false, runner);
}

// Theo1's end correction (docs/total.md): with v every other residual of one end of the record
// (r[2p] or r[2p+1] of the first m, or of the last m reversed), the sum over pairs p <= q with
// p + q < c of v[p] v[q] / (h - (q - p)), h = m / 2: the pairs at even distance whose midpoint lies
// in the end's first half. Both ends at once (the same c): their FFTs share the inverse transform.
// Dyadic split of the triangle: a square of pairs by FFT cross-correlation, two half-size
// triangles recursively. O(c log^2 c).
struct Sums {
  double head = 0.0, tail = 0.0;
  Sums operator+(const Sums& o) const { return {head + o.head, tail + o.tail}; }
};

// The direct blocks' pairs (Triangles::direct): head[a + p] head[b + q] and tail[a + p] tail[b + q]
// weighted k[s - 1 - p + q], each row's pairs four at a time in four running sums (vector lanes),
// the rest in a fifth. On x86-64 with AVX2 the four lanes are one register (no fused multiply-add:
// the same bits), else two.
[[gnu::always_inline]] inline Sums direct_pairs(const double* head, const double* tail, Index a, Index b, Index s,
                                                bool whole, const double* k) {
  using Four = double __attribute__((vector_size(4 * sizeof(double))));
  Four heads = {}, tails = {};
  Sums rest;
  for (Index p = 0; p < s; ++p) {
    const double hp = head[a + p], tp = tail[a + p];
    const double* kp = k + (s - 1 - p);  // kp[q]: the weight of distance (b + q) - (a + p)
    const Index len = whole ? s : s - p;
    Index q = 0;
    for (; q + 4 <= len; q += 4) {
      Four kq, hq, tq;
      __builtin_memcpy(&kq, kp + q, sizeof kq);
      __builtin_memcpy(&hq, &head[b + q], sizeof hq);
      __builtin_memcpy(&tq, &tail[b + q], sizeof tq);
      heads += kq * hp * hq;
      tails += kq * tp * tq;
    }
    for (; q < len; ++q) rest = rest + Sums{kp[q] * hp * head[b + q], kp[q] * tp * tail[b + q]};
  }
  return Sums{(heads[0] + heads[1]) + (heads[2] + heads[3]), (tails[0] + tails[1]) + (tails[2] + tails[3])} + rest;
}
Sums direct_pairs_scalar(const double* head, const double* tail, Index a, Index b, Index s, bool whole, const double* k) {
  return direct_pairs(head, tail, a, b, s, whole, k);
}
#ifdef GYROCHAR_FFT_AVX
[[gnu::target("avx2")]] Sums direct_pairs_avx2(const double* head, const double* tail, Index a, Index b, Index s, bool whole,
                                               const double* k) {
  return direct_pairs(head, tail, a, b, s, whole, k);
}
#endif

struct Triangles {
  std::span<const double> head, tail;  // the two ends' sequences, c values each
  Index c, h;
  Theo1Workspace& w;
  static constexpr Index direct_side = 96;

  double weight(std::ptrdiff_t d) const { return 1.0 / (as_double(h) - static_cast<double>(d < 0 ? -d : d)); }

  // Pairs i in [a, a + s), j in [b, b + s) (s <= direct_side) one by one, the whole square or the
  // triangle (i - a) + (j - b) < s: the weights of the 2 s - 1 distances computed first, each once.
  Sums direct(Index a, Index b, Index s, bool whole) const {
    double k[2 * direct_side - 1];
    const std::ptrdiff_t base = static_cast<std::ptrdiff_t>(b) - static_cast<std::ptrdiff_t>(a) -
                                static_cast<std::ptrdiff_t>(s) + 1;  // distance of k[0]
    for (Index f = 0; f + 1 < 2 * s; ++f) k[f] = weight(base + static_cast<std::ptrdiff_t>(f));
#ifdef GYROCHAR_FFT_AVX
    if (fft_avx2()) return direct_pairs_avx2(head.data(), tail.data(), a, b, s, whole, k);
#endif
    return direct_pairs_scalar(head.data(), tail.data(), a, b, s, whole, k);
  }

  // Pairs i in [a, a + s), j in [b, b + s): the whole square.
  Sums square(Index a, Index b, Index s) const {
    if (s <= direct_side) return direct(a, b, s, true);
    Sums sum;
    const Index n = fft_length(2 * s);
    double* d = w.buffer.data();
    double* e = d + 2 * n;
    load(d, n, head.subspan(a, s), head.subspan(b, s));
    load(e, n, tail.subspan(a, s), tail.subspan(b, s));
    forward_bitreversed(d, n, w.twiddle.data());
    forward_bitreversed(e, n, w.twiddle.data());
    combine(d, n, true);
    combine(e, n, true);
    for (Index k = 0; k < n; ++k) {  // both real correlations in one inverse: head + i tail
      const double re = d[2 * k] - e[2 * k + 1], im = d[2 * k + 1] + e[2 * k];
      d[2 * k] = re, d[2 * k + 1] = im;
    }
    inverse_from_bitreversed(d, n, w.twiddle.data());
    // c(f) at f mod n, f = q - p in (-s, s); the pair's distance is b - a + f
    const auto base = static_cast<std::ptrdiff_t>(b) - static_cast<std::ptrdiff_t>(a);
    for (Index f = 0; f < s; ++f) {
      const double k = weight(base + static_cast<std::ptrdiff_t>(f));
      sum.head += k * d[2 * f], sum.tail += k * d[2 * f + 1];
    }
    for (Index f = 1; f < s; ++f) {
      const double k = weight(base - static_cast<std::ptrdiff_t>(f));
      sum.head += k * d[2 * (n - f)], sum.tail += k * d[2 * (n - f) + 1];
    }
    return {sum.head / as_double(n), sum.tail / as_double(n)};
  }

  // Pairs i in [a, a + s), j in [b, b + s) with (i - a) + (j - b) < s.
  Sums triangle(Index a, Index b, Index s) const {
    if (s <= direct_side) return direct(a, b, s, false);
    const Index big = (s + 1) / 2, small = s / 2;
    return square(a, b, big) + triangle(a, b + big, small) + triangle(a + big, b, small);
  }

  // The pairs p <= q of the triangle p + q < c (each unordered pair once), both ends.
  Sums half() const {
    const Index big = (c + 1) / 2, small = c / 2;
    // The triangle over all ordered pairs: its two off-square parts mirror each other.
    const Sums corner = triangle(0, big, small), full = square(0, 0, big) + corner + corner;
    Sums diagonal;  // p = q, 2 p < c
    for (Index p = 0; 2 * p < c; ++p) diagonal = diagonal + Sums{head[p] * head[p], tail[p] * tail[p]};
    return {0.5 * (full.head + diagonal.head / as_double(h)), 0.5 * (full.tail + diagonal.tail / as_double(h))};
  }
};

// Whether Theo1 at m is defined on the prepared record (even, 2 <= m <= N - 1).
bool theo1_defined(const Theo1Workspace& w, std::uint64_t m) {
  return w.ready && m >= 2 && m % 2 == 0 && m <= w.r.size() - 1;
}

// One parity's two triangles (every other residual, even: r[2p], odd: r[2p+1], of the first m and
// of the last m reversed): their share of the end corrections H + T of docs/total.md.
Sums end_triangles(std::span<const double> r, Index M, bool odd, Theo1Workspace& w) {
  const Index N = r.size(), h = M / 2, c = odd ? h - 1 : h, o = odd ? 1 : 0;
  // The two sequences (2 c values) go in the FFT buffer past the triangles' largest FFTs (4 n
  // doubles, n = fft_length(2 ceil(h / 2)) <= Q = fft_length(h + 1), that of the first square):
  // memory theo1_fast's end autocorrelations have touched already. There is room: h <= (N - 1) / 2,
  // so the buffer's 2 fft_length(2 N) >= 2 fft_length(4 h + 2) = 8 Q >= 4 n + 4 (h + 1).
  const Index used = 4 * fft_length(2 * ((h + 1) / 2));
  const std::span<double> head = w.buffer.subspan(used, c), tail = w.buffer.subspan(used + c, c);
  for (Index p = 0; p < c; ++p) head[p] = r[2 * p + o], tail[p] = r[N - 1 - 2 * p - o];
  return Triangles{head, tail, c, h, w}.half();
}

}  // namespace

std::size_t fft_length(std::size_t n) {
  std::size_t p = 1;
  while (p < n) p *= 2;
  return p;
}

std::size_t fft_twiddle_size(std::size_t P) { return P <= whole_up_to ? 2 * P : 2 * large_stage(2 * P); }

void fft_twiddles(std::span<double> twiddle, std::size_t P) {
  // The whole stages, each contiguous: the largest computed, each smaller one read from the one
  // above it (every other value: two streams).
  const Index top = P < whole_up_to ? P : whole_up_to;
  auto cis = [&](Index at, Index k, Index len) {  // exp(2 pi i k / len) at complex index `at`
    const double a = 2.0 * std::numbers::pi * static_cast<double>(k) / static_cast<double>(len);
    twiddle[2 * at] = std::cos(a), twiddle[2 * at + 1] = std::sin(a);
  };
  for (Index k = 0; 2 * k < top; ++k) cis(top / 2 + k, k, top);
  for (Index len = top / 2; len >= 2; len /= 2)
    for (Index k = 0; 2 * k < len; ++k) {
      twiddle[2 * (len / 2 + k)] = twiddle[2 * (len + 2 * k)];
      twiddle[2 * (len / 2 + k) + 1] = twiddle[2 * (len + 2 * k) + 1];
    }
  for (Index len = 2 * whole_up_to; len <= P; len *= 2) {  // the larger stages' two lists
    const Index at = large_stage(len);
    for (Index j = 0; j < fine; ++j) cis(at + j, j, len);
    for (Index c = 0; c * fine < len / 2; ++c) cis(at + fine + c, c * fine, len);
  }
}

void fft(std::span<double> data, std::size_t n, std::span<const double> twiddle, bool inverse) {
  double* d = data.data();
  auto reorder = [&] {
    for (Index i = 1, j = 0; i < n; ++i) {  // bit-reversed order <-> natural order
      Index bit = n >> 1;
      for (; (j & bit) != 0; bit >>= 1) j ^= bit;
      j ^= bit;
      if (i < j) {
        const double tr = d[2 * i], ti = d[2 * i + 1];
        d[2 * i] = d[2 * j], d[2 * i + 1] = d[2 * j + 1];
        d[2 * j] = tr, d[2 * j + 1] = ti;
      }
    }
  };
  if (inverse) {
    reorder();
    inverse_from_bitreversed(d, n, twiddle.data());
  } else {
    forward_bitreversed(d, n, twiddle.data());
    reorder();
  }
}

void cross_correlation(std::span<const double> a, std::span<const double> b, std::size_t n, Theo1Workspace& w) {
  double* d = w.buffer.data();
  load(d, n, a, b);
  forward_bitreversed(d, n, w.twiddle.data());
  combine(d, n, true);
  inverse_from_bitreversed(d, n, w.twiddle.data());
  for (Index e = 0; e < n; ++e) d[e] = d[2 * e] / as_double(n);  // the real parts, scaled
}

void autocorrelation_sum(std::span<const double> a, std::span<const double> b, std::size_t n, Theo1Workspace& w) {
  // a + i b: the inverse of |Z|^2 is acf(a) + acf(b) plus i times an odd cross term.
  double* d = w.buffer.data();
  load(d, n, a, b);
  forward_bitreversed(d, n, w.twiddle.data());
  for (Index k = 0; k < n; ++k) {
    d[2 * k] = d[2 * k] * d[2 * k] + d[2 * k + 1] * d[2 * k + 1];
    d[2 * k + 1] = 0.0;
  }
  inverse_from_bitreversed(d, n, w.twiddle.data());
  for (Index e = 0; e < n; ++e) d[e] = d[2 * e] / as_double(n);
}

void ends_correlations(std::span<const double> a, std::span<const double> b, std::size_t first, std::size_t n,
                       Theo1Workspace& w) {
  // Two spectra: of a + i b and of their first values. Per pair of frequencies k, n - k the four real
  // sequences' spectra (as in `combine`), then S = |A|^2 + |B|^2 (real, even) and C = conj(A_first) A
  // + conj(B_first) B (the spectrum of a real correlation: C at n - k is conj C), and one inverse of
  // S + i C: both real results at once.
  double* d = w.buffer.data();
  double* e = d + 2 * n;
  load(d, n, a, b);
  load(e, n, a.first(first), b.first(first));
  forward_bitreversed(d, n, w.twiddle.data());
  forward_bitreversed(e, n, w.twiddle.data());
  auto split = [](const double* z, const double* v, double(&s)[4]) {  // A (re, im), B (re, im) at k
    s[0] = 0.5 * (z[0] + v[0]), s[1] = 0.5 * (z[1] - v[1]), s[2] = 0.5 * (z[1] + v[1]), s[3] = -0.5 * (z[0] - v[0]);
  };
  for_each_mirror_pair(n, [d, e, &split](Index p, Index q, Index) {
    double whole[4], head[4];
    split(d + 2 * p, d + 2 * q, whole);
    split(e + 2 * p, e + 2 * q, head);
    const double S = whole[0] * whole[0] + whole[1] * whole[1] + whole[2] * whole[2] + whole[3] * whole[3];
    const double cr = head[0] * whole[0] + head[1] * whole[1] + head[2] * whole[2] + head[3] * whole[3];
    const double ci = head[0] * whole[1] - head[1] * whole[0] + head[2] * whole[3] - head[3] * whole[2];
    d[2 * p] = S - ci, d[2 * p + 1] = cr;  // S + i C at k; at n - k S + i conj C (the same where q = p)
    d[2 * q] = S + ci, d[2 * q + 1] = cr;
  });
  inverse_from_bitreversed(d, n, w.twiddle.data());
}

namespace {

// Least-squares quadratic of d = x - x[0] in the orthogonal basis 1, t, t^2 - mean(t^2) (t centred,
// symmetric), fitted and removed in long double: the residual r then carries the rounding of its
// own size, not that of the phase values (a 1e-3 ramp over 1e-12 noise keeps its noise). Returns
// the quadratic's coefficient of t^2.
template <class T>
double remove_quadratic(std::span<const T> x, std::span<double> r) {
  const Index N = x.size();
  using Wide = long double;
  auto d = [&](Index i) { return static_cast<Wide>(x[i]) - static_cast<Wide>(x[0]); };
  const Wide c = 0.5L * static_cast<Wide>(N - 1);
  Wide t2 = 0, p22 = 0, mean = 0, dt = 0, dp = 0;
  for (Index i = 0; i < N; ++i) t2 += (static_cast<Wide>(i) - c) * (static_cast<Wide>(i) - c);
  const Wide mt2 = t2 / static_cast<Wide>(N);
  for (Index i = 0; i < N; ++i) {
    const Wide t = static_cast<Wide>(i) - c, p = t * t - mt2, di = d(i);
    mean += di, dt += di * t, dp += di * p, p22 += p * p;
  }
  mean /= static_cast<Wide>(N);
  const Wide a1 = dt / t2, a2 = p22 > 0 ? dp / p22 : 0.0L;
  for (Index i = 0; i < N; ++i) {
    const Wide t = static_cast<Wide>(i) - c;
    r[i] = static_cast<double>(d(i) - mean - a1 * t - a2 * (t * t - mt2));
  }
  return static_cast<double>(a2);
}

}  // namespace

std::size_t theo1_workspace_size(std::size_t n_phase) {
  const std::size_t P = fft_length(2 * n_phase);
  return 4 * n_phase + 2 + fft_twiddle_size(P) + 2 * P;
}

Theo1Workspace theo1_prepare(PhaseSpan x, std::span<double> work, const RowRunner* runner) {
  const Index N = x.size();
  Theo1Workspace w;
  if (N < 3 || work.size() < theo1_workspace_size(N)) return w;
  w.P = fft_length(2 * N);
  Index at = 0;
  auto take = [&](Index count) {
    const std::span<double> s = work.subspan(at, count);
    at += count;
    return s;
  };
  w.r = take(N), w.s1 = take(N + 1), w.s2 = take(N + 1), w.ac = take(N);
  w.twiddle = take(fft_twiddle_size(w.P)), w.buffer = take(2 * w.P);
  w.curvature = x.visit([&](auto v) { return remove_quadratic(v, w.r); });
  w.s1[0] = w.s2[0] = 0.0;
  for (Index i = 0; i < N; ++i) {
    w.s1[i + 1] = w.s1[i] + w.r[i];
    w.s2[i + 1] = w.s2[i] + w.r[i] * w.r[i];
  }
  fft_twiddles(w.twiddle, w.P);
  real_autocorrelation(w.r, w.P, w.buffer.data(), w.twiddle.data(), runner);
  const double* d = w.buffer.data();
  for (Index lag = 0; lag < N; ++lag) w.ac[lag] = d[lag] / as_double(w.P);
  w.ready = true;
  return w;
}

void theo1_piece(Theo1Workspace& w, std::uint64_t m, int piece, Theo1Pieces& out) {
  if (!theo1_defined(w, m)) return;
  const Index N = w.r.size(), M = static_cast<Index>(m);
  if (piece == 1 || piece == 2) {
    // The product r[i+k] r[i+m-k] over i in [k, k + L) is the whole record's lag sum less the pairs
    // at either end (midpoint in the first or last m / 2 points), weighted 1 / k: the triangles.
    const Sums t = end_triangles(w.r, M, piece == 2, w);
    double* to = piece == 1 ? out.even : out.odd;
    to[0] = t.head, to[1] = t.tail;
    return;
  }
  const Index h = M / 2, L = N - M;
  const std::span<const double> r = w.r, s1 = w.s1, s2 = w.s2, R = w.ac;
  // The autocorrelations of the first and the last m residuals at lags below m: one FFT pair.
  const Index n = fft_length(2 * M);
  double* d = w.buffer.data();
  load(d, n, r.first(M), {});
  for (Index p = 0; p < M; ++p) d[2 * p + 1] = r[N - M + p];
  forward_bitreversed(d, n, w.twiddle.data());
  combine(d, n, false);
  inverse_from_bitreversed(d, n, w.twiddle.data());
  auto first = [&](Index lag) { return d[2 * lag] / as_double(n); };
  auto last = [&](Index lag) { return d[2 * lag + 1] / as_double(n); };
  // Sums of r and r^2 over the L start points shifted by s.
  auto sum1 = [&](Index s) { return s1[s + L] - s1[s]; };
  auto sum2 = [&](Index s) { return s2[s + L] - s2[s]; };
  double sum = 0.0;
  for (Index k = 1; k <= h; ++k) {
    // sum_i (r[i] - r[i+k] - r[i+m-k] + r[i+m])^2 over i < L: squares, then the six products as
    // lag sums over i in [s, s + L), each the whole record's less its ends (docs/total.md).
    const double squares = sum2(0) + sum2(k) + sum2(M - k) + sum2(M);
    const double products = -(R[k] - last(k)) - (R[M - k] - last(M - k)) + R[M] + R[M - 2 * k] - (R[M - k] - first(M - k)) -
                            (R[k] - first(k));
    const double gamma = 2.0 * w.curvature * as_double(k) * as_double(M - k);  // the quadratic's term
    const double linear = sum1(0) - sum1(k) - sum1(M - k) + sum1(M);
    sum += (squares + 2.0 * products + 2.0 * gamma * linear + as_double(L) * gamma * gamma) / as_double(k);
  }
  out.sums = sum;
}

TotalVariance theo1_from_pieces(const Theo1Workspace& w, std::uint64_t m, double tau0_s, const Theo1Pieces& p) {
  if (!theo1_defined(w, m) || !(tau0_s > 0)) return {};
  const Index L = w.r.size() - static_cast<Index>(m);
  const double ends = p.even[0] + p.even[1] + p.odd[0] + p.odd[1];
  const double sum = p.sums - 2.0 * ends, tau = as_double(m) * tau0_s;
  return {sum / (0.75 * as_double(L) * tau * tau), static_cast<std::uint64_t>(L) * (m / 2), 1};
}

TotalVariance theo1_fast(Theo1Workspace& w, std::uint64_t m, double tau0_s) {
  Theo1Pieces p;
  for (int piece = 0; piece < theo1_pieces; ++piece) theo1_piece(w, m, piece, p);
  return theo1_from_pieces(w, m, tau0_s, p);
}

TheoBiasRatio theo_bias_ratio_fast(PhaseSpan x, Theo1Workspace& w, double tau0_s, std::uint64_t ratio_taus) {
  const std::uint64_t N = x.size();
  if (N < 24 || ratio_taus < 2 || !(tau0_s > 0) || !w.ready || w.r.size() != N) return {};
  const std::uint64_t last = theo_bias_last(N);
  const std::uint64_t count = last + 1 <= ratio_taus ? last + 1 : ratio_taus;
  TheoBiasRatio out;
  out.defined = last + 1;
  out.exact = count == last + 1;
  double sum = 0.0;
  for (std::uint64_t j = 0; j < count; ++j) {
    const std::uint64_t i = theo_bias_index(j, count, last);
    const TotalVariance t = theo1_fast(w, 12 + 4 * i, tau0_s);
    const TotalVariance a = oavar(x, 9 + 3 * i, tau0_s, 1);
    if (t.n == 0 || a.n == 0 || !(t.var > 0)) return {};
    sum += a.var / t.var;
  }
  out.ratio = sum / as_double(count);
  out.taus = count;
  return out;
}

}  // namespace gyrochar
