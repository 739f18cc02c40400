// The total and Theo family; definitions, costs and the decimated variants in total.hpp.
#include "gyrochar/total.hpp"

#include <cmath>

namespace gyrochar {
namespace {

using Index = std::size_t;  // indices into the record (32 bits on the MCU builds)
double as_double(std::uint64_t v) { return static_cast<double>(v); }
Index as_index(std::uint64_t v) { return static_cast<Index>(v); }  // after checking v <= a span's size

// Theo1's terms (x_i - x_{i+k} - x_{i+M-k} + x_{i+M})^2 / k of the starts i = 0, step, ... < end
// and the k of one block [k0, k0 + len), w[j] = 1 / (k0 + j): eight k a step in two vectors of four
// (two lanes a register on SSE2 and NEON, four with AVX2, whose fused multiply-adds round once
// where the others round twice), x_{i+M-k} read backwards. Integers are converted as they load.
using Lanes = double __attribute__((vector_size(32)));
inline constexpr Index theo1_block = 8192;  // 64 KB of weights: long runs of each start's values
// (No vector is passed by value or returned: that would change with the target's ABI.)
[[gnu::always_inline]] inline void load(Lanes& v, const double* p) { __builtin_memcpy(&v, p, sizeof v); }
template <class T>
[[gnu::always_inline]] inline void load(Lanes& v, const T* p) {
  v = Lanes{static_cast<double>(p[0]), static_cast<double>(p[1]), static_cast<double>(p[2]), static_cast<double>(p[3])};
}
template <class T>
[[gnu::always_inline]] inline void load_backwards(Lanes& v, const T* p) {
  v = Lanes{static_cast<double>(p[3]), static_cast<double>(p[2]), static_cast<double>(p[1]), static_cast<double>(p[0])};
}
template <class T>
[[gnu::always_inline]] inline double theo1_terms(const T* x, Index end, Index step, Index M, Index k0, Index len,
                                                 const double* w) {
  double sum = 0.0;
  for (Index i = 0; i < end; i += step) {
    const T* p = x + i;
    const double first = static_cast<double>(p[0]), last = static_cast<double>(p[M]);
    Lanes s0 = {}, s1 = {};
    Index j = 0;
    for (; j + 8 <= len; j += 8) {
      const Index k = k0 + j;
      Lanes a0, a1, b0, b1, w0, w1;
      load(a0, p + k);
      load(a1, p + k + 4);
      load_backwards(b0, p + M - k - 3);
      load_backwards(b1, p + M - k - 7);
      load(w0, w + j);
      load(w1, w + j + 4);
      const Lanes t0 = ((first - a0) - b0) + last, t1 = ((first - a1) - b1) + last;
      s0 += t0 * t0 * w0;
      s1 += t1 * t1 * w1;
    }
    const Lanes s = s0 + s1;
    double inner = (s[0] + s[1]) + (s[2] + s[3]);
    for (; j < len; ++j) {
      const Index k = k0 + j;
      const double t = ((first - static_cast<double>(p[k])) - static_cast<double>(p[M - k])) + last;
      inner += t * t * w[j];
    }
    sum += inner;
  }
  return sum;
}
// The same terms in another order, for starts far apart (step >= theo1_block / 2, where one start's
// block shares nothing with the next one's): a span of at most theo1_span positions p = i + k at a
// time, every start whose run of k reaches the span summing its terms there. Each start's x_{i+k}
// then come from the cache, read by the one before. The backward values x_{i+M-k} of start i at p
// are those of start i + step at p + 2 step, so the spans go in that order: the positions cut into
// periods of 2 step, the spans at the same offset of every period one after the other. Of a span's
// S / 2 backward runs (S = M / step) all but one were read by the span before: a span reads two
// new runs (one forward, one backward) for its S / 2 runs of terms, about 4 / S new values a term
// where it was 1 + 2 / S (measured in BENCHMARKS.md). The weights
// are divided where they are used, one division for 1 / k = (k + 4) r and 1 / (k + 4) = k r,
// r = 1 / (k (k + 4)): three roundings, each weight within 1.5 ulp of the quotient.
inline constexpr Index theo1_span = 16384;
template <class T>
[[gnu::always_inline]] inline double theo1_run(const T* p, Index M, Index k0, Index k1) {
  const double first = static_cast<double>(p[0]), last = static_cast<double>(p[M]);
  Lanes s0 = {}, s1 = {};
  Lanes k = {static_cast<double>(k0), static_cast<double>(k0 + 1), static_cast<double>(k0 + 2), static_cast<double>(k0 + 3)};
  Index j = k0;
  for (; j + 7 <= k1; j += 8) {
    Lanes a0, a1, b0, b1;
    load(a0, p + j);
    load(a1, p + j + 4);
    load_backwards(b0, p + M - j - 3);
    load_backwards(b1, p + M - j - 7);
    const Lanes k4 = k + 4.0, r = 1.0 / (k * k4), w0 = k4 * r, w1 = k * r;
    k += 8.0;
    const Lanes t0 = ((first - a0) - b0) + last, t1 = ((first - a1) - b1) + last;
    s0 += t0 * t0 * w0;
    s1 += t1 * t1 * w1;
  }
  const Lanes s = s0 + s1;
  double inner = (s[0] + s[1]) + (s[2] + s[3]);
  for (; j <= k1; ++j) {
    const double t = ((first - static_cast<double>(p[j])) - static_cast<double>(p[M - j])) + last;
    inner += t * t * (1.0 / static_cast<double>(j));
  }
  return inner;
}
#if defined(__x86_64__)
// The same runs eight lanes a register (AVX-512): thirty-two k a step in four vectors, one
// division for their four weights, r = 1 / (A B) with A = k (k + 8), B = (k + 16)(k + 24): 1 / k =
// (k + 8) B r, 1 / (k + 8) = k B r, 1 / (k + 16) = (k + 24) A r, 1 / (k + 24) = (k + 16) A r; at
// most six roundings, each weight within 3 ulp of the quotient. (On Intel's cores a division of
// eight lanes takes as long as two of four: one for four weights keeps it off the path.) A run's
// last k (fewer than 32) go four lanes at a time as above.
using Lanes8 = double __attribute__((vector_size(64)));
template <class T>
[[gnu::always_inline]] inline void load(Lanes8& v, const T* p) {
  v = Lanes8{static_cast<double>(p[0]), static_cast<double>(p[1]), static_cast<double>(p[2]), static_cast<double>(p[3]),
             static_cast<double>(p[4]), static_cast<double>(p[5]), static_cast<double>(p[6]), static_cast<double>(p[7])};
}
template <class T>
[[gnu::always_inline]] inline void load_backwards(Lanes8& v, const T* p) {
  v = Lanes8{static_cast<double>(p[7]), static_cast<double>(p[6]), static_cast<double>(p[5]), static_cast<double>(p[4]),
             static_cast<double>(p[3]), static_cast<double>(p[2]), static_cast<double>(p[1]), static_cast<double>(p[0])};
}
template <class T>
[[gnu::target("avx512f,avx512dq,avx2,fma")]] double theo1_run_avx512(const T* p, Index M, Index k0, Index k1) {
  const double first = static_cast<double>(p[0]), last = static_cast<double>(p[M]);
  Lanes8 s0 = {}, s1 = {}, s2 = {}, s3 = {};
  Lanes8 k = {0, 1, 2, 3, 4, 5, 6, 7};
  k += static_cast<double>(k0);
  Index j = k0;
  for (; j + 31 <= k1; j += 32) {
    Lanes8 a0, a1, a2, a3, b0, b1, b2, b3;
    load(a0, p + j);
    load(a1, p + j + 8);
    load(a2, p + j + 16);
    load(a3, p + j + 24);
    load_backwards(b0, p + M - j - 7);
    load_backwards(b1, p + M - j - 15);
    load_backwards(b2, p + M - j - 23);
    load_backwards(b3, p + M - j - 31);
    const Lanes8 k8 = k + 8.0, k16 = k + 16.0, k24 = k + 24.0, A = k * k8, B = k16 * k24;
    const Lanes8 r = 1.0 / (A * B), Br = B * r, Ar = A * r;
    const Lanes8 t0 = ((first - a0) - b0) + last, t1 = ((first - a1) - b1) + last;
    const Lanes8 t2 = ((first - a2) - b2) + last, t3 = ((first - a3) - b3) + last;
    s0 += t0 * t0 * (k8 * Br);
    s1 += t1 * t1 * (k * Br);
    s2 += t2 * t2 * (k24 * Ar);
    s3 += t3 * t3 * (k16 * Ar);
    k += 32.0;
  }
  const Lanes8 s = (s0 + s1) + (s2 + s3);
  const double inner = ((s[0] + s[1]) + (s[2] + s[3])) + ((s[4] + s[5]) + (s[6] + s[7]));
  return j <= k1 ? inner + theo1_run(p, M, j, k1) : inner;
}
#endif
template <auto run, class T>  // run: theo1_run or theo1_run_avx512
[[gnu::always_inline]] inline double theo1_spans(const T* x, Index end, Index step, Index M) {
  const Index h = M / 2, period = 2 * step, stop = end + h;  // the positions p in [1, stop)
  double sum = 0.0;
  for (Index offset = 0; offset < period; offset += theo1_span) {
    const Index width = period - offset < theo1_span ? period - offset : theo1_span;
    for (Index p0 = 1 + offset; p0 < stop; p0 += period) {
      const Index p1 = p0 + width - 1;  // the span [p0, p1]
      // The starts i (multiples of step) whose run [i + 1, i + h] reaches the span.
      for (Index i = p0 > h ? (p0 - h + step - 1) / step * step : 0; i < end && i < p1; i += step) {
        const Index k0 = p0 > i ? p0 - i : 1, k1 = p1 - i < h ? p1 - i : h;
        sum += run(x + i, M, k0, k1);
      }
    }
  }
  return sum;
}
#if defined(__x86_64__)
template <class T>
[[gnu::target("avx512f,avx512dq,avx2,fma")]] double theo1_spans_avx512(const T* x, Index end, Index step, Index M) {
  return theo1_spans<theo1_run_avx512<T>>(x, end, step, M);
}
template <class T>
[[gnu::target("avx2,fma")]] double theo1_terms_avx2(const T* x, Index end, Index step, Index M, Index k0, Index len,
                                                    const double* w) {
  return theo1_terms(x, end, step, M, k0, len, w);
}
template <class T>
[[gnu::target("avx2,fma")]] double theo1_spans_avx2(const T* x, Index end, Index step, Index M) {
  return theo1_spans<theo1_run<T>>(x, end, step, M);
}
#endif
// TOTVAR's terms (x_{i-M} - 2 x_i + x_{i+M})^2 of i in [from, to), none of them reflected: eight a
// step in two vectors of four (two lanes a register on SSE2 and NEON, four with AVX2, whose fused
// multiply-adds round once where the others round twice).
template <class T>
[[gnu::always_inline]] inline double totvar_terms(const T* x, Index from, Index to, Index M) {
  Lanes s0 = {}, s1 = {};
  Index i = from;
  for (; i + 8 <= to; i += 8) {
    Lanes a0, a1, b0, b1, c0, c1;
    load(a0, x + i - M);
    load(a1, x + i - M + 4);
    load(b0, x + i);
    load(b1, x + i + 4);
    load(c0, x + i + M);
    load(c1, x + i + M + 4);
    const Lanes t0 = (a0 - 2.0 * b0) + c0, t1 = (a1 - 2.0 * b1) + c1;
    s0 += t0 * t0;
    s1 += t1 * t1;
  }
  const Lanes s = s0 + s1;
  double sum = (s[0] + s[1]) + (s[2] + s[3]);
  for (; i < to; ++i) {
    const double t = (static_cast<double>(x[i - M]) - 2.0 * static_cast<double>(x[i])) + static_cast<double>(x[i + M]);
    sum += t * t;
  }
  return sum;
}
#if defined(__x86_64__)
template <class T>
[[gnu::target("avx2,fma")]] double totvar_terms_avx2(const T* x, Index from, Index to, Index M) {
  return totvar_terms(x, from, to, M);
}
#endif
template <class T>
double totvar_interior(const T* x, Index from, Index to, Index M) {
#if defined(__x86_64__)
  if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) return totvar_terms_avx2(x, from, to, M);
#endif
  return totvar_terms(x, from, to, M);
}

template <class T>
double theo1_block_terms(const T* x, Index end, Index step, Index M, Index k0, Index len, const double* w) {
#if defined(__x86_64__)
  if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) return theo1_terms_avx2(x, end, step, M, k0, len, w);
#endif
  return theo1_terms(x, end, step, M, k0, len, w);
}
template <class T>
double theo1_span_terms(const T* x, Index end, Index step, Index M) {
#if defined(__x86_64__)
  if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq")) return theo1_spans_avx512(x, end, step, M);
  if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) return theo1_spans_avx2(x, end, step, M);
#endif
  return theo1_spans<theo1_run<T>>(x, end, step, M);
}

// The record's values seen through a sequence: v(k), k in [0, size).
template <class T>
struct Values {  // x itself
  std::span<const T> v;
  Index size() const { return v.size(); }
  double operator()(Index k) const { return static_cast<double>(v[k]); }
};
template <class T>
struct Increments {  // x[(k+1) b] - x[k b]: frequencies summed over blocks of b samples, times tau0
  std::span<const T> x;
  Index b;
  Index size() const { return (x.size() - 1) / b; }
  double operator()(Index k) const { return static_cast<double>(x[(k + 1) * b]) - static_cast<double>(x[k * b]); }
};
struct Window {  // a window of block sums: v(k) for k from `from` on
  const double* sums;
  Index from;
  double operator()(Index k) const { return sums[k - from]; }
};

// The kernel MTOTVAR and HTOTVAR share: over every run of 3S consecutive values v (the
// sub-sequences) starting in [n0, n1), remove the line through the means of its halves, mirror it at
// both ends to 9S values e, and add the average of z_k^2 = (E[k+3S] - 3E[k+2S] + 3E[k+S] - E[k])^2
// over k in [0, 6S) to `sum`, E the prefix sums of e (a range at a time, the same additions in the
// same order as all at once). E (scratch) holds 9S + 1 prefix sums. O(15 S) per sub-sequence.
template <class Seq>
void total_kernel(const Seq& v, Index S, Index n0, Index n1, std::span<double> E, double& sum) {
  const Index len = 3 * S;
  const Index half = len / 2;                // points in each half; the middle one of an odd run is in neither
  const double run = as_double(len - half);  // distance between the centres of the halves
  for (Index n = n0; n < n1; ++n) {
    double first = 0.0, second = 0.0;
    for (Index t = 0; t < half; ++t) {
      first += v(n + t);
      second += v(n + len - half + t);
    }
    const double slope = (second - first) / as_double(half) / run;
    // Detrended values, centred (a constant does not change z but would cost precision):
    // u_t = v(n + t) - slope (t - c) - mean, with c the run's centre.
    const double centre = 0.5 * as_double(len - 1);
    const double mean = (first + second) / as_double(2 * half);  // = the mean of the line at the centre
    // E over the extension [u reversed, u, u reversed].
    E[0] = 0.0;
    for (Index t = 0; t < len; ++t) {
      const Index s = len - 1 - t;
      E[t + 1] = E[t] + (v(n + s) - slope * (as_double(s) - centre) - mean);
    }
    for (Index t = 0; t < len; ++t) E[len + t + 1] = E[len + t] + (v(n + t) - slope * (as_double(t) - centre) - mean);
    for (Index t = 0; t < len; ++t) E[2 * len + t + 1] = E[2 * len + t] + (E[t + 1] - E[t]);
    // z over [0, 6S) is symmetric: the extension is even about -1/2 and the modified Allan filter
    // about its centre, so z_k = z_{3S-k} on [0, 3S] and z_k = z_{9S-k} on (3S, 6S). Each pair once,
    // twice weighted, a term that is its own partner once: half the work.
    auto z2 = [&](Index k) {
      const double z = E[k + len] - 3.0 * E[k + 2 * S] + 3.0 * E[k + S] - E[k];
      return z * z;
    };
    double acc = 0.0;
    for (Index k = 0; 2 * k < len; ++k) acc += 2.0 * z2(k);
    if (len % 2 == 0) acc += z2(len / 2);
    for (Index k = len + 1; 2 * k < 3 * len; ++k) acc += 2.0 * z2(k);
    if (len % 2 == 0) acc += z2(3 * len / 2);
    sum += acc / as_double(2 * len);
  }
}

bool block_ok(std::uint64_t block, std::uint64_t m) {
  return block >= 1 && m >= 1 && m % block == 0 && (block == 1 || (m / block) % 2 == 0);
}

template <class T>
TotalVariance totvar_of(std::span<const T> x, std::uint64_t m, double tau0_s, const double* interior) {
  const Index N = x.size();
  if (N < 3 || m < 1 || m > N - 1 || !(tau0_s > 0)) return {};
  const Index M = as_index(m), last = N - 1;
  auto at = [&](Index i) { return static_cast<double>(x[i]); };
  // x* by odd reflection about the end points; i - M and i + M stay within (-(N-1), 2(N-1)).
  auto left = [&](Index i) { return i >= M ? at(i - M) : 2.0 * at(0) - at(M - i); };
  auto right = [&](Index i) { return i + M <= last ? at(i + M) : 2.0 * at(last) - at(2 * last - i - M); };
  auto terms = [&](Index from, Index to) {
    double sum = 0.0;
    for (Index i = from; i < to; ++i) {
      const double t = left(i) - 2.0 * at(i) + right(i);
      sum += t * t;
    }
    return sum;
  };
  // The terms that reflect at the start (i < M), those in between in vector lanes, those that
  // reflect at the end (i > last - M).
  double sum = 0.0;
  if (M <= last - M) {
    sum = terms(1, M) + (interior ? *interior : totvar_interior(x.data(), M, last - M + 1, M));
    sum += terms(last - M + 1, last);
  } else {
    sum = terms(1, last);
  }
  const double tau = as_double(m) * tau0_s;
  return {sum / (2.0 * tau * tau * as_double(N - 2)), N - 2, 1};
}

template <class T>
TotalVariance mtotvar_of(std::span<const T> x, std::uint64_t block, std::uint64_t m, double tau0_s,
                         std::span<double> scratch) {
  if (!block_ok(block, m) || !(tau0_s > 0)) return {};
  const Index S = as_index(m / block), b = as_index(block), len = 3 * S, count = x.size() / b;
  if (count < len || scratch.size() < total_scratch_size(m, block)) return {};
  const Index starts = count - len + 1;
  const std::span<double> E = scratch.first(9 * S + 1);
  double sum = 0.0;
  if (b == 1) {
    total_kernel(Values<T>{x}, S, 0, starts, E, sum);
  } else {
    // The block sums of total_window starts at a time, with the 3S - 1 more the last one reaches.
    double* sums = scratch.data() + E.size();
    for (Index n0 = 0; n0 < starts; n0 += total_window) {
      const Index n1 = starts - n0 < total_window ? starts : n0 + total_window;
      for (Index k = n0; k < n1 + len - 1; ++k) {
        double s = 0.0;
        for (Index t = 0; t < b; ++t) s += static_cast<double>(x[k * b + t]);
        sums[k - n0] = s;
      }
      total_kernel(Window{sums, n0}, S, n0, n1, E, sum);
    }
  }
  const double tau = as_double(m) * tau0_s;
  return {sum / (as_double(starts) * 2.0 * as_double(m) * as_double(m) * tau * tau), starts, block};
}

template <class T>
TotalVariance htotvar_of(std::span<const T> x, std::uint64_t block, std::uint64_t m, double tau0_s,
                         std::span<double> scratch) {
  const Index N = x.size();
  if (!block_ok(block, m) || !(tau0_s > 0) || N < 4 || block >= N) return {};
  if (m == 1) {  // the overlapping Hadamard variance (SP 1065 eq. 18)
    auto at = [&](Index i) { return static_cast<double>(x[i]); };
    double sum = 0.0;
    for (Index i = 0; i + 3 < N; ++i) {
      const double h = at(i + 3) - 3.0 * at(i + 2) + 3.0 * at(i + 1) - at(i);
      sum += h * h;
    }
    return {sum / (6.0 * as_double(N - 3) * tau0_s * tau0_s), N - 3, 1};
  }
  const Index S = as_index(m / block);
  const Increments<T> y{x, as_index(block)};
  if (y.size() < 3 * S || scratch.size() < total_scratch_size(m, block)) return {};
  const Index starts = y.size() - 3 * S + 1;
  double sum = 0.0;
  total_kernel(y, S, 0, starts, scratch, sum);
  // z sums m frequencies times tau0: H = z / (m tau0).
  const double scale = as_double(m) * tau0_s;
  return {sum / (as_double(starts) * 6.0 * scale * scale), starts, block};
}

template <class T>
TotalVariance theo1_of(std::span<const T> x, std::uint64_t m, double tau0_s, std::uint64_t stride) {
  const Index N = x.size();
  if (N < 3 || m < 2 || m % 2 != 0 || m > N - 1 || stride < 1 || !(tau0_s > 0)) return {};
  const Index M = as_index(m), h = M / 2, step = stride < N ? as_index(stride) : N;
  const std::uint64_t starts = (N - M + step - 1) / step;
  const double tau = as_double(m) * tau0_s;  // the definition's scale (tau is 0.75 of it)
  auto variance = [&](double sum) {
    return TotalVariance{sum / (0.75 * as_double(starts) * tau * tau), starts * h, stride};
  };
  if (2 * step >= theo1_block) return variance(theo1_span_terms(x.data(), N - M, step, M));  // starts far apart
  // The weights 1/k a block of k at a time (one division each), every start's terms of that block.
  // (64 KB of stack: an offline estimator; the board does not call it.)
  alignas(32) double weight[theo1_block];
  double sum = 0.0;
  for (Index k0 = 1; k0 <= h; k0 += theo1_block) {
    const Index len = h + 1 - k0 < theo1_block ? h + 1 - k0 : theo1_block;
    for (Index j = 0; j < len; ++j) weight[j] = 1.0 / static_cast<double>(k0 + j);
    sum += theo1_block_terms(x.data(), N - M, step, M, k0, len, weight);
  }
  return variance(sum);
}

template <class T>
TotalVariance oavar_of(std::span<const T> x, std::uint64_t m, double tau0_s, std::uint64_t stride) {
  const Index N = x.size();
  if (m < 1 || N < 2 * m + 1 || stride < 1 || !(tau0_s > 0)) return {};
  const Index M = as_index(m), step = stride < N ? as_index(stride) : N;
  auto at = [&](Index i) { return static_cast<double>(x[i]); };
  double sum = 0.0;
  std::uint64_t n = 0;
  for (Index i = 0; i + 2 * M < N; i += step, ++n) {
    const double t = at(i + 2 * M) - 2.0 * at(i + M) + at(i);
    sum += t * t;
  }
  const double tau = as_double(m) * tau0_s;
  return {sum / (2.0 * as_double(n) * tau * tau), n, stride};
}

}  // namespace

TotalVariance totvar(PhaseSpan x, std::uint64_t m, double tau0_s) {
  return x.visit([&](auto v) { return totvar_of(v, m, tau0_s, nullptr); });
}

TotalVariance totvar_from_interior(PhaseSpan x, std::uint64_t m, double tau0_s, double interior) {
  const std::uint64_t N = x.size();
  if (N < 3 || m < 1 || 2 * m > N - 1 || !(interior >= 0)) return {};
  return x.visit([&](auto v) { return totvar_of(v, m, tau0_s, &interior); });
}

TotalVariance mtotvar(PhaseSpan x, std::uint64_t block, std::uint64_t m, double tau0_s, std::span<double> scratch) {
  return x.visit([&](auto v) { return mtotvar_of(v, block, m, tau0_s, scratch); });
}

TotalVariance htotvar(PhaseSpan x, std::uint64_t block, std::uint64_t m, double tau0_s, std::span<double> scratch) {
  return x.visit([&](auto v) { return htotvar_of(v, block, m, tau0_s, scratch); });
}

TotalVariance theo1(PhaseSpan x, std::uint64_t m, double tau0_s, std::uint64_t stride) {
  return x.visit([&](auto v) { return theo1_of(v, m, tau0_s, stride); });
}

TotalVariance oavar(PhaseSpan x, std::uint64_t m, double tau0_s, std::uint64_t stride) {
  return x.visit([&](auto v) { return oavar_of(v, m, tau0_s, stride); });
}

std::uint64_t theo_bias_last(std::uint64_t n_phase) {
  std::uint64_t last = n_phase / 6 - 3;          // n of the definition, floor(N / 6 - 3)
  if (2 * (9 + 3 * last) + 1 > n_phase) --last;  // its AVAR would need N + 1 points
  return last;
}

std::uint64_t theo_bias_index(std::uint64_t j, std::uint64_t count, std::uint64_t last) {
  // Evenly spread over 0..last, first and last included.
  return count == last + 1 ? j : (j * last + (count - 1) / 2) / (count - 1);
}

TheoBiasRatio theo_bias_ratio(PhaseSpan x, double tau0_s, std::uint32_t stride_factor, std::uint64_t ratio_taus,
                              const RowRunner* runner) {
  const std::uint64_t N = x.size();
  if (N < 24 || ratio_taus < 2 || !(tau0_s > 0)) return {};
  const std::uint64_t last = theo_bias_last(N);
  const std::uint64_t count = last + 1 <= ratio_taus ? last + 1 : ratio_taus;
  TheoBiasRatio out;
  out.defined = last + 1;
  out.exact = count == last + 1 && stride_factor == 0;
  // The taus a batch at a time, each AVAR / Theo1 in its slot (no heap), then summed in order.
  constexpr std::uint64_t batch = 64;
  struct Batch {
    PhaseSpan x;
    double tau0_s;
    std::uint32_t S;
    std::uint64_t count, last, first = 0;
    double term[batch] = {};
    bool defined[batch] = {};
    void row(std::size_t k) {
      const std::uint64_t i = theo_bias_index(first + k, count, last);
      const std::uint64_t mt = 12 + 4 * i, ma = 9 + 3 * i;
      const TotalVariance t = theo1(x, mt, tau0_s, S == 0 || mt <= S ? 1 : mt / S);
      const TotalVariance a = oavar(x, ma, tau0_s, S == 0 || ma <= S ? 1 : ma / S);
      defined[k] = t.n != 0 && a.n != 0 && t.var > 0;
      term[k] = defined[k] ? a.var / t.var : 0.0;
    }
  } taus{x, tau0_s, stride_factor, count, last};
  const Rows rows{[](void* context, std::size_t k) { static_cast<Batch*>(context)->row(k); }, &taus};
  double sum = 0.0;
  for (; taus.first < count; taus.first += batch) {
    const std::uint64_t size = count - taus.first < batch ? count - taus.first : batch;
    run_rows(runner, rows, static_cast<std::size_t>(size));
    for (std::uint64_t k = 0; k < size; ++k) {
      if (!taus.defined[k]) return {};
      sum += taus.term[k];
    }
  }
  out.ratio = sum / as_double(count);
  out.taus = count;
  return out;
}

std::uint64_t theo_bias_taus(std::uint64_t n_phase, std::uint32_t S) {
  if (n_phase < 24) return 0;
  const std::uint64_t all = n_phase / 6 - 2;
  if (S == 0) return all;
  double cost = 0.0;
  for (std::uint64_t i = 0; i < all; ++i) cost += total_exact_cost(true, 12 + 4 * i, n_phase);
  return cost <= total_exact_budget ? all : (all < 64 ? all : 64);
}

double total_exact_cost(bool theo, std::uint64_t m, std::uint64_t n_phase) {
  if (theo) return m < n_phase ? as_double(n_phase - m) * as_double(m / 2) : 0.0;
  return 3 * m <= n_phase ? as_double(n_phase - 3 * m + 1) * 15.0 * as_double(m) : 0.0;
}

std::uint64_t total_block(std::uint64_t m, std::uint64_t n_phase, std::uint32_t S) {
  if (S == 0 || m <= S || total_exact_cost(false, m, n_phase) <= total_exact_budget) return 1;
  std::uint64_t b = 1;
  while (2 * b <= m / S && m % (4 * b) == 0) b *= 2;  // 2b divides m with m / (2b) even
  return b;
}

std::uint64_t theo1_stride(std::uint64_t m, std::uint64_t n_phase, std::uint32_t S) {
  if (S == 0 || m <= S || total_exact_cost(true, m, n_phase) <= total_exact_budget) return 1;
  return m / S;
}

std::uint64_t theoh_switch(std::uint64_t n_phase) {
  const std::uint64_t limit = n_phase > 1 ? (n_phase - 1) / 10 : 0;
  std::uint64_t k = 1;
  while (2 * k <= limit) k *= 2;
  return k;
}

double totvar_bias(int alpha, double n_phase, double m) {
  const double a = alpha == -1 ? 1.0 / (3.0 * std::log(2.0)) : alpha == -2 ? 0.75 : 0.0;
  return 1.0 - a * m / (n_phase - 1.0);
}

double htotvar_bias(int alpha, std::uint64_t m) {
  if (m < 2) return 1.0;
  switch (alpha) {
    case 0: return 1.0 - 0.005;
    case -1: return 1.0 - 0.149;
    case -2: return 1.0 - 0.229;
    case -3: return 1.0 - 0.283;
    case -4: return 1.0 - 0.321;
    default: return 1.0;
  }
}

// b N / m - c from a table of (alpha, b, c) rows; 0 where alpha has none.
struct EdfRow {
  int alpha;
  double b, c;
};
template <std::size_t R>
double linear_edf(const EdfRow (&table)[R], int alpha, double n_phase, double m) {
  for (const EdfRow& row : table)
    if (row.alpha == alpha) return row.b * n_phase / m - row.c;
  return 0.0;
}

double edf_totvar(int alpha, double n_phase, double m) {
  static constexpr EdfRow table7[] = {{0, 1.50, 0.0}, {-1, 1.17, 0.22}, {-2, 0.93, 0.36}};
  return linear_edf(table7, alpha, n_phase, m);
}

double edf_mtotvar(int alpha, double n_phase, double m) {
  static constexpr EdfRow table8[] = {{2, 1.90, 2.1}, {1, 1.20, 1.40}, {0, 1.10, 1.2}, {-1, 0.85, 0.50}, {-2, 0.75, 0.31}};
  return linear_edf(table8, alpha, n_phase, m);
}

double edf_htotvar(int alpha, double n_phase, double m) {
  double b0 = 0, b1 = 0;
  switch (alpha) {
    case 0:
      b0 = 0.559;
      b1 = 1.004;
      break;
    case -1:
      b0 = 0.868;
      b1 = 1.140;
      break;
    case -2:
      b0 = 0.938;
      b1 = 1.696;
      break;
    default: return 0.0;
  }
  return (n_phase / m) / (b0 + b1 * m / n_phase);
}

double edf_theo1(int alpha, double n_phase, double m) {
  const double N = n_phase, r = 0.75 * m;
  switch (alpha) {
    case 2: return (0.86 * (N + 1) * (N - 4 * r / 3) / (N - r)) * (r / (r + 1.14));
    case 1: return ((4.798 * N * N - 6.374 * N * r + 12.387 * r) / (std::sqrt(r + 36.6) * (N - r))) * (r / (r + 0.3));
    case 0: return ((4.1 * N + 0.8) / r - (3.1 * N + 6.5) / N) * (std::pow(r, 1.5) / (std::pow(r, 1.5) + 5.2));
    case -1: return ((2 * N * N - 1.3 * N * r - 3.5 * r) / (N * r)) * (r * r * r / (r * r * r + 2.3));
    case -2: {
      const double a = 4.4 * N;
      return ((a - 2) / (2.9 * r)) * (((a - 1) * (a - 1) - 8.6 * r * (a - 1) + 11.4 * r * r) / ((a - 3) * (a - 3)));
    }
    default: return 0.0;
  }
}

}  // namespace gyrochar
