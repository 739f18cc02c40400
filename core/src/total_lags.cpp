// MTOTVAR and HTOTVAR at short averaging factors from the exact lag products of an integer record's
// differences (total_lags.hpp; the derivation in docs/total.md).
#include "gyrochar/total_lags.hpp"

#include <cstdint>
#include <type_traits>

namespace gyrochar {
namespace {

using Index = std::size_t;                             // indices into the record (32 bits on the MCU builds)
constexpr Index stripes = 16;                          // the pass's rows
constexpr Index chunk = 8192;                          // products added in double, then exactly
constexpr Index block = 512;                           // values whose products go lag by lag, in the cache
constexpr Index max_lags = 3 * lag_table_max_m - 2;    // 382
constexpr Index padded_lags = (max_lags + 3) / 4 * 4;  // the lags four at a time
constexpr double exact_products = 0x1p53 / chunk;      // |w|^2 below this: a chunk's sums are exact

// Double-double arithmetic, no fused multiply-add (Knuth's and Dekker's error-free transformations):
// the same bits on every target.
ExactSum two_sum(double a, double b) {
  const double s = a + b, v = s - a;
  return {s, (a - (s - v)) + (b - v)};
}
ExactSum fast_two_sum(double a, double b) {  // |a| >= |b|
  const double s = a + b;
  return {s, b - (s - a)};
}
ExactSum split(double a) {
  const double c = 134217729.0 * a;  // 2^27 + 1
  const double hi = c - (c - a);
  return {hi, a - hi};
}
ExactSum two_product(double a, double b) {
  const double p = a * b;
  const ExactSum x = split(a), y = split(b);
  return {p, ((x.hi * y.hi - p) + x.hi * y.lo + x.lo * y.hi) + x.lo * y.lo};
}
ExactSum operator+(ExactSum a, ExactSum b) {
  const ExactSum s = two_sum(a.hi, b.hi);
  return fast_two_sum(s.hi, s.lo + (a.lo + b.lo));
}
ExactSum operator-(ExactSum a) { return {-a.hi, -a.lo}; }
ExactSum operator-(ExactSum a, ExactSum b) { return a + -b; }
ExactSum operator*(ExactSum a, ExactSum b) {
  const ExactSum p = two_product(a.hi, b.hi);
  return fast_two_sum(p.hi, p.lo + (a.hi * b.lo + a.lo * b.hi));
}

// The difference of order 2 or 3 at j, exact in 64 bits, as a double (exact while |w| < 2^53).
template <class T>
double difference(const T* x, Index j, int order) {
  const std::int64_t a = std::int64_t{x[j + 1]} - x[j], b = std::int64_t{x[j + 2]} - x[j + 1];
  if (order == 2) return static_cast<double>(b - a);
  const std::int64_t c = std::int64_t{x[j + 3]} - x[j + 2];
  return static_cast<double>((c - b) - (b - a));
}

// The sum of x over group k of `group` samples, modulo 2^64 (so its differences are exact while
// they are below 2^63).
template <class T>
std::uint64_t group_sum(const T* x, Index k, Index group) {
  std::uint64_t sum = 0;
  for (const T* p = x + k * group; p < x + (k + 1) * group; ++p) sum += static_cast<std::uint64_t>(std::int64_t{*p});
  return sum;
}

// out[i] = w[from + i] for i < count, zero past the last difference, w the differences of the
// record's sums over groups of `group` samples (1: of x itself); the largest |w| loaded.
double load(PhaseSpan x, Index group, int order, Index values, Index from, Index count, double* out) {
  double largest = 0;
  x.visit([&]<class T>(std::span<const T> v) {
    if constexpr (!std::is_floating_point_v<T>) {
      const Index have = from < values ? (values - from < count ? values - from : count) : 0;
      if (group == 1) {
        for (Index i = 0; i < have; ++i) out[i] = difference(v.data(), from + i, order);
      } else {
        // The group sums from `from` on, each once: g holds the last order + 1 of them. Their
        // differences modulo 2^64, as the sums.
        const auto less = [](std::uint64_t a, std::uint64_t b) { return a - b; };
        std::uint64_t g[4];
        for (Index k = 0; k < static_cast<Index>(order) && k < have; ++k) g[k] = group_sum(v.data(), from + k, group);
        for (Index i = 0; i < have; ++i) {
          g[order] = group_sum(v.data(), from + i + static_cast<Index>(order), group);
          const std::uint64_t a = less(g[1], g[0]), b = less(g[2], g[1]);
          const std::uint64_t w = order == 2 ? less(b, a) : less(less(less(g[3], g[2]), b), less(b, a));
          out[i] = static_cast<double>(static_cast<std::int64_t>(w));
          for (int k = 0; k < order; ++k) g[k] = g[k + 1];
        }
      }
      for (Index i = 0; i < have; ++i) largest = out[i] > largest ? out[i] : -out[i] > largest ? -out[i] : largest;
      for (Index i = have; i < count; ++i) out[i] = 0.0;
    }
  });
  return largest;
}

// partial[d] += sum_{j < block} a[j] r[j + d] for every d < lags (a multiple of four): four lags
// at a time, a vector of products a lag. On x86-64 (checked at run time) the vector is one
// register: eight lanes with AVX-512, four with AVX2, both with fused multiply-adds; else two
// registers of two. Integers within exact_products: every sum is exact, so every path gives the
// same bits.
using Four = double __attribute__((vector_size(4 * sizeof(double))));
using Eight = double __attribute__((vector_size(8 * sizeof(double))));
template <class Lanes>
[[gnu::always_inline]] inline double lane_sum(const Lanes& s) {
  double sum = 0;
  for (Index i = 0; i < sizeof s / sizeof sum; ++i) sum += s[i];
  return sum;
}
template <class Lanes>
[[gnu::always_inline]] inline void block_products(const double* a, const double* r, Index lags, double* partial) {
  constexpr Index width = sizeof(Lanes) / sizeof(double);
  static_assert(block % width == 0);
  for (Index d = 0; d < lags; d += 4) {
    Lanes s0 = {}, s1 = {}, s2 = {}, s3 = {};
    for (Index j = 0; j < block; j += width) {
      Lanes v, r0, r1, r2, r3;
      __builtin_memcpy(&v, a + j, sizeof v);
      __builtin_memcpy(&r0, r + j + d, sizeof r0);
      __builtin_memcpy(&r1, r + j + d + 1, sizeof r1);
      __builtin_memcpy(&r2, r + j + d + 2, sizeof r2);
      __builtin_memcpy(&r3, r + j + d + 3, sizeof r3);
      s0 += v * r0, s1 += v * r1, s2 += v * r2, s3 += v * r3;
    }
    partial[d] += lane_sum(s0);
    partial[d + 1] += lane_sum(s1);
    partial[d + 2] += lane_sum(s2);
    partial[d + 3] += lane_sum(s3);
  }
}
void block_products_scalar(const double* a, const double* r, Index lags, double* partial) {
  block_products<Four>(a, r, lags, partial);
}
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define GYROCHAR_LAGS_AVX 1
[[gnu::target("avx512f")]] void block_products_avx512(const double* a, const double* r, Index lags, double* partial) {
  block_products<Eight>(a, r, lags, partial);
}
[[gnu::target("avx2,fma")]] void block_products_avx2(const double* a, const double* r, Index lags, double* partial) {
  block_products<Four>(a, r, lags, partial);
}
// The same sums on differences below narrow_limit held as int16, with AVX-512BW (checked at run
// time): the compiler makes each lag's products multiply-and-add instructions of 32 int16 a
// register, four times the products of the doubles' eight. A lag's block sum is at most
// block narrow_limit^2 < 2^31 (int32, exact), then added to its double exactly: the same sums.
constexpr double narrow_limit = 2048;
[[gnu::target("avx512f,avx512bw")]] void block_products_narrow(const std::int16_t* a, const std::int16_t* r, Index lags,
                                                               double* partial) {
  for (Index d = 0; d < lags; d += 4) {
    std::int32_t s0 = 0, s1 = 0, s2 = 0, s3 = 0;
    for (Index j = 0; j < block; ++j) {
      const std::int32_t v = a[j];
      s0 += v * r[j + d];
      s1 += v * r[j + d + 1];
      s2 += v * r[j + d + 2];
      s3 += v * r[j + d + 3];
    }
    partial[d] += s0, partial[d + 1] += s1, partial[d + 2] += s2, partial[d + 3] += s3;
  }
}
#endif

struct Pass {
  PhaseSpan x;
  Index group;
  int order;
  Index lags, values;
  ExactSum* sums;   // stripes x lags
  double* largest;  // each stripe's largest |w|
};

// Stripe s: the products w[j] w[j + d] of its j, chunk by chunk, each chunk's sums in double added
// to the stripe's exactly.
void stripe(const Pass& p, Index s) {
  const auto part = [&](Index i) { return static_cast<Index>(static_cast<std::uint64_t>(p.values) * i / stripes); };
  const Index j0 = part(s), j1 = part(s + 1);
  const Index lags = (p.lags + 3) / 4 * 4;
  ExactSum* out = p.sums + s * p.lags;
  for (Index d = 0; d < p.lags; ++d) out[d] = {};
  double left[chunk], right[chunk + padded_lags + 4], partial[padded_lags];
#ifdef GYROCHAR_LAGS_AVX
  std::int16_t left16[chunk], right16[chunk + padded_lags + 4];
  const bool has_narrow = __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512bw");
#endif
  double largest = 0;
  for (Index c0 = j0; c0 < j1; c0 += chunk) {
    const Index n = j1 - c0 < chunk ? j1 - c0 : chunk, rounded = (n + block - 1) / block * block;
    const double most = load(p.x, p.group, p.order, p.values, c0, rounded + lags + 4, right);
    for (Index i = 0; i < rounded; ++i) left[i] = i < n ? right[i] : 0.0;  // past n: the next stripe's products
    largest = most > largest ? most : largest;
    for (Index d = 0; d < lags; ++d) partial[d] = 0.0;
#ifdef GYROCHAR_LAGS_AVX
    if (has_narrow && most < narrow_limit) {
      for (Index i = 0; i < rounded; ++i) left16[i] = static_cast<std::int16_t>(left[i]);
      for (Index i = 0; i < rounded + lags + 4; ++i) right16[i] = static_cast<std::int16_t>(right[i]);
      for (Index b = 0; b < rounded; b += block) block_products_narrow(left16 + b, right16 + b, lags, partial);
      for (Index d = 0; d < p.lags; ++d) out[d] = out[d] + ExactSum{partial[d], 0};
      continue;
    }
#endif
    for (Index b = 0; b < rounded; b += block) {
#ifdef GYROCHAR_LAGS_AVX
      if (__builtin_cpu_supports("avx512f")) {
        block_products_avx512(left + b, right + b, lags, partial);
        continue;
      }
      if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) {
        block_products_avx2(left + b, right + b, lags, partial);
        continue;
      }
#endif
      block_products_scalar(left + b, right + b, lags, partial);
    }
    for (Index d = 0; d < p.lags; ++d) out[d] = out[d] + ExactSum{partial[d], 0};
  }
  p.largest[s] = largest;
}

// The 6m terms z_k of one window u of 3m integers by MTOTVAR's definition (total.cpp's kernel),
// times D = h (3m - h): the line through the half means removed (its slope is an integer over D; a
// constant too would change no term), the window mirrored at both ends, E the extension's prefix
// sums (9m + 1), z_k = E[k+3m] - 3 E[k+2m] + 3 E[k+m] - E[k]. Integers: exact.
void window_terms(const std::int64_t* u, Index m, std::int64_t* E, std::int64_t* z) {
  const Index len = 3 * m, half = len / 2;
  const auto D = static_cast<std::int64_t>(half * (len - half));
  std::int64_t first = 0, second = 0;
  for (Index t = 0; t < half; ++t) first += u[t], second += u[len - half + t];
  auto detrended = [&](Index t) { return D * u[t] - (second - first) * static_cast<std::int64_t>(t); };
  E[0] = 0;
  for (Index t = 0; t < len; ++t) E[t + 1] = E[t] + detrended(len - 1 - t);
  for (Index t = 0; t < len; ++t) E[len + t + 1] = E[len + t] + detrended(t);
  for (Index t = 0; t < len; ++t) E[2 * len + t + 1] = E[2 * len + t] + detrended(len - 1 - t);
  for (Index k = 0; k < 6 * m; ++k) z[k] = E[k + 3 * m] - 3 * E[k + 2 * m] + 3 * E[k + m] - E[k];
}

// D^2 times the sum over the windows and the 6m terms of z^2, from the table (order checked by the
// caller). c[v][k]: D times term k of the window whose only nonzero second difference is a 1 at v
// (the ramp max(0, t - v - 1)), so D z_k(n) = sum_v c[v][k] w[n + v]; then every pair v <= v'
// weighted by its products' sum over the windows' range. The terms pair up as in the definition
// (z_k = z_{3m-k} on [0, 3m], z_k = z_{9m-k} beyond): each pair once, twice weighted. O(27 m^3)
// double-double operations.
ExactSum window_sum(const LagTable& t, Index m, std::span<double> scratch) {
  const Index len = 3 * m, L = len - 2;
  Index kept[6 * lag_table_max_m], K = 0;
  double weight[6 * lag_table_max_m];
  for (Index k = 0; k < 6 * m; ++k) {
    const Index partner = k <= len ? len - k : 3 * len - k;
    if (k <= partner) kept[K] = k, weight[K++] = k == partner ? 1 : 2;
  }
  double* c = scratch.data();  // L x K, integers below 2^53 (docs/total.md)
  std::int64_t u[3 * lag_table_max_m], E[9 * lag_table_max_m + 1], z[6 * lag_table_max_m];
  for (Index v = 0; v < L; ++v) {
    for (Index s = 0; s < len; ++s) u[s] = s > v + 1 ? static_cast<std::int64_t>(s - v - 1) : 0;
    window_terms(u, m, E, z);
    for (Index i = 0; i < K; ++i) c[v * K + i] = static_cast<double>(z[kept[i]]);
  }
  ExactSum sum;
  for (Index v = 0; v < L; ++v) {
    for (Index v2 = v; v2 < L; ++v2) {
      const Index d = v2 - v;
      const ExactSum products = t.total[d] - t.head[d * t.lags + v] - t.tail[d * t.lags + (L - 1 - v2)];
      ExactSum q;
      for (Index i = 0; i < K; ++i) {
        const ExactSum p = two_product(c[v * K + i], c[v2 * K + i]);
        q = q + ExactSum{weight[i] * p.hi, weight[i] * p.lo};
      }
      const ExactSum term = q * products;
      sum = sum + (v2 == v ? term : ExactSum{2 * term.hi, 2 * term.lo});
    }
  }
  return sum;
}

bool lagged_defined(const LagTable& t, int order, std::uint64_t m, std::uint64_t least, double tau0_s,
                    std::span<double> scratch) {
  return t.ready && t.order == order && m >= least && m <= lag_table_max_m && 3 * m - 2 <= t.lags && 3 * m <= t.values + 2 &&
         tau0_s > 0 && scratch.size() >= lagged_scratch_size(m);
}

// The mean over the windows of the mean of their 6m squared terms.
double window_mean(const LagTable& t, std::uint64_t m, std::span<double> scratch) {
  const ExactSum sum = window_sum(t, static_cast<Index>(m), scratch);
  const Index len = 3 * static_cast<Index>(m), half = len / 2;
  const double D = static_cast<double>(half * (len - half)), windows = static_cast<double>(t.values + 2 - len + 1);
  return (sum.hi + sum.lo) / (D * D) / (6.0 * static_cast<double>(m) * windows);
}

}  // namespace

std::size_t lag_table_size(std::size_t lags) { return lags * (2 * lags + 1 + stripes); }

LagTable lag_table(PhaseSpan x, int order, std::size_t lags, std::span<ExactSum> work, const RowRunner* runner,
                   std::uint64_t group) {
  LagTable t;
  if ((order != 2 && order != 3) || !x.integers() || group < 1 || x.size() / group <= static_cast<Index>(order) ||
      lags < 1 || lags > max_lags || work.size() < lag_table_size(lags))
    return t;
  const Index values = static_cast<Index>(x.size() / group) - static_cast<Index>(order);
  ExactSum* total = work.data();
  ExactSum* head = total + lags;
  ExactSum* tail = head + lags * lags;
  double largest[stripes];
  Pass pass{x, static_cast<Index>(group), order, lags, values, tail + lags * lags, largest};
  run_rows(runner, Rows{[](void* p, std::size_t s) { stripe(*static_cast<const Pass*>(p), s); }, &pass}, stripes);
  for (Index s = 0; s < stripes; ++s)
    if (!(largest[s] * largest[s] < exact_products)) return t;  // a chunk's sums might have rounded
  for (Index d = 0; d < lags; ++d) {
    total[d] = {};
    for (Index s = 0; s < stripes; ++s) total[d] = total[d] + pass.sums[s * lags + d];
  }
  // The ends: the first and the last 2 lags differences (or fewer), their products directly.
  const Index span = 2 * lags < values ? 2 * lags : values;
  double first[2 * max_lags], last[2 * max_lags];
  load(x, static_cast<Index>(group), order, values, 0, span, first);
  load(x, static_cast<Index>(group), order, values, values - span, span, last);
  for (Index d = 0; d < lags; ++d) {
    ExactSum* h = head + d * lags;
    ExactSum* e = tail + d * lags;
    h[0] = e[0] = {};
    for (Index c = 0; c + 1 < lags; ++c) {
      // head: the product at j = c; tail: at j = values - 1 - d - c (both where they exist)
      const bool exists = c + d < values;
      h[c + 1] = h[c] + ExactSum{exists ? first[c] * first[c + d] : 0.0, 0};
      e[c + 1] = e[c] + ExactSum{exists ? last[span - 1 - d - c] * last[span - 1 - c] : 0.0, 0};
    }
  }
  t.lags = lags, t.values = values, t.order = order;
  t.total = {total, lags}, t.head = {head, lags * lags}, t.tail = {tail, lags * lags};
  t.ready = true;
  return t;
}

std::size_t lagged_scratch_size(std::uint64_t m) {
  const std::uint64_t L = 3 * m > 2 ? 3 * m - 2 : 0;
  return static_cast<std::size_t>(L * (3 * m + 1));  // the coefficients of the kept terms
}

TotalVariance mtotvar_lagged(const LagTable& t, std::uint64_t m, double tau0_s, std::span<double> scratch) {
  if (!lagged_defined(t, 2, m, 1, tau0_s, scratch)) return {};
  const double md = static_cast<double>(m), tau = md * tau0_s;
  return {window_mean(t, m, scratch) / (2.0 * md * md * tau * tau), t.values + 2 - 3 * m + 1, 1};
}

TotalVariance htotvar_lagged(const LagTable& t, std::uint64_t m, double tau0_s, std::span<double> scratch) {
  if (!lagged_defined(t, 3, m, 2, tau0_s, scratch)) return {};
  const double scale = static_cast<double>(m) * tau0_s;  // of the N - 1 frequencies' windows
  return {window_mean(t, m, scratch) / (6.0 * scale * scale), t.values + 2 - 3 * m + 1, 1};
}

}  // namespace gyrochar
