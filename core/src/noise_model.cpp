// Exact second moments of the Allan-family estimators under discrete-time power-law noise (see
// noise_model.hpp for the model and the closed forms).
#include "gyrochar/noise_model.hpp"

#include <cmath>

#include "noise_kernel.hpp"

namespace gyrochar {

using namespace noise_kernel;

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

double markov_term_covariance(double a, Stat a_stat, std::uint64_t m_a, Stat b_stat, std::uint64_t m_b, std::int64_t lag) {
  if (!(a > 0)) return 0.0;
  const Kernel k = kernel(a_stat, m_a, b_stat, m_b);
  return markov_covariance(k, MarkovAutocovariance(a, k.level), lag);
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
  const NoiseAtAnyLag noise(pass.setup, a, b);
  NodeWalker walk = pass.walker();
  std::int64_t lag = 0;
  double weight = 0;
  while (walk.next(lag, weight)) {
    const double w = pass.weight_at(lag, weight);
    if (w == 0) continue;
    std::array<double, max_noises> c{};
    noise.at(pass.setup, lag, c);
    pass.accumulate(w, c);
  }
  pass.finish(a, b);
  return pass.out;
}

void pair_sums_of_two(const NoiseSet& set, const TermGrid& a1, const TermGrid& b1, const TermGrid& a2, const TermGrid& b2,
                      PairSums& out1, PairSums& out2) {
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
  const NoiseAtAnyLag noise(one.setup, a1, b1);
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
      noise.at(one.setup, lag, c);
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

MarkovPairSums markov_pair_sums(const NoiseSet& set, std::span<const double> rates, const TermGrid& a, const TermGrid& b) {
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
  std::array<MarkovAutocovariance, max_markov_rates> r{};
  for (std::size_t j = 0; j < markov; ++j) {
    r[j] = MarkovAutocovariance(rates[j], k.level);
    edge_lo[j] = markov_covariance(k, r[j], span_lo);
    edge_hi[j] = markov_covariance(k, r[j], span_hi);
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
                  cm[j] = inside          ? markov_covariance(k, r[j], lag)
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

}  // namespace gyrochar
