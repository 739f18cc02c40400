#pragma once
// The machinery of the exact second moments (noise_model.hpp), shared by noise_model.cpp (the
// moments and pair sums) and pair_sum_cache.cpp (their rounding bound, the exact skewness EDF and
// the cache): the digamma values, each term as taps and the kernel of two terms, the noises'
// generalized autocovariances R, the quadrature over lags, and the pair sums' common setup. Inline:
// the pair sums' inner loops call them at every node. Not part of the core's interface.
#include <array>
#include <cmath>
#include <cstdint>

#include "gyrochar/noise_model.hpp"

namespace gyrochar::noise_kernel {

constexpr double pi = 3.14159265358979323846;

// psi(n + 1/2) for 0 <= n < 64, by the recurrence psi(z + 1) = psi(z) + 1/z from psi(1/2) =
// -gamma - 2 ln 2.
constexpr std::array<double, 64> digamma_half_table = [] {
  std::array<double, 64> t{};
  t[0] = -1.96351002602142347944;
  for (std::size_t n = 1; n < t.size(); ++n) t[n] = t[n - 1] + 1.0 / (static_cast<double>(n) - 0.5);
  return t;
}();

// psi(a + j + 1/2) for j = -2 .. 2 (out[j + 2]), any integer a >= 0. psi(1/2 - n) = psi(1/2 + n) by
// the reflection formula (cot(pi (n + 1/2)) = 0). Small arguments from the table, large ones from
// one asymptotic series (error below 1e-17 for z >= 64) and the recurrence for the neighbours.
inline void digamma_row(std::int64_t a, std::array<double, 5>& out) {
  if (a < 62) {
    for (std::int64_t j = -2; j <= 2; ++j) {
      const std::int64_t n = a + j < 0 ? -(a + j) : a + j;
      out[static_cast<std::size_t>(j + 2)] = digamma_half_table[static_cast<std::size_t>(n)];
    }
    return;
  }
  const double z = static_cast<double>(a) + 0.5, w = 1.0 / (z * z);
  const double psi = std::log(z) - 0.5 / z - w * (1.0 / 12 - w * (1.0 / 120 - w * (1.0 / 252 - w * (1.0 / 240 - w / 132))));
  out[2] = psi;
  out[3] = psi + 1.0 / z;
  out[4] = out[3] + 1.0 / (z + 1);
  out[1] = psi - 1.0 / (z - 1);
  out[0] = out[1] - 1.0 / (z - 2);
}

// n! for the n that R needs (twice_d <= 8 at level 1: n <= 8), exact in double.
constexpr std::array<double, 9> factorials = [] {
  std::array<double, 9> f{};
  f[0] = 1;
  for (std::size_t n = 1; n < f.size(); ++n) f[n] = f[n - 1] * static_cast<double>(n);
  return f;
}();

inline double factorial(int n) { return factorials[static_cast<std::size_t>(n)]; }

// A term as taps on one process: x (level 0) or its prefix sums P (level 1). Offsets are relative
// to the newest point e of the term.
struct Taps {
  std::array<std::int64_t, 8> offset{};
  std::array<double, 8> weight{};
  int count = 0;
  void add(std::int64_t o, double w) {
    offset[static_cast<std::size_t>(count)] = o;
    weight[static_cast<std::size_t>(count)] = w;
    ++count;
  }
};

inline Taps taps(Stat s, std::uint64_t m, int level) {
  static constexpr double binomial2[] = {1, -2, 1};
  static constexpr double binomial3[] = {1, -3, 3, -1};
  const auto mm = static_cast<std::int64_t>(m);
  Taps t;
  if (s == Stat::mvar) {  // on P: P[e+1-km]
    for (int k = 0; k <= 3; ++k) t.add(1 - k * mm, binomial3[k]);
    return t;
  }
  const int d = difference_order(s);
  const double* b = d == 2 ? binomial2 : binomial3;
  for (int k = 0; k <= d; ++k) {
    if (level == 0) {
      t.add(-k * mm, b[k]);
    } else {  // x[j] = P[j+1] - P[j]
      t.add(1 - k * mm, b[k]);
      t.add(-k * mm, -b[k]);
    }
  }
  return t;
}

// The covariance kernel of two terms: c(lag) = sum_u w_u R(lag + u), on process `level`.
struct Kernel {
  std::array<std::int64_t, 64> u{};
  std::array<double, 64> w{};
  int count = 0;
  int level = 0;
  std::int64_t u_min() const { return u[0]; }
  std::int64_t u_max() const { return u[static_cast<std::size_t>(count - 1)]; }
};

inline Kernel kernel(Stat a, std::uint64_t m_a, Stat b, std::uint64_t m_b) {
  Kernel k;
  k.level = a == Stat::mvar || b == Stat::mvar ? 1 : 0;
  const Taps ta = taps(a, m_a, k.level), tb = taps(b, m_b, k.level);
  for (int i = 0; i < ta.count; ++i) {
    for (int j = 0; j < tb.count; ++j) {
      const std::int64_t u = ta.offset[static_cast<std::size_t>(i)] - tb.offset[static_cast<std::size_t>(j)];
      const double w = ta.weight[static_cast<std::size_t>(i)] * tb.weight[static_cast<std::size_t>(j)];
      int p = 0;  // insertion into the sorted list, merging equal offsets
      while (p < k.count && k.u[static_cast<std::size_t>(p)] < u) ++p;
      if (p < k.count && k.u[static_cast<std::size_t>(p)] == u) {
        k.w[static_cast<std::size_t>(p)] += w;
        continue;
      }
      for (int q = k.count; q > p; --q) {
        k.u[static_cast<std::size_t>(q)] = k.u[static_cast<std::size_t>(q - 1)];
        k.w[static_cast<std::size_t>(q)] = k.w[static_cast<std::size_t>(q - 1)];
      }
      k.u[static_cast<std::size_t>(p)] = u;
      k.w[static_cast<std::size_t>(p)] = w;
      ++k.count;
    }
  }
  return k;
}

// R(twice_d, k) for several noises at one argument, sharing the digamma values (flicker noises).
struct ManyR {
  std::array<int, max_noises> twice_d{};
  std::size_t count = 0;
  bool flicker = false;
  void at(std::int64_t k, std::array<double, max_noises>& out) const;
  // sum[t] += w R_t(k) for every noise: what at() gives, added as it is made (through an array
  // of values, the scalar stores and the vector loads of the sums stalled on each other).
  void add(std::int64_t k, double w, std::array<double, max_noises>& sum) const;
};

inline double integer_r(int twice_d, double a) {  // R for integer d >= 1, a = |k|
  const int j = twice_d / 2;
  double p = a;
  for (int i = 1; i < j; ++i) p *= a * a - static_cast<double>(i) * i;
  return (j % 2 ? -p : p) / (2 * factorial(2 * j - 1));
}

// psi(n + 1/2) for any integer n (beyond the shared row).
inline double digamma_half(std::int64_t n) {
  std::array<double, 5> row{};
  digamma_row(n < 0 ? -n : n, row);
  return row[2];
}

inline double flicker_r(int twice_d, std::int64_t ak, const std::array<double, 5>& psi) {  // d = j + 1/2
  const int j = (twice_d - 1) / 2;
  const double a = static_cast<double>(ak);
  double p = 1;
  for (int i = 1; i <= j; ++i) p *= a * a - (i - 0.5) * (i - 0.5);
  const auto uj = static_cast<std::size_t>(j);  // j >= 0: twice_d is odd and positive
  const double s = j <= 2 ? psi[2 + uj] + psi[2 - uj] : digamma_half(ak + j) + digamma_half(ak - j);
  return (j % 2 ? p : -p) * s / (2 * pi * factorial(2 * j));
}

inline void ManyR::at(std::int64_t k, std::array<double, max_noises>& out) const {
  out.fill(0.0);
  add(k, 1.0, out);
}

inline void ManyR::add(std::int64_t k, double w, std::array<double, max_noises>& sum) const {
  const std::int64_t ak = k < 0 ? -k : k;
  const double a = static_cast<double>(ak);
  std::array<double, 5> psi{};
  if (flicker) digamma_row(ak, psi);
  for (std::size_t t = 0; t < count; ++t) {
    const int d = twice_d[t];
    sum[t] += w * (d <= 0 ? (k == 0 ? 1.0 : 0.0) : d % 2 == 0 ? integer_r(d, a) : flicker_r(d, ak, psi));
  }
}

inline double covariance(const Kernel& k, int twice_d, std::int64_t lag) {
  double c = 0;
  for (int i = 0; i < k.count; ++i)
    c += k.w[static_cast<std::size_t>(i)] * generalized_autocovariance(twice_d, lag + k.u[static_cast<std::size_t>(i)]);
  return c;
}

// c_t(lag) of every noise of `r` at once.
inline void covariances(const Kernel& k, const ManyR& r, std::int64_t lag, std::array<double, max_noises>& c) {
  std::array<double, max_noises> sum{};
  for (int i = 0; i < k.count; ++i) r.add(lag + k.u[static_cast<std::size_t>(i)], k.w[static_cast<std::size_t>(i)], sum);
  c = sum;
}

inline std::int64_t floor_div(std::int64_t a, std::int64_t b) { return a / b - ((a % b != 0) && ((a < 0) != (b < 0))); }
inline std::int64_t ceil_div(std::int64_t a, std::int64_t b) { return -floor_div(-a, b); }

// Pairs (i, j) of the grids with e_i - e_j = lag, for nested strides.
struct PairCounter {
  std::int64_t first_a, last_a, first_b, last_b, s_a, s_b;
  std::int64_t n_a, n_b;
  std::int64_t operator()(std::int64_t lag) const {
    if (s_a <= s_b) {  // for each j, at most one i
      const std::int64_t lo = ceil_div(first_a - first_b - lag, s_b), hi = floor_div(last_a - first_b - lag, s_b);
      const std::int64_t from = lo > 0 ? lo : 0, to = hi < n_b - 1 ? hi : n_b - 1;
      return to >= from ? to - from + 1 : 0;
    }
    const std::int64_t lo = ceil_div(first_b + lag - first_a, s_a), hi = floor_div(last_b + lag - first_a, s_a);
    const std::int64_t from = lo > 0 ? lo : 0, to = hi < n_a - 1 ? hi : n_a - 1;
    return to >= from ? to - from + 1 : 0;
  }
};

// Quadrature over the lag lattice (multiples of `step`) between lo and hi: every lattice point near
// the breakpoints (where c or the pair count is not smooth), then steps growing with the distance
// to the nearest breakpoint (at most 1/grading of it, and at most max_step inside [smooth_lo,
// smooth_hi] where c oscillates on the scale of m). Trapezoid weights, which are exactly 1 where
// the nodes are consecutive lattice points.
constexpr std::int64_t grading = 16;

// The nodes one at a time, in increasing order, each with its weight (what visit_nodes() visits):
// two walks over the same kernel can then share the covariances at the lags they have in common.
class NodeWalker {
 public:
  NodeWalker(std::int64_t lo, std::int64_t hi, std::int64_t step, std::int64_t max_step, std::int64_t smooth_lo,
             std::int64_t smooth_hi, const std::int64_t* breaks, int n_breaks)
      : hi_(hi),
        step_(step),
        max_step_(max_step),
        smooth_lo_(smooth_lo),
        smooth_hi_(smooth_hi),
        lo_(lo),
        breaks_(breaks),
        n_breaks_(n_breaks),
        current_(lo),
        lattice_(static_cast<double>(step)) {}
  // False once every node was given.
  bool next(std::int64_t& lag, double& weight) {
    if (done_) return false;
    lag = current_;
    if (current_ >= hi_) {
      weight = have_previous_ ? static_cast<double>(current_ - previous_) / (2 * lattice_) + 0.5 : 1.0;
      done_ = true;
      return true;
    }
    const std::int64_t following = current_ + step_after(current_);
    const double left = static_cast<double>(current_ - (have_previous_ ? previous_ : current_));
    weight = (left + static_cast<double>(following - current_)) / (2 * lattice_) + (have_previous_ ? 0.0 : 0.5);
    previous_ = current_;
    have_previous_ = true;
    current_ = following;
    return true;
  }

 private:
  std::int64_t step_after(std::int64_t node) {
    while (b_ < n_breaks_ && breaks_[b_] <= node) ++b_;
    const std::int64_t to_previous = node - (b_ > 0 ? breaks_[b_ - 1] : lo_);
    const std::int64_t to_next = (b_ < n_breaks_ ? breaks_[b_] : hi_) - node;
    std::int64_t h = ((to_previous < to_next ? to_previous : to_next) / (grading * step_)) * step_;
    if (node >= smooth_lo_ && node <= smooth_hi_ && h > max_step_) h = max_step_;
    if (h < step_) h = step_;
    if (b_ < n_breaks_ && node + h > breaks_[b_]) h = breaks_[b_] - node;
    if (node + h > hi_) h = hi_ - node;
    return h;
  }
  std::int64_t hi_, step_, max_step_, smooth_lo_, smooth_hi_, lo_;
  const std::int64_t* breaks_;
  int n_breaks_;
  int b_ = 0;
  std::int64_t previous_ = 0, current_;
  bool have_previous_ = false, done_ = false;
  double lattice_;
};

template <class Visit>
inline void visit_nodes(std::int64_t lo, std::int64_t hi, std::int64_t step, std::int64_t max_step, std::int64_t smooth_lo,
                        std::int64_t smooth_hi, const std::int64_t* breaks, int n_breaks, Visit&& visit) {
  NodeWalker walk(lo, hi, step, max_step, smooth_lo, smooth_hi, breaks, n_breaks);
  std::int64_t lag = 0;
  double weight = 0;
  while (walk.next(lag, weight)) visit(lag, weight);
}

// e^-s minus its Taylor polynomial of degree < order: sum_{j >= order} (-s)^j / j!, by the series
// where it would otherwise cancel (s < 1), directly beyond.
inline double exp_remainder(int order, double s) {
  if (s < 1) {
    double term = 1;
    for (int j = 1; j <= order; ++j) term *= -s / j;
    double sum = 0;
    for (int j = order; j < order + 30; ++j) {
      sum += term;
      term *= -s / (j + 1);
      if (std::fabs(term) <= 1e-18 * std::fabs(sum)) break;
    }
    return sum;
  }
  double poly = 0, term = 1;
  for (int j = 0; j < order; ++j) {
    poly += term;
    term *= -s / (j + 1);
  }
  return std::exp(-s) - poly;
}

// The generalized autocovariance of the Markov phase (level 0) or its prefix sums (level 1), see
// noise_model.hpp. What does not depend on the lag (sinh and the series in a) is made once per
// rate: the exact Markov sums call it at every tap of every node. Series below a = 0.05 (their
// last terms are below 1e-16 of the first there).
struct MarkovAutocovariance {
  double a = 0;
  int level = 0;
  double linear = 0, cubic = 0, denominator = 1;
  MarkovAutocovariance() = default;
  MarkovAutocovariance(double rate, int at_level) : a(rate), level(at_level) {
    const double h = std::sinh(a / 2);
    const double a2 = a * a, a3 = a2 * a, a5 = a3 * a2;
    if (level == 0) {
      linear = a < 0.05 ? a3 * (1.0 / 6 + a2 * (1.0 / 120 + a2 * (1.0 / 5040 + a2 / 362880))) : std::sinh(a) - a;
      denominator = 4 * h * h;
      return;
    }
    if (a < 0.05) {
      linear = -a5 * (1.0 / 30 + a2 * (1.0 / 252 + a2 * (1.0 / 4320 + a2 * (17.0 / 1995840 + a2 * 31.0 / 141523200))));
      cubic = a5 * (1.0 / 24 + a2 * (1.0 / 240 + a2 * (17.0 / 72576 + a2 * (31.0 / 3628800 + a2 / 4561920))));
    } else {
      linear = std::sinh(a) * (1 - 2 * h * h / 3) - a;
      cubic = 2 * std::sinh(a) * h * h / 3 - a3 / 6;
    }
    denominator = 16 * h * h * h * h;
  }
  double operator()(std::int64_t k) const {
    const double ak = static_cast<double>(k < 0 ? -k : k);
    if (level == 0) return -(exp_remainder(2, a * ak) + linear * ak) / denominator;
    return (exp_remainder(4, a * ak) + linear * ak + cubic * ak * ak * ak) / denominator;
  }
};

// c of Markov rate r.a (unit stationary variance) at `lag` under kernel k (r made at k.level).
inline double markov_covariance(const Kernel& k, const MarkovAutocovariance& r, std::int64_t lag) {
  double c = 0;
  for (int i = 0; i < k.count; ++i) c += k.w[static_cast<std::size_t>(i)] * r(lag + k.u[static_cast<std::size_t>(i)]);
  return c;
}

// What pair_sums() and markov_pair_sums() share: the kernel of the two statistics, the noises' R,
// the pair counter and the lags that have pairs (on the finer stride's lattice).
struct PairSetup {
  Kernel k;
  ManyR many;
  PairCounter pairs{};
  std::int64_t step = 1, extent_lo = 0, extent_hi = 0;
};

// False when either grid has no term, the strides do not nest or a noise of `set` does not
// converge for either statistic.
inline bool pair_setup(const NoiseSet& set, const TermGrid& a, const TermGrid& b, PairSetup& s) {
  if (a.n == 0 || b.n == 0 || a.stride == 0 || b.stride == 0) return false;
  const std::uint64_t fine = a.stride < b.stride ? a.stride : b.stride;
  const std::uint64_t coarse = a.stride < b.stride ? b.stride : a.stride;
  if (coarse % fine != 0) return false;  // strides must nest (powers of two always do)
  s.k = kernel(a.stat, a.m, b.stat, b.m);
  for (std::size_t t = 0; t < set.count && t < max_noises; ++t) {
    if (!noise_supported(a.stat, set.alpha[t]) || !noise_supported(b.stat, set.alpha[t])) return false;
    s.many.twice_d[t] = 2 - set.alpha[t] + 2 * s.k.level;
    s.many.flicker |= s.many.twice_d[t] % 2 != 0;
    s.many.count = t + 1;
  }
  s.step = static_cast<std::int64_t>(fine);
  s.pairs = PairCounter{static_cast<std::int64_t>(a.first),  static_cast<std::int64_t>(a.first + (a.n - 1) * a.stride),
                        static_cast<std::int64_t>(b.first),  static_cast<std::int64_t>(b.first + (b.n - 1) * b.stride),
                        static_cast<std::int64_t>(a.stride), static_cast<std::int64_t>(b.stride),
                        static_cast<std::int64_t>(a.n),      static_cast<std::int64_t>(b.n)};
  s.extent_lo = s.pairs.first_a - s.pairs.last_b;
  s.extent_hi = s.pairs.last_a - s.pairs.first_b;
  return true;
}

// Breakpoints in [lo, hi], sorted: where an R argument crosses 0, and where the pair count has a
// kink. Returns their number.
inline int pair_breaks(const PairSetup& s, std::int64_t lo, std::int64_t hi, std::array<std::int64_t, 72>& breaks) {
  int n_breaks = 0;
  auto add_break = [&](std::int64_t v) {
    v = floor_div(v, s.step) * s.step;
    if (v < lo || v > hi) return;
    int p = 0;
    while (p < n_breaks && breaks[static_cast<std::size_t>(p)] < v) ++p;
    if (p < n_breaks && breaks[static_cast<std::size_t>(p)] == v) return;
    for (int q = n_breaks; q > p; --q) breaks[static_cast<std::size_t>(q)] = breaks[static_cast<std::size_t>(q - 1)];
    breaks[static_cast<std::size_t>(p)] = v;
    ++n_breaks;
  };
  for (int i = 0; i < s.k.count; ++i) {
    add_break(-s.k.u[static_cast<std::size_t>(i)]);
    add_break(-s.k.u[static_cast<std::size_t>(i)] + s.step);  // the lattice point just past it
  }
  const PairCounter& p = s.pairs;
  for (const std::int64_t v : {p.first_a - p.first_b, p.last_a - p.last_b, p.first_a - p.last_b, p.last_a - p.first_b})
    add_break(v);
  return n_breaks;
}

// Away from the breakpoints c varies on the scale of the longer term: at least 256 nodes there.
inline std::int64_t smooth_step(const TermGrid& a, const TermGrid& b, std::int64_t step) {
  const std::uint64_t m_max = a.m > b.m ? a.m : b.m;
  const std::int64_t max_step = static_cast<std::int64_t>(m_max / 256) / step * step;
  return max_step < step ? step : max_step;
}

// Beyond three kernel widths a flicker noise's c falls as lag^-p from the kernel's centre: p for
// each noise of s (0 for the others).
inline std::array<double, max_noises> tail_powers(const PairSetup& s, const TermGrid& a, const TermGrid& b) {
  const int level = s.k.level;
  const int order = difference_order(a.stat) + difference_order(b.stat) + (a.stat == Stat::mvar ? 0 : level) +
                    (b.stat == Stat::mvar ? 0 : level) + (a.stat == Stat::mvar) + (b.stat == Stat::mvar);
  std::array<double, max_noises> p{};
  for (std::size_t t = 0; t < s.many.count; ++t)
    if (s.many.twice_d[t] % 2 != 0) p[t] = order - (s.many.twice_d[t] - 1);
  return p;
}

// The power-law noises' c at any lag, for the sums beside a Markov rate or a sinusoid that reach
// beyond the kernel's span: there every R argument has one sign, the kernel annihilates R's
// polynomial part and c is zero but for flicker noises: direct to three kernel widths, then the
// power law pair_sums() integrates (its value at three widths times (L / |lag - centre|)^p).
struct NoiseAtAnyLag {
  std::int64_t span_lo = 0, span_hi = 0, flicker_lo = 0, flicker_hi = 0;
  double center = 0;
  std::array<double, max_noises> p{}, tail_lo{}, tail_hi{};
  ManyR flickers;  // the flicker noises of the set alone: beyond the span only they are evaluated
  std::array<std::size_t, max_noises> flicker_of{};  // flickers' entry f is the set's noise flicker_of[f]

  NoiseAtAnyLag(const PairSetup& s, const TermGrid& a, const TermGrid& b)
      : span_lo(-s.k.u_max()),
        span_hi(-s.k.u_min()),
        center(-0.5 * static_cast<double>(s.k.u_min() + s.k.u_max())),
        p(tail_powers(s, a, b)) {
    const std::int64_t width = span_hi - span_lo + 1;
    flicker_lo = span_lo - 3 * width;
    flicker_hi = span_hi + 3 * width;
    if (!s.many.flicker) return;
    flickers.flicker = true;
    for (std::size_t t = 0; t < s.many.count; ++t) {
      if (s.many.twice_d[t] % 2 == 0) continue;
      flicker_of[flickers.count] = t;
      flickers.twice_d[flickers.count++] = s.many.twice_d[t];
    }
    flicker_covariances(s, flicker_lo, tail_lo);
    flicker_covariances(s, flicker_hi, tail_hi);
  }
  bool inside(std::int64_t lag) const { return lag >= span_lo && lag <= span_hi; }
  void at(const PairSetup& s, std::int64_t lag, std::array<double, max_noises>& c) const {
    if (inside(lag)) {
      covariances(s.k, s.many, lag, c);
      return;
    }
    c.fill(0.0);  // beyond the span the other noises' c is zero but for rounding
    if (!s.many.flicker) return;
    if (lag >= flicker_lo && lag <= flicker_hi) {
      flicker_covariances(s, lag, c);
      return;
    }
    const bool left = lag < flicker_lo;
    const double L = std::fabs(static_cast<double>(left ? flicker_lo : flicker_hi) - center);
    for (std::size_t f = 0; f < flickers.count; ++f) {
      const std::size_t t = flicker_of[f];
      c[t] = (left ? tail_lo[t] : tail_hi[t]) * std::pow(L / std::fabs(static_cast<double>(lag) - center), p[t]);
    }
  }

 private:
  // c of the flicker noises only (the same sums as covariances() gives them), at their places in c.
  void flicker_covariances(const PairSetup& s, std::int64_t lag, std::array<double, max_noises>& c) const {
    std::array<double, max_noises> own{};
    covariances(s.k, flickers, lag, own);
    for (std::size_t f = 0; f < flickers.count; ++f) c[flicker_of[f]] = own[f];
  }
};

// The response sum_k w_k e^(i theta o_k) of a term's taps: its real and imaginary parts.
inline void response(const Taps& t, double theta, double& re, double& im) {
  re = im = 0;
  for (int k = 0; k < t.count; ++k) {
    const double phase = theta * static_cast<double>(t.offset[static_cast<std::size_t>(k)]);
    re += t.weight[static_cast<std::size_t>(k)] * std::cos(phase);
    im += t.weight[static_cast<std::size_t>(k)] * std::sin(phase);
  }
}

// A sinusoid's c(lag) = Re(e^(i theta lag) W) g / (2 theta^2): W = F_a conj(F_b) as (re, im), g the
// prefix sums' gain at `level`.
struct SinusoidKernel {
  double theta = 0, re = 0, im = 0;
  double at(std::int64_t lag) const {
    const double phase = theta * static_cast<double>(lag);
    return std::cos(phase) * re - std::sin(phase) * im;
  }
};

inline SinusoidKernel sinusoid_kernel(double theta, Stat a, std::uint64_t m_a, Stat b, std::uint64_t m_b) {
  const int level = a == Stat::mvar || b == Stat::mvar ? 1 : 0;
  double ar, ai, br, bi;
  response(taps(a, m_a, level), theta, ar, ai);
  response(taps(b, m_b, level), theta, br, bi);
  const double half = std::sin(theta / 2);
  const double scale = 1 / (2 * theta * theta * (level == 1 ? 4 * half * half : 1.0));
  return {theta, (ar * br + ai * bi) * scale, (ai * br - ar * bi) * scale};
}

}  // namespace gyrochar::noise_kernel
