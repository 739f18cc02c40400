// Exact second moments of the Allan-family estimators under discrete-time power-law noise (see
// noise_model.hpp for the model and the closed forms).
#include "gyrochar/noise_model.hpp"

#include <cmath>

namespace gyrochar {
namespace {

constexpr double pi = 3.14159265358979323846;

// psi(n + 1/2) for any integer n (psi(1/2 - n) = psi(1/2 + n) by the reflection formula, since
// cot(pi (n + 1/2)) = 0). Small arguments by the recurrence psi(z + 1) = psi(z) + 1/z from
// psi(1/2) = -gamma - 2 ln 2, large ones by the asymptotic series (error below 1e-17 for z >= 16).
double digamma_half(std::int64_t n) {
  const double a = static_cast<double>(n < 0 ? -n : n);
  if (a < 16) {
    double s = -1.96351002602142347944;  // psi(1/2)
    for (double i = 0; i < a; i += 1) s += 1.0 / (i + 0.5);
    return s;
  }
  const double z = a + 0.5, w = 1.0 / (z * z);
  return std::log(z) - 0.5 / z - w * (1.0 / 12 - w * (1.0 / 120 - w * (1.0 / 252 - w * (1.0 / 240 - w / 132))));
}

double factorial(int n) {
  double f = 1;
  for (int i = 2; i <= n; ++i) f *= i;
  return f;
}

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

double covariance(const Kernel& k, int twice_d, std::int64_t lag) {
  double c = 0;
  for (int i = 0; i < k.count; ++i)
    c += k.w[static_cast<std::size_t>(i)] * generalized_autocovariance(twice_d, lag + k.u[static_cast<std::size_t>(i)]);
  return c;
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

template <class Visit>
void visit_nodes(std::int64_t lo, std::int64_t hi, std::int64_t step, std::int64_t max_step, std::int64_t smooth_lo,
                 std::int64_t smooth_hi, const std::int64_t* breaks, int n_breaks, Visit&& visit) {
  const double lattice = static_cast<double>(step);
  std::int64_t previous = 0, current = 0;
  bool have_previous = false, have_current = false;
  auto emit = [&](std::int64_t next) {  // the weight of `current` is known once `next` is
    if (have_current) {
      const double left = static_cast<double>(current - (have_previous ? previous : current));
      visit(current, (left + static_cast<double>(next - current)) / (2 * lattice) + (have_previous ? 0.0 : 0.5));
      previous = current;
      have_previous = true;
    }
    current = next;
    have_current = true;
  };
  int b = 0;
  for (std::int64_t node = lo;;) {
    emit(node);
    if (node >= hi) break;
    while (b < n_breaks && breaks[b] <= node) ++b;
    const std::int64_t to_previous = node - (b > 0 ? breaks[b - 1] : lo);
    const std::int64_t to_next = (b < n_breaks ? breaks[b] : hi) - node;
    std::int64_t h = ((to_previous < to_next ? to_previous : to_next) / (grading * step)) * step;
    if (node >= smooth_lo && node <= smooth_hi && h > max_step) h = max_step;
    if (h < step) h = step;
    if (b < n_breaks && node + h > breaks[b]) h = breaks[b] - node;
    if (node + h > hi) h = hi - node;
    node += h;
  }
  visit(current, have_previous ? static_cast<double>(current - previous) / (2 * lattice) + 0.5 : 1.0);
}

}  // namespace

double generalized_autocovariance(int twice_d, std::int64_t k) {
  const double a = static_cast<double>(k < 0 ? -k : k);
  if (twice_d <= 0) return k == 0 ? 1.0 : 0.0;
  if (twice_d % 2 == 0) {
    const int j = twice_d / 2;
    double p = a;
    for (int i = 1; i < j; ++i) p *= a * a - static_cast<double>(i) * i;
    return (j % 2 ? -p : p) / (2 * factorial(2 * j - 1));
  }
  const int j = (twice_d - 1) / 2;
  double p = 1;
  for (int i = 1; i <= j; ++i) p *= a * a - (i - 0.5) * (i - 0.5);
  const std::int64_t ak = k < 0 ? -k : k;
  const double s = digamma_half(ak + j) + digamma_half(ak - j);
  return (j % 2 ? p : -p) * s / (2 * pi * factorial(2 * j));
}

double term_covariance(int alpha, Stat a, std::uint64_t m_a, Stat b, std::uint64_t m_b, std::int64_t lag) {
  if (!noise_supported(a, alpha) || !noise_supported(b, alpha)) return 0.0;
  const Kernel k = kernel(a, m_a, b, m_b);
  return covariance(k, 2 - alpha + 2 * k.level, lag);
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

PairSums pair_sums(const NoiseSet& set, const TermGrid& a, const TermGrid& b) {
  PairSums out;
  if (a.n == 0 || b.n == 0 || a.stride == 0 || b.stride == 0) return out;
  const std::uint64_t fine = a.stride < b.stride ? a.stride : b.stride;
  const std::uint64_t coarse = a.stride < b.stride ? b.stride : a.stride;
  if (coarse % fine != 0) return out;  // strides must nest (powers of two always do)
  const Kernel k = kernel(a.stat, a.m, b.stat, b.m);
  std::array<int, max_noises> twice_d{};
  bool flicker = false;
  std::size_t noises = 0;
  for (std::size_t t = 0; t < set.count && t < max_noises; ++t) {
    if (!noise_supported(a.stat, set.alpha[t]) || !noise_supported(b.stat, set.alpha[t])) return out;
    twice_d[t] = 2 - set.alpha[t] + 2 * k.level;
    flicker |= twice_d[t] % 2 != 0;
    noises = t + 1;
  }
  const auto step = static_cast<std::int64_t>(fine);
  const PairCounter pairs{static_cast<std::int64_t>(a.first),
                          static_cast<std::int64_t>(a.first + (a.n - 1) * a.stride),
                          static_cast<std::int64_t>(b.first),
                          static_cast<std::int64_t>(b.first + (b.n - 1) * b.stride),
                          static_cast<std::int64_t>(a.stride),
                          static_cast<std::int64_t>(b.stride),
                          static_cast<std::int64_t>(a.n),
                          static_cast<std::int64_t>(b.n)};
  // Lags with pairs, and the reach of c: (-u_max, -u_min) for polynomial noises. Flicker noises
  // reach further, with c ~ lag^-p (p = the kernel's difference order minus the leading power of
  // R): summed directly out to three kernel widths, beyond which the sum is the integral of that
  // power law (its share there is below 1 %, the power law's own error a few percent of it). Far
  // out, c is a difference of huge nearly equal values and could not be evaluated directly.
  const std::int64_t extent_lo = pairs.first_a - pairs.last_b, extent_hi = pairs.last_a - pairs.first_b;
  const std::int64_t width = k.u_max() - k.u_min() + 1;
  const std::int64_t reach = flicker ? 3 * width : 0;
  std::int64_t lo = extent_lo, hi = extent_hi;
  if (lo < -k.u_max() - reach) lo = ceil_div(-k.u_max() - reach, step) * step;
  if (hi > -k.u_min() + reach) hi = floor_div(-k.u_min() + reach, step) * step;
  if (lo > hi) return out;
  // Breakpoints: where an R argument crosses 0, and where the pair count has a kink.
  std::array<std::int64_t, 72> breaks{};
  int n_breaks = 0;
  auto add_break = [&](std::int64_t v) {
    v = floor_div(v, step) * step;
    if (v < lo || v > hi) return;
    int p = 0;
    while (p < n_breaks && breaks[static_cast<std::size_t>(p)] < v) ++p;
    if (p < n_breaks && breaks[static_cast<std::size_t>(p)] == v) return;
    for (int q = n_breaks; q > p; --q) breaks[static_cast<std::size_t>(q)] = breaks[static_cast<std::size_t>(q - 1)];
    breaks[static_cast<std::size_t>(p)] = v;
    ++n_breaks;
  };
  for (int i = 0; i < k.count; ++i) {
    add_break(-k.u[static_cast<std::size_t>(i)]);
    add_break(-k.u[static_cast<std::size_t>(i)] + step);  // the lattice point just past it
  }
  for (const std::int64_t v : {pairs.first_a - pairs.first_b, pairs.last_a - pairs.last_b, pairs.first_a - pairs.last_b,
                               pairs.last_a - pairs.first_b})
    add_break(v);
  // Away from the breakpoints c varies on the scale of the longer term: at least 256 nodes there.
  const std::uint64_t m_max = a.m > b.m ? a.m : b.m;
  std::int64_t max_step = static_cast<std::int64_t>(m_max / 256) / step * step;
  if (max_step < step) max_step = step;
  auto accumulate = [&](double w, const std::array<double, max_noises>& c) {
    for (std::size_t t = 0; t < noises; ++t) {
      out.c[t] += w * c[t];
      for (std::size_t u = 0; u <= t; ++u) out.cc[t][u] += w * c[t] * c[u];
    }
  };
  visit_nodes(lo, hi, step, max_step, -k.u_max(), -k.u_min(), breaks.data(), n_breaks,
              [&](std::int64_t lag, double weight) {
                const double w = weight * static_cast<double>(pairs(lag));
                if (w == 0) return;
                std::array<double, max_noises> c{};
                for (std::size_t t = 0; t < noises; ++t) c[t] = covariance(k, twice_d[t], lag);
                accumulate(w, c);
              });
  if (flicker) {  // the power-law tails beyond lo and hi, out to the lags that have pairs
    const double center = -0.5 * static_cast<double>(k.u_min() + k.u_max());
    const int order = difference_order(a.stat) + difference_order(b.stat) + (a.stat == Stat::mvar ? 0 : k.level) +
                      (b.stat == Stat::mvar ? 0 : k.level) + (a.stat == Stat::mvar) + (b.stat == Stat::mvar);
    for (const std::int64_t edge : {lo, hi}) {
      const bool left = edge == lo;
      if (left ? extent_lo >= lo : extent_hi <= hi) continue;
      const double pairs_at = static_cast<double>(pairs(edge));
      if (pairs_at == 0) continue;
      const double L = std::fabs(static_cast<double>(edge) - center);
      const double L_max = std::fabs(static_cast<double>(left ? extent_lo : extent_hi) - center);
      std::array<double, max_noises> c{}, p{};
      for (std::size_t t = 0; t < noises; ++t) {
        c[t] = covariance(k, twice_d[t], edge);
        p[t] = order - (twice_d[t] - 1);  // c ~ lag^-p; 0 where c vanishes beyond the reach anyway
      }
      // sum over the lattice beyond the edge = integral / step - f(edge) / 2 (Euler-Maclaurin),
      // with f = pairs(edge) c_t c_u (L / x)^(p_t + p_u) and the pair count taken as constant.
      for (std::size_t t = 0; t < noises; ++t) {
        if (twice_d[t] % 2 == 0) continue;
        const double lin = L / (p[t] - 1) * (1 - std::pow(L / L_max, p[t] - 1)) / static_cast<double>(step) - 0.5;
        out.c[t] += pairs_at * c[t] * lin;
        for (std::size_t u = 0; u <= t; ++u) {
          if (twice_d[u] % 2 == 0) continue;
          const double q = p[t] + p[u];
          const double sq = L / (q - 1) * (1 - std::pow(L / L_max, q - 1)) / static_cast<double>(step) - 0.5;
          out.cc[t][u] += pairs_at * c[t] * c[u] * sq;
        }
      }
    }
  }
  for (std::size_t t = 0; t < noises; ++t)
    for (std::size_t u = 0; u < t; ++u) out.cc[u][t] = out.cc[t][u];
  return out;
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
