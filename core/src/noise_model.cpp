// Exact second moments of the Allan-family estimators under discrete-time power-law noise (see
// noise_model.hpp for the model and the closed forms).
#include "gyrochar/noise_model.hpp"

#include <cmath>

namespace gyrochar {
namespace {

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
void digamma_row(std::int64_t a, std::array<double, 5>& out) {
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

double factorial(int n) { return factorials[static_cast<std::size_t>(n)]; }

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

Taps taps(Stat s, std::uint64_t m, int level) {
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

Kernel kernel(Stat a, std::uint64_t m_a, Stat b, std::uint64_t m_b) {
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
};

double integer_r(int twice_d, double a) {  // R for integer d >= 1, a = |k|
  const int j = twice_d / 2;
  double p = a;
  for (int i = 1; i < j; ++i) p *= a * a - static_cast<double>(i) * i;
  return (j % 2 ? -p : p) / (2 * factorial(2 * j - 1));
}

// psi(n + 1/2) for any integer n (beyond the shared row).
double digamma_half(std::int64_t n) {
  std::array<double, 5> row{};
  digamma_row(n < 0 ? -n : n, row);
  return row[2];
}

double flicker_r(int twice_d, std::int64_t ak, const std::array<double, 5>& psi) {  // d = j + 1/2
  const int j = (twice_d - 1) / 2;
  const double a = static_cast<double>(ak);
  double p = 1;
  for (int i = 1; i <= j; ++i) p *= a * a - (i - 0.5) * (i - 0.5);
  const double s = j <= 2 ? psi[static_cast<std::size_t>(2 + j)] + psi[static_cast<std::size_t>(2 - j)]
                          : digamma_half(ak + j) + digamma_half(ak - j);
  return (j % 2 ? p : -p) * s / (2 * pi * factorial(2 * j));
}

void ManyR::at(std::int64_t k, std::array<double, max_noises>& out) const {
  const std::int64_t ak = k < 0 ? -k : k;
  const double a = static_cast<double>(ak);
  std::array<double, 5> psi{};
  if (flicker) digamma_row(ak, psi);
  for (std::size_t t = 0; t < count; ++t) {
    const int d = twice_d[t];
    out[t] = d <= 0 ? (k == 0 ? 1.0 : 0.0) : d % 2 == 0 ? integer_r(d, a) : flicker_r(d, ak, psi);
  }
}

double covariance(const Kernel& k, int twice_d, std::int64_t lag) {
  double c = 0;
  for (int i = 0; i < k.count; ++i)
    c += k.w[static_cast<std::size_t>(i)] * generalized_autocovariance(twice_d, lag + k.u[static_cast<std::size_t>(i)]);
  return c;
}

// c_t(lag) of every noise of `r` at once.
void covariances(const Kernel& k, const ManyR& r, std::int64_t lag, std::array<double, max_noises>& c) {
  c.fill(0.0);
  std::array<double, max_noises> values{};
  for (int i = 0; i < k.count; ++i) {
    r.at(lag + k.u[static_cast<std::size_t>(i)], values);
    const double w = k.w[static_cast<std::size_t>(i)];
    for (std::size_t t = 0; t < r.count; ++t) c[t] += w * values[t];
  }
}

std::int64_t floor_div(std::int64_t a, std::int64_t b) { return a / b - ((a % b != 0) && ((a < 0) != (b < 0))); }
std::int64_t ceil_div(std::int64_t a, std::int64_t b) { return -floor_div(-a, b); }

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
      : hi_(hi), step_(step), max_step_(max_step), smooth_lo_(smooth_lo), smooth_hi_(smooth_hi), lo_(lo),
        breaks_(breaks), n_breaks_(n_breaks), current_(lo), lattice_(static_cast<double>(step)) {}
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
void visit_nodes(std::int64_t lo, std::int64_t hi, std::int64_t step, std::int64_t max_step, std::int64_t smooth_lo,
                 std::int64_t smooth_hi, const std::int64_t* breaks, int n_breaks, Visit&& visit) {
  NodeWalker walk(lo, hi, step, max_step, smooth_lo, smooth_hi, breaks, n_breaks);
  std::int64_t lag = 0;
  double weight = 0;
  while (walk.next(lag, weight)) visit(lag, weight);
}

}  // namespace

double generalized_autocovariance(int twice_d, std::int64_t k) {
  ManyR r;
  r.twice_d[0] = twice_d;
  r.count = 1;
  r.flicker = twice_d > 0 && twice_d % 2 != 0;
  std::array<double, max_noises> out{};
  r.at(k, out);
  return out[0];
}

double term_covariance(int alpha, Stat a, std::uint64_t m_a, Stat b, std::uint64_t m_b, std::int64_t lag) {
  if (!noise_supported(a, alpha) || !noise_supported(b, alpha)) return 0.0;
  const Kernel k = kernel(a, m_a, b, m_b);
  return covariance(k, 2 - alpha + 2 * k.level, lag);
}

namespace {

// e^-s minus its Taylor polynomial of degree < order: sum_{j >= order} (-s)^j / j!, by the series
// where it would otherwise cancel (s < 1), directly beyond.
double exp_remainder(int order, double s) {
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
// noise_model.hpp. Series below a = 0.05 (their last terms are below 1e-16 of the first there).
double markov_autocovariance(double a, int level, std::int64_t k) {
  const double ak = static_cast<double>(k < 0 ? -k : k);
  const double h = std::sinh(a / 2);
  const double a2 = a * a, a3 = a2 * a, a5 = a3 * a2;
  if (level == 0) {
    const double d = a < 0.05 ? a3 * (1.0 / 6 + a2 * (1.0 / 120 + a2 * (1.0 / 5040 + a2 / 362880))) : std::sinh(a) - a;
    return -(exp_remainder(2, a * ak) + d * ak) / (4 * h * h);
  }
  double d1, d3;
  if (a < 0.05) {
    d1 = -a5 * (1.0 / 30 + a2 * (1.0 / 252 + a2 * (1.0 / 4320 + a2 * (17.0 / 1995840 + a2 * 31.0 / 141523200))));
    d3 = a5 * (1.0 / 24 + a2 * (1.0 / 240 + a2 * (17.0 / 72576 + a2 * (31.0 / 3628800 + a2 / 4561920))));
  } else {
    d1 = std::sinh(a) * (1 - 2 * h * h / 3) - a;
    d3 = 2 * std::sinh(a) * h * h / 3 - a3 / 6;
  }
  return (exp_remainder(4, a * ak) + d1 * ak + d3 * ak * ak * ak) / (16 * h * h * h * h);
}

// c of Markov rate a (unit stationary variance) at `lag` under kernel k.
double markov_covariance(const Kernel& k, double a, std::int64_t lag) {
  double c = 0;
  for (int i = 0; i < k.count; ++i)
    c += k.w[static_cast<std::size_t>(i)] * markov_autocovariance(a, k.level, lag + k.u[static_cast<std::size_t>(i)]);
  return c;
}

}  // namespace

double markov_term_covariance(double a, Stat a_stat, std::uint64_t m_a, Stat b_stat, std::uint64_t m_b,
                              std::int64_t lag) {
  if (!(a > 0)) return 0.0;
  return markov_covariance(kernel(a_stat, m_a, b_stat, m_b), a, lag);
}

TermGrid unbroken_grid(Stat stat, std::uint64_t m, std::uint64_t stride, std::uint64_t n_phase) {
  TermGrid g{stat, m, stride, 0, 0};
  if (m == 0 || stride == 0) return g;
  const std::uint64_t earliest = first_newest_point(stat, m);
  g.first = (earliest + stride - 1) / stride * stride;
  if (n_phase == 0 || g.first > n_phase - 1) return g;
  g.n = (n_phase - 1 - g.first) / stride + 1;
  return g;
}

namespace {

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
bool pair_setup(const NoiseSet& set, const TermGrid& a, const TermGrid& b, PairSetup& s) {
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
  s.pairs = PairCounter{static_cast<std::int64_t>(a.first),
                        static_cast<std::int64_t>(a.first + (a.n - 1) * a.stride),
                        static_cast<std::int64_t>(b.first),
                        static_cast<std::int64_t>(b.first + (b.n - 1) * b.stride),
                        static_cast<std::int64_t>(a.stride),
                        static_cast<std::int64_t>(b.stride),
                        static_cast<std::int64_t>(a.n),
                        static_cast<std::int64_t>(b.n)};
  s.extent_lo = s.pairs.first_a - s.pairs.last_b;
  s.extent_hi = s.pairs.last_a - s.pairs.first_b;
  return true;
}

// Breakpoints in [lo, hi], sorted: where an R argument crosses 0, and where the pair count has a
// kink. Returns their number.
int pair_breaks(const PairSetup& s, std::int64_t lo, std::int64_t hi, std::array<std::int64_t, 72>& breaks) {
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
std::int64_t smooth_step(const TermGrid& a, const TermGrid& b, std::int64_t step) {
  const std::uint64_t m_max = a.m > b.m ? a.m : b.m;
  const std::int64_t max_step = static_cast<std::int64_t>(m_max / 256) / step * step;
  return max_step < step ? step : max_step;
}

// Beyond three kernel widths a flicker noise's c falls as lag^-p from the kernel's centre: p for
// each noise of s (0 for the others).
std::array<double, max_noises> tail_powers(const PairSetup& s, const TermGrid& a, const TermGrid& b) {
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

  NoiseAtAnyLag(const PairSetup& s, const TermGrid& a, const TermGrid& b)
      : span_lo(-s.k.u_max()), span_hi(-s.k.u_min()), center(-0.5 * static_cast<double>(s.k.u_min() + s.k.u_max())),
        p(tail_powers(s, a, b)) {
    const std::int64_t width = span_hi - span_lo + 1;
    flicker_lo = span_lo - 3 * width;
    flicker_hi = span_hi + 3 * width;
    if (!s.many.flicker) return;
    covariances(s.k, s.many, flicker_lo, tail_lo);
    covariances(s.k, s.many, flicker_hi, tail_hi);
  }
  bool inside(std::int64_t lag) const { return lag >= span_lo && lag <= span_hi; }
  void at(const PairSetup& s, std::int64_t lag, std::array<double, max_noises>& c) const {
    c.fill(0.0);
    const bool near = lag >= flicker_lo && lag <= flicker_hi;
    if (inside(lag) || (s.many.flicker && near)) covariances(s.k, s.many, lag, c);
    if (inside(lag)) return;
    for (std::size_t t = 0; t < s.many.count; ++t) {
      if (s.many.twice_d[t] % 2 == 0) {
        c[t] = 0;  // beyond the span: zero but for rounding
      } else if (!near) {
        const bool left = lag < flicker_lo;
        const double L = std::fabs(static_cast<double>(left ? flicker_lo : flicker_hi) - center);
        c[t] = (left ? tail_lo[t] : tail_hi[t]) * std::pow(L / std::fabs(static_cast<double>(lag) - center), p[t]);
      }
    }
  }
};

}  // namespace

namespace {

// One pair_sums() evaluation: its lags, nodes and sums; the covariances at each node are given to it.
struct PowerPass {
  PairSetup setup;
  PairSums out;
  std::int64_t lo = 0, hi = 0, max_step = 0;
  std::array<std::int64_t, 72> breaks{};
  int n_breaks = 0;

  // False when there is nothing to sum (out stays zero).
  bool prepare(const NoiseSet& set, const TermGrid& a, const TermGrid& b) {
    if (!pair_setup(set, a, b, setup)) return false;
    const Kernel& k = setup.k;
    const std::int64_t step = setup.step;
    // Lags with pairs, and the reach of c: (-u_max, -u_min) for polynomial noises. Flicker noises
    // reach further, with c ~ lag^-p (p = the kernel's difference order minus the leading power of
    // R): summed directly out to three kernel widths, beyond which the sum is the integral of that
    // power law (its share there is below 1 %, the power law's own error a few percent of it). Far
    // out, c is a difference of huge nearly equal values and could not be evaluated directly.
    const std::int64_t width = k.u_max() - k.u_min() + 1;
    const std::int64_t reach = setup.many.flicker ? 3 * width : 0;
    lo = setup.extent_lo, hi = setup.extent_hi;
    if (lo < -k.u_max() - reach) lo = ceil_div(-k.u_max() - reach, step) * step;
    if (hi > -k.u_min() + reach) hi = floor_div(-k.u_min() + reach, step) * step;
    if (lo > hi) return false;
    n_breaks = pair_breaks(setup, lo, hi, breaks);
    max_step = smooth_step(a, b, step);
    return true;
  }
  NodeWalker walker() const {
    return NodeWalker(lo, hi, setup.step, max_step, -setup.k.u_max(), -setup.k.u_min(), breaks.data(), n_breaks);
  }
  // The node's weight times its pairs (0: nothing to add there).
  double weight_at(std::int64_t lag, double weight) const { return weight * static_cast<double>(setup.pairs(lag)); }
  void accumulate(double w, const std::array<double, max_noises>& c) {
    for (std::size_t t = 0; t < setup.many.count; ++t) {
      out.c[t] += w * c[t];
      for (std::size_t u = 0; u <= t; ++u) out.cc[t][u] += w * c[t] * c[u];
    }
  }
  // The power-law tails beyond lo and hi, out to the lags that have pairs; cc made symmetric.
  void finish(const TermGrid& a, const TermGrid& b) {
    const Kernel& k = setup.k;
    const auto& twice_d = setup.many.twice_d;
    const std::size_t noises = setup.many.count;
    const PairCounter& pairs = setup.pairs;
    if (setup.many.flicker) {
      const double center = -0.5 * static_cast<double>(k.u_min() + k.u_max());
      const std::array<double, max_noises> p = tail_powers(setup, a, b);
      for (const std::int64_t edge : {lo, hi}) {
        const bool left = edge == lo;
        if (left ? setup.extent_lo >= lo : setup.extent_hi <= hi) continue;
        const double pairs_at = static_cast<double>(pairs(edge));
        if (pairs_at == 0) continue;
        const double L = std::fabs(static_cast<double>(edge) - center);
        const double L_max = std::fabs(static_cast<double>(left ? setup.extent_lo : setup.extent_hi) - center);
        std::array<double, max_noises> c{};
        covariances(k, setup.many, edge, c);
        // sum over the lattice beyond the edge = integral / step - f(edge) / 2 (Euler-Maclaurin),
        // with f = pairs(edge) c_t c_u (L / x)^(p_t + p_u) and the pair count taken as constant.
        for (std::size_t t = 0; t < noises; ++t) {
          if (twice_d[t] % 2 == 0) continue;
          const double lin = L / (p[t] - 1) * (1 - std::pow(L / L_max, p[t] - 1)) / static_cast<double>(setup.step) - 0.5;
          out.c[t] += pairs_at * c[t] * lin;
          for (std::size_t u = 0; u <= t; ++u) {
            if (twice_d[u] % 2 == 0) continue;
            const double q = p[t] + p[u];
            const double sq = L / (q - 1) * (1 - std::pow(L / L_max, q - 1)) / static_cast<double>(setup.step) - 0.5;
            out.cc[t][u] += pairs_at * c[t] * c[u] * sq;
          }
        }
      }
    }
    for (std::size_t t = 0; t < noises; ++t)
      for (std::size_t u = 0; u < t; ++u) out.cc[u][t] = out.cc[t][u];
  }
};

}  // namespace

PairSums pair_sums(const NoiseSet& set, const TermGrid& a, const TermGrid& b) {
  PowerPass pass;
  if (!pass.prepare(set, a, b)) return pass.out;
  NodeWalker walk = pass.walker();
  std::int64_t lag = 0;
  double weight = 0;
  while (walk.next(lag, weight)) {
    const double w = pass.weight_at(lag, weight);
    if (w == 0) continue;
    std::array<double, max_noises> c{};
    covariances(pass.setup.k, pass.setup.many, lag, c);
    pass.accumulate(w, c);
  }
  pass.finish(a, b);
  return pass.out;
}

void pair_sums_of_two(const NoiseSet& set, const TermGrid& a1, const TermGrid& b1, const TermGrid& a2,
                      const TermGrid& b2, PairSums& out1, PairSums& out2) {
  const bool same_kernel = a1.stat == a2.stat && a1.m == a2.m && b1.stat == b2.stat && b1.m == b2.m &&
                           a1.stride == a2.stride && b1.stride == b2.stride;
  PowerPass one, two;
  const bool has_one = one.prepare(set, a1, b1), has_two = two.prepare(set, a2, b2);
  if (!same_kernel || !has_one || !has_two) {
    out1 = pair_sums(set, a1, b1);
    out2 = pair_sums(set, a2, b2);
    return;
  }
  // The two walks in step: a lag both visit has its covariances evaluated once.
  NodeWalker walk1 = one.walker(), walk2 = two.walker();
  std::int64_t lag1 = 0, lag2 = 0;
  double weight1 = 0, weight2 = 0;
  bool more1 = walk1.next(lag1, weight1), more2 = walk2.next(lag2, weight2);
  while (more1 || more2) {
    const bool take1 = more1 && (!more2 || lag1 <= lag2), take2 = more2 && (!more1 || lag2 <= lag1);
    const std::int64_t lag = take1 ? lag1 : lag2;
    const double w1 = take1 ? one.weight_at(lag, weight1) : 0.0, w2 = take2 ? two.weight_at(lag, weight2) : 0.0;
    if (w1 != 0 || w2 != 0) {
      std::array<double, max_noises> c{};
      covariances(one.setup.k, one.setup.many, lag, c);
      if (w1 != 0) one.accumulate(w1, c);
      if (w2 != 0) two.accumulate(w2, c);
    }
    if (take1) more1 = walk1.next(lag1, weight1);
    if (take2) more2 = walk2.next(lag2, weight2);
  }
  one.finish(a1, b1);
  two.finish(a2, b2);
  out1 = one.out;
  out2 = two.out;
}

MarkovPairSums markov_pair_sums(const NoiseSet& set, std::span<const double> rates, const TermGrid& a,
                                const TermGrid& b) {
  MarkovPairSums out;
  PairSetup setup;
  const std::size_t markov = rates.size() < max_markov_rates ? rates.size() : max_markov_rates;
  if (markov == 0 || !pair_setup(set, a, b, setup)) return out;
  double slowest = rates[0];
  for (std::size_t j = 0; j < markov; ++j) {
    if (!(rates[j] > 0)) return out;
    slowest = std::fmin(slowest, rates[j]);
  }
  const Kernel& k = setup.k;
  const ManyR& many = setup.many;
  const std::int64_t step = setup.step;
  // Inside [span_lo, span_hi] the R arguments have both signs. Beyond, a Markov rate's c is the
  // exponential alone: c(edge) e^(-a |lag - edge|), summed out to e^-27 (2e-12) of its edge value;
  // the power-law noises' as NoiseAtAnyLag says.
  const NoiseAtAnyLag noise(setup, a, b);
  const std::int64_t span_lo = noise.span_lo, span_hi = noise.span_hi;
  const double reach_lags = 27 / slowest;
  const std::int64_t reach = reach_lags < 4e15 ? static_cast<std::int64_t>(reach_lags) + 1 : std::int64_t{4000000000000000};
  std::int64_t lo = setup.extent_lo, hi = setup.extent_hi;
  if (lo < span_lo - reach) lo = ceil_div(span_lo - reach, step) * step;
  if (hi > span_hi + reach) hi = floor_div(span_hi + reach, step) * step;
  if (lo > hi) return out;
  std::array<std::int64_t, 72> breaks{};
  const int n_breaks = pair_breaks(setup, lo, hi, breaks);
  std::array<double, max_markov_rates> edge_lo{}, edge_hi{};
  for (std::size_t j = 0; j < markov; ++j) {
    edge_lo[j] = markov_covariance(k, rates[j], span_lo);
    edge_hi[j] = markov_covariance(k, rates[j], span_hi);
  }
  visit_nodes(lo, hi, step, smooth_step(a, b, step), span_lo, span_hi, breaks.data(), n_breaks,
              [&](std::int64_t lag, double weight) {
                const double w = weight * static_cast<double>(setup.pairs(lag));
                if (w == 0) return;
                std::array<double, max_noises> c{};
                std::array<double, max_markov_rates> cm{};
                const bool inside = noise.inside(lag);
                noise.at(setup, lag, c);
                for (std::size_t j = 0; j < markov; ++j)
                  cm[j] = inside          ? markov_covariance(k, rates[j], lag)
                          : lag < span_lo ? edge_lo[j] * std::exp(-rates[j] * static_cast<double>(span_lo - lag))
                                          : edge_hi[j] * std::exp(-rates[j] * static_cast<double>(lag - span_hi));
                for (std::size_t j = 0; j < markov; ++j) {
                  out.c[j] += w * cm[j];
                  for (std::size_t t = 0; t < many.count; ++t) out.cm[j][t] += w * cm[j] * c[t];
                  for (std::size_t l = 0; l <= j; ++l) out.mm[j][l] += w * cm[j] * cm[l];
                }
              });
  for (std::size_t j = 0; j < markov; ++j)
    for (std::size_t l = 0; l < j; ++l) out.mm[l][j] = out.mm[j][l];
  return out;
}

namespace {

// The response sum_k w_k e^(i theta o_k) of a term's taps: its real and imaginary parts.
void response(const Taps& t, double theta, double& re, double& im) {
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

SinusoidKernel sinusoid_kernel(double theta, Stat a, std::uint64_t m_a, Stat b, std::uint64_t m_b) {
  const int level = a == Stat::mvar || b == Stat::mvar ? 1 : 0;
  double ar, ai, br, bi;
  response(taps(a, m_a, level), theta, ar, ai);
  response(taps(b, m_b, level), theta, br, bi);
  const double half = std::sin(theta / 2);
  const double scale = 1 / (2 * theta * theta * (level == 1 ? 4 * half * half : 1.0));
  return {theta, (ar * br + ai * bi) * scale, (ai * br - ar * bi) * scale};
}

}  // namespace

double sinusoid_term_covariance(double theta, Stat a_stat, std::uint64_t m_a, Stat b_stat, std::uint64_t m_b,
                                std::int64_t lag) {
  if (!(theta > 0 && theta <= pi)) return 0.0;
  return sinusoid_kernel(theta, a_stat, m_a, b_stat, m_b).at(lag);
}

SinusoidPairSums sinusoid_pair_sums(const NoiseSet& set, std::span<const double> thetas, const TermGrid& a,
                                    const TermGrid& b) {
  SinusoidPairSums out;
  PairSetup setup;
  const std::size_t count = thetas.size() < max_sinusoid_rates ? thetas.size() : max_sinusoid_rates;
  if (count == 0 || !pair_setup(set, a, b, setup)) return out;
  const double m_max = static_cast<double>(a.m > b.m ? a.m : b.m);
  std::array<SinusoidKernel, max_sinusoid_rates> sk{};
  double fastest = 0;
  for (std::size_t j = 0; j < count; ++j) {
    const double theta = thetas[j];
    if (!(theta > 0 && theta <= pi) || theta * m_max / 2 > 64) continue;
    sk[j] = sinusoid_kernel(theta, a.stat, a.m, b.stat, b.m);
    fastest = std::fmax(fastest, theta);
  }
  if (fastest == 0) return out;
  const ManyR& many = setup.many;
  const std::int64_t step = setup.step;
  // The noises' c as NoiseAtAnyLag gives it, summed out to four periods of the slowest sinusoid
  // beyond a flicker noise's three kernel widths, where the oscillation has cancelled the rest.
  const NoiseAtAnyLag noise(setup, a, b);
  const std::int64_t span_lo = noise.span_lo, span_hi = noise.span_hi;
  const std::int64_t width = span_hi - span_lo + 1;
  double slowest = pi;
  for (std::size_t j = 0; j < count; ++j)
    if (sk[j].theta > 0) slowest = std::fmin(slowest, sk[j].theta);
  const std::int64_t reach = many.flicker ? 3 * width + static_cast<std::int64_t>(8 * pi / slowest) + 1 : 0;
  std::int64_t lo = setup.extent_lo, hi = setup.extent_hi;
  if (lo < span_lo - reach) lo = ceil_div(span_lo - reach, step) * step;
  if (hi > span_hi + reach) hi = floor_div(span_hi + reach, step) * step;
  if (lo > hi) return out;
  std::array<std::int64_t, 72> breaks{};
  const int n_breaks = pair_breaks(setup, lo, hi, breaks);
  // A tenth of the fastest sinusoid's period at most, and no more than the power-law sums take.
  std::int64_t max_step = static_cast<std::int64_t>(2 * pi / (10 * fastest)) / step * step;
  const std::int64_t power_step = smooth_step(a, b, step);
  max_step = max_step < step ? step : max_step > power_step ? power_step : max_step;
  visit_nodes(lo, hi, step, max_step, lo, hi, breaks.data(), n_breaks, [&](std::int64_t lag, double weight) {
    const double w = weight * static_cast<double>(setup.pairs(lag));
    if (w == 0) return;
    std::array<double, max_noises> c{};
    noise.at(setup, lag, c);
    for (std::size_t j = 0; j < count; ++j) {
      if (sk[j].theta == 0) continue;
      const double cj = sk[j].at(lag);
      for (std::size_t t = 0; t < many.count; ++t) out.cs[j][t] += w * cj * c[t];
    }
  });
  return out;
}

double pair_sums_rounding(int alpha, const TermGrid& a, const TermGrid& b) {
  if (!noise_supported(a.stat, alpha) || !noise_supported(b.stat, alpha)) return 0.0;
  const Kernel k = kernel(a.stat, a.m, b.stat, b.m);
  const int twice_d = 2 - alpha + 2 * k.level;
  // The widest argument of R that pair_sums() evaluates: the kernel's span, and for flicker noises
  // the tails summed directly out to three kernel widths beyond it.
  const std::int64_t width = k.u_max() - k.u_min() + 1;
  const std::int64_t widest = twice_d % 2 != 0 ? 4 * width : width;
  double weights = 0;
  for (int i = 0; i < k.count; ++i) weights += std::fabs(k.w[static_cast<std::size_t>(i)]);
  const double r_max = std::fmax(std::fabs(generalized_autocovariance(twice_d, widest)),
                                 std::fabs(generalized_autocovariance(twice_d, 0)));
  // Error of one c(lag) (a sum of k.count products, R itself good to a few ulps), relative to
  // the terms' own standard deviations.
  constexpr double ulp = 2.220446049250313e-16;
  const double sd = std::sqrt(term_covariance(alpha, a.stat, a.m, a.stat, a.m, 0) *
                              term_covariance(alpha, b.stat, b.m, b.stat, b.m, 0));
  if (!(sd > 0)) return 0.0;
  const double delta = 16 * ulp * weights * r_max / sd;
  // sum c^2 over the pairs at about `width` lags, against sqrt(sum c_a^2 sum c_b^2) over the
  // estimates' own reaches: |c| <= sd, so the correlation moves by at most (2 delta + delta^2)
  // times width / sqrt(width_a width_b).
  const Kernel ka = kernel(a.stat, a.m, a.stat, a.m), kb = kernel(b.stat, b.m, b.stat, b.m);
  const double wa = static_cast<double>(ka.u_max() - ka.u_min() + 1), wb = static_cast<double>(kb.u_max() - kb.u_min() + 1);
  return (2 * delta + delta * delta) * static_cast<double>(widest) / std::sqrt(wa * wb);
}

double exact_skew_dof(int alpha, const TermGrid& g) {
  if (g.n == 0 || !noise_supported(g.stat, alpha)) return 0.0;
  const Kernel k = kernel(g.stat, g.m, g.stat, g.m);
  const int twice_d = 2 - alpha + 2 * k.level;
  const auto s = static_cast<std::int64_t>(g.stride);
  const auto n = static_cast<std::int64_t>(g.n);
  // Lags (in strides) with c != 0: the kernel's reach, plus three widths of flicker tail (c^3
  // falls as lag^-6 or faster there).
  std::int64_t reach = (k.u_max() + s - 1) / s;
  if (twice_d % 2 != 0) reach += 3 * (k.u_max() - k.u_min() + 1) / s;
  if (reach > n - 1) reach = n - 1;
  auto count = [n](std::int64_t u, std::int64_t v) {  // (i, j, l) with i - j = u, j - l = v
    const std::int64_t w = u + v;
    const std::int64_t hi = u > 0 ? (w > u ? w : u) : (w > 0 ? w : 0);
    const std::int64_t lo = u < 0 ? (w < u ? w : u) : (w < 0 ? w : 0);
    return static_cast<double>(n - (hi - lo) > 0 ? n - (hi - lo) : 0);
  };
  double c3 = 0;
  if (twice_d == 0) {  // white PM, unmodified: c lives on the lags that are multiples of m
    std::array<std::int64_t, 7> lags{};
    std::array<double, 7> c{};
    int nz = 0;
    for (std::int64_t j = -3; j <= 3; ++j) {
      const std::int64_t lag = j * static_cast<std::int64_t>(g.m);
      if (lag % s != 0 || lag / s > reach || -lag / s > reach) continue;
      lags[static_cast<std::size_t>(nz)] = lag / s;
      c[static_cast<std::size_t>(nz++)] = covariance(k, twice_d, lag);
    }
    for (int a = 0; a < nz; ++a)
      for (int b = 0; b < nz; ++b) {
        const std::int64_t w = lags[static_cast<std::size_t>(a)] + lags[static_cast<std::size_t>(b)];
        for (int d = 0; d < nz; ++d)
          if (lags[static_cast<std::size_t>(d)] == w)
            c3 += c[static_cast<std::size_t>(a)] * c[static_cast<std::size_t>(b)] * c[static_cast<std::size_t>(d)] *
                  count(lags[static_cast<std::size_t>(a)], lags[static_cast<std::size_t>(b)]);
      }
  } else {
    constexpr std::int64_t cap = 256;
    std::int64_t q = 1;
    while (reach / q > cap) q *= 2;
    const std::int64_t top = reach / q;
    std::array<double, 2 * cap + 2> table{};  // c at lags 0, q, 2q, ... 2 top (u + v reaches 2 top)
    for (std::int64_t j = 0; j <= 2 * top; ++j) table[static_cast<std::size_t>(j)] = j * q <= reach ? covariance(k, twice_d, j * q * s) : 0.0;
    auto c = [&](std::int64_t j) { return table[static_cast<std::size_t>(j < 0 ? -j : j)]; };
    for (std::int64_t u = -top; u <= top; ++u)
      for (std::int64_t v = -top; v <= top; ++v) {
        const std::int64_t w = u + v;
        if (w > top || w < -top) continue;
        c3 += c(u) * c(v) * c(w) * count(u * q, v * q);
      }
    c3 *= static_cast<double>(q * q);
  }
  NoiseSet set;
  set.alpha[0] = alpha;
  set.count = 1;
  const double c2 = pair_sums(set, g, g).cc[0][0];  // tr C^2
  if (!(c3 > 0) || !(c2 > 0)) return 0.0;
  const double k2 = 2 * c2, k3 = 8 * c3;
  return 8 * k2 * k2 * k2 / (k3 * k3);
}

NoiseSet allan_noises() {
  NoiseSet set;
  set.alpha = {2, 1, 0, -1, -2};
  set.count = 5;
  return set;
}

namespace {

void add_scaled(PairSums& out, const PairSums& a, double k, const PairSums& b) {
  for (std::size_t t = 0; t < max_noises; ++t) {
    out.c[t] = a.c[t] * k + b.c[t];
    for (std::size_t u = 0; u < max_noises; ++u) out.cc[t][u] = a.cc[t][u] * k + b.cc[t][u];
  }
}

}  // namespace

PairSumCache::Entry* PairSumCache::slot(const TermGrid& a, const TermGrid& b) {
  if (entries_.empty() || a.stat == Stat::hvar || b.stat == Stat::hvar) return nullptr;
  // Open addressing on the grids' shape.
  std::uint64_t h = (a.m * 0x9E3779B97F4A7C15u) ^ (b.m * 0xC2B2AE3D27D4EB4Fu) ^ (a.stride << 7) ^ (b.stride << 13) ^
                    (static_cast<std::uint64_t>(a.stat) << 3) ^ (static_cast<std::uint64_t>(b.stat) << 5);
  // At most 64 probes: a full table (say a dense tau list's) answers "not kept" in O(1).
  Entry* entry = nullptr;
  for (std::size_t probe = 0; probe < entries_.size() && probe < 64; ++probe) {
    Entry& e = entries_[static_cast<std::size_t>((h + probe) % entries_.size())];
    if (!e.used || (e.stat_a == a.stat && e.stat_b == b.stat && e.m_a == a.m && e.m_b == b.m &&
                    e.stride_a == a.stride && e.stride_b == b.stride)) {
      entry = &e;
      break;
    }
  }
  return entry;
}

PairSums PairSumCache::get(const TermGrid& a, const TermGrid& b) {
  if (PairSums found; source_ != nullptr && source_->find(a, b, found)) return found;
  const NoiseSet set = allan_noises();
  Entry* entry = slot(a, b);
  if (entry == nullptr) return pair_sums(set, a, b);  // hvar, or full
  const bool a_coarse = a.stride >= b.stride;
  const std::uint64_t n = a_coarse ? a.n : b.n;
  if (entry->used && entry->linear && n >= entry->from) {
    PairSums out;
    add_scaled(out, entry->slope, static_cast<double>(n), entry->sums);
    return out;
  }
  // Short grids: the last sums, scaled with the coarse grid's terms while both grids have grown by
  // less than 2 % (the sums are nearly proportional to it: the EDF moves by less than 1e-3), or by
  // 10 % for grids of different taus (their covariance only weights the fit: 1 % at most).
  const std::uint64_t growth = a.m == b.m ? 50 : 10;
  if (entry->used && !entry->linear && a.n >= entry->n_a && b.n >= entry->n_b &&
      growth * (a.n - entry->n_a) <= entry->n_a && growth * (b.n - entry->n_b) <= entry->n_b) {
    PairSums out;
    add_scaled(out, entry->sums, static_cast<double>(n) / static_cast<double>(a_coarse ? entry->n_a : entry->n_b),
               PairSums{});
    return out;
  }
  *entry = Entry{};
  entry->used = true;
  entry->stat_a = a.stat, entry->stat_b = b.stat, entry->m_a = a.m, entry->m_b = b.m;
  entry->stride_a = a.stride, entry->stride_b = b.stride;
  // Linear once the coarse grid spans the terms' reach 8 times over: the flicker tails (summed
  // out to the lags that have pairs) then change by less than 1e-4 of the sums.
  const std::uint64_t coarse = a_coarse ? a.stride : b.stride;
  const std::uint64_t span = 3 * (a.m > b.m ? a.m : b.m) + 2;
  const std::uint64_t from = (8 * span) / coarse + 4;
  if (n >= from) {
    const std::uint64_t first = first_newest_point(a.stat, a.m) > first_newest_point(b.stat, b.m)
                                    ? first_newest_point(a.stat, a.m)
                                    : first_newest_point(b.stat, b.m);
    const std::uint64_t n1 = first + (from + 2) * coarse, n2 = n1 + 8 * span + 8 * coarse;
    const TermGrid a1 = unbroken_grid(a.stat, a.m, a.stride, n1), b1 = unbroken_grid(b.stat, b.m, b.stride, n1);
    const TermGrid a2 = unbroken_grid(a.stat, a.m, a.stride, n2), b2 = unbroken_grid(b.stat, b.m, b.stride, n2);
    PairSums s1, s2;
    pair_sums_of_two(set, a1, b1, a2, b2, s1, s2);
    const double c1 = static_cast<double>(a_coarse ? a1.n : b1.n), c2 = static_cast<double>(a_coarse ? a2.n : b2.n);
    PairSums minus;
    add_scaled(minus, s1, -1.0, PairSums{});
    add_scaled(entry->slope, s2, 1.0, minus);  // s2 - s1
    add_scaled(entry->slope, entry->slope, 1.0 / (c2 - c1), PairSums{});
    add_scaled(entry->sums, entry->slope, -c1, s1);  // intercept
    entry->linear = true;
    entry->from = a_coarse ? a1.n : b1.n;
    PairSums out;
    add_scaled(out, entry->slope, static_cast<double>(n), entry->sums);
    return out;
  }
  entry->n_a = a.n;
  entry->n_b = b.n;
  entry->sums = pair_sums(set, a, b);
  return entry->sums;
}

namespace {

bool same_grid(const TermGrid& a, const TermGrid& b) {
  return a.stat == b.stat && a.m == b.m && a.stride == b.stride && a.first == b.first && a.n == b.n;
}

}  // namespace

SinusoidPairSums PairSumCache::sinusoid_sums(const NoiseSet& set, std::span<const double> thetas, const TermGrid& a,
                                             const TermGrid& b) {
  const std::size_t count = thetas.size() < max_sinusoid_rates ? thetas.size() : max_sinusoid_rates;
  std::uint64_t h = (a.m * 0x9E3779B97F4A7C15u) ^ (b.m * 0xC2B2AE3D27D4EB4Fu) ^ (a.n << 7) ^ (b.n << 13) ^
                    (static_cast<std::uint64_t>(a.stat) << 3) ^ (static_cast<std::uint64_t>(b.stat) << 5);
  for (std::size_t probe = 0; probe < sinusoids_.size() && probe < 64; ++probe) {
    SinusoidEntry& e = sinusoids_[static_cast<std::size_t>((h + probe) % sinusoids_.size())];
    if (e.used) {
      bool same = e.count == count && e.set.count == set.count && same_grid(e.a, a) && same_grid(e.b, b);
      for (std::size_t t = 0; same && t < set.count; ++t) same = e.set.alpha[t] == set.alpha[t];
      for (std::size_t j = 0; same && j < count; ++j) same = e.thetas[j] == thetas[j];
      if (same) return e.sums;
      continue;
    }
    e.used = true;
    e.set = set;
    e.a = a;
    e.b = b;
    e.count = count;
    for (std::size_t j = 0; j < count; ++j) e.thetas[j] = thetas[j];
    e.sums = sinusoid_pair_sums(set, thetas, a, b);
    return e.sums;
  }
  return sinusoid_pair_sums(set, thetas, a, b);
}

void PairSumCache::clear() {
  for (Entry& e : entries_) e = Entry{};
  for (SinusoidEntry& e : sinusoids_) e = SinusoidEntry{};
}

double exact_edf(int alpha, const TermGrid& g) {
  if (g.n == 0 || !noise_supported(g.stat, alpha)) return 0.0;
  NoiseSet set;
  set.alpha[0] = alpha;
  set.count = 1;
  const double sum = pair_sums(set, g, g).cc[0][0];
  const double c0 = term_covariance(alpha, g.stat, g.m, g.stat, g.m, 0);
  const double n = static_cast<double>(g.n);
  return sum > 0 ? n * n * c0 * c0 / sum : 0.0;
}

}  // namespace gyrochar
