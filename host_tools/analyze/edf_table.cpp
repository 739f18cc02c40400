// The EDF of dense tau lists from exact anchors (see edf_table.hpp).
#include "edf_table.hpp"

#include <algorithm>
#include <cmath>
#include <span>

namespace gyrochar {
namespace {

// The largest ratio of m, and of the number of terms, between neighbouring anchors.
const double spacing = std::exp2(1.0 / 16);
// Where the skewness is kept: the read-out asks for it below an EDF of 100.
constexpr double skew_below = 200;

double interpolate(double v0, double v1, double w) {
  if (!(v0 > 0) || !(v1 > 0)) return 0.0;
  return std::exp((1 - w) * std::log(v0) + w * std::log(v1));
}

}  // namespace

std::vector<std::uint64_t> dense_anchors(std::span<const Stat> stats, std::uint64_t n_phase, std::uint64_t m_min,
                                         std::uint64_t m_max) {
  std::vector<std::uint64_t> anchors;
  const auto terms = [&](Stat s, std::uint64_t m) { return unbroken_grid(s, m, 1, n_phase).n; };
  const auto fewest = [&](std::uint64_t m) {
    std::uint64_t n = UINT64_MAX;
    for (const Stat s : stats) n = std::min(n, terms(s, m));
    return n;
  };
  if (m_min == 0 || m_min > m_max || fewest(m_max) == 0) return anchors;
  // The EDF has kinks in m where the number of terms crosses a multiple of m (the term
  // covariance has its own there, within the terms' reach of 3m): anchors on both sides.
  std::vector<std::uint64_t> kinks;
  for (const Stat s : stats) {
    for (std::uint64_t j = 1; j <= 4; ++j) {
      std::uint64_t lo = m_min, hi = m_max + 1;  // the first m with terms <= j m
      while (lo < hi) {
        const std::uint64_t mid = lo + (hi - lo) / 2;
        if (terms(s, mid) <= j * mid) hi = mid;
        else lo = mid + 1;
      }
      if (lo > m_min && lo <= m_max) kinks.insert(kinks.end(), {lo - 1, lo});
    }
  }
  std::sort(kinks.begin(), kinks.end());
  for (std::uint64_t m = m_min;;) {
    anchors.push_back(m);
    if (m == m_max) break;
    // The next anchor: m and the terms both within the spacing of this one's.
    std::uint64_t next = std::min(m_max, std::max(m + 1, static_cast<std::uint64_t>(static_cast<double>(m) * spacing)));
    const double n = static_cast<double>(fewest(m));
    while (next > m + 1 && static_cast<double>(fewest(next)) * spacing < n) next = m + (next - m) / 2;
    const auto kink = std::upper_bound(kinks.begin(), kinks.end(), m);
    if (kink != kinks.end() && *kink < next) next = *kink;
    m = next;
  }
  return anchors;
}

TauSums unbroken_sums(DevStat stat, std::uint64_t m, std::uint64_t n_phase) {
  TauSums t;
  t.m = m;
  t.stride = 1;
  t.n[static_cast<std::size_t>(sum_kind(stat))] = unbroken_grid(stat_of(stat), m, 1, n_phase).n;
  t.variance[static_cast<std::size_t>(sum_kind(stat))] = 1.0;
  return t;
}

EdfTable::EdfTable(DevStat stat, std::uint64_t n_phase, std::uint64_t m_min, std::uint64_t m_max, PairSumCache& cache)
    : stat_(stat), n_phase_(n_phase) {
  const Stat s = stat_of(stat);
  const EstimateOptions exact{1.0, 1.0, EdfModel::exact, false};
  for (const std::uint64_t m : dense_anchors(std::span<const Stat>(&s, 1), n_phase, m_min, m_max)) {
    Anchor a;
    a.m = m;
    const TauSums t = unbroken_sums(stat, m, n_phase);
    for (int alpha = 2; alpha >= -4; --alpha) {
      const NoiseId given{alpha, alpha, alpha, NoiseIdMethod::given};
      a.value[2 - alpha].edf = gyrochar::estimate(t, n_phase, stat, given, exact, &cache).edf;
      a.skew_known[2 - alpha] = !(a.value[2 - alpha].edf > 0 && a.value[2 - alpha].edf < skew_below);
    }
    anchors_.push_back(a);
  }
}

EdfTable::Value EdfTable::at(std::uint64_t m, int alpha, bool skew) const {
  if (alpha > 2 || alpha < -4) return {};
  const auto k = static_cast<std::size_t>(2 - alpha);
  const auto hi = std::lower_bound(anchors_.begin(), anchors_.end(), m,
                                   [](const Anchor& a, std::uint64_t v) { return a.m < v; });
  // The skewness of an anchor when first asked for (it costs more than the EDF).
  for (Anchor* a : {&*hi, hi == anchors_.begin() ? &*hi : &*(hi - 1)}) {
    if (!skew || a->skew_known[k]) continue;
    a->value[k].skew_dof = exact_skew_dof(alpha, unbroken_grid(stat_of(stat_), a->m, 1, n_phase_));
    a->skew_known[k] = true;
  }
  if (hi->m == m) return hi->value[k];
  const Anchor& lo = *(hi - 1);
  const double w = std::log(static_cast<double>(m) / static_cast<double>(lo.m)) /
                   std::log(static_cast<double>(hi->m) / static_cast<double>(lo.m));
  return {interpolate(lo.value[k].edf, hi->value[k].edf, w), interpolate(lo.value[k].skew_dof, hi->value[k].skew_dof, w)};
}

Estimate EdfTable::estimate(const TauSums& t, std::uint64_t n_phase, const NoiseId& noise, const EstimateOptions& o) const {
  Estimate e = gyrochar::estimate(t, n_phase, stat_, NoiseId{}, o, nullptr);  // the deviation only
  e.noise = noise;
  if (e.n == 0 || !noise.identified()) return e;
  const std::uint64_t grid_n = unbroken_grid(stat_of(stat_), t.m, 1, n_phase).n;
  // Gaps remove terms: scaled by the share formed, as estimate() does.
  const double share = e.n >= grid_n ? 1.0 : static_cast<double>(e.n) / static_cast<double>(grid_n);
  for (int alpha = noise.low; alpha <= noise.high; ++alpha) {  // the smallest plausible EDF
    const double edf = at(t.m, alpha, false).edf;
    if (edf > 0 && (e.edf == 0 || edf < e.edf)) {
      e.edf = edf;
      e.edf_alpha = alpha;
    }
  }
  e.edf *= share;
  if (o.skewness && e.edf > 0 && e.edf < 100) e.skew_dof = at(t.m, e.edf_alpha).skew_dof * share;
  return e;
}

}  // namespace gyrochar

namespace gyrochar {
namespace {

// Pair sums between two anchors at weight w (0: p0, 1: p1): each diagonal sum (positive: a sum
// of squares) log-linearly, the others as their ratio to the diagonal scale, linearly.
PairSums interpolate(const PairSums& p0, const PairSums& p1, double w) {
  PairSums out;
  const auto scale = [&](const PairSums& p, std::size_t t, std::size_t u) { return std::sqrt(p.cc[t][t] * p.cc[u][u]); };
  const auto mix = [&](double v0, double s0, double v1, double s1) {
    if (!(s0 > 0) || !(s1 > 0)) return (1 - w) * v0 + w * v1;
    return ((1 - w) * v0 / s0 + w * v1 / s1) * interpolate(s0, s1, w);
  };
  for (std::size_t t = 0; t < max_noises; ++t) {
    for (std::size_t u = 0; u < max_noises; ++u)
      out.cc[t][u] = mix(p0.cc[t][u], scale(p0, t, u), p1.cc[t][u], scale(p1, t, u));
    out.c[t] = mix(p0.c[t], std::sqrt(p0.cc[t][t]), p1.c[t], std::sqrt(p1.cc[t][t]));
  }
  return out;
}

}  // namespace

DenseNoiseSums::DenseNoiseSums(std::span<const std::uint64_t> m_list, std::uint64_t n_phase, std::uint64_t m_min,
                               PairSumCache& cache)
    : n_phase_(n_phase) {
  std::uint64_t m_max = 0;
  for (const std::uint64_t m : m_list)
    if (m >= m_min && unbroken_grid(Stat::mvar, m, 1, n_phase).n > 0) m_max = m;
  static constexpr Stat stats[] = {Stat::avar, Stat::mvar};
  for (const std::uint64_t m : dense_anchors(stats, n_phase, m_min, m_max)) {
    const TermGrid a = unbroken_grid(Stat::avar, m, 1, n_phase), b = unbroken_grid(Stat::mvar, m, 1, n_phase);
    anchors_.push_back({m, cache.get(a, a), cache.get(b, b), cache.get(a, b)});
  }
}

bool DenseNoiseSums::find(const TermGrid& a, const TermGrid& b, PairSums& out) const {
  if (anchors_.empty() || a.m != b.m || a.m < anchors_.front().m || a.m > anchors_.back().m) return false;
  const auto unbroken = [&](const TermGrid& g) {
    const TermGrid u = unbroken_grid(g.stat, g.m, 1, n_phase_);
    return (g.stat == Stat::avar || g.stat == Stat::mvar) && g.stride == 1 && g.first == u.first && g.n == u.n;
  };
  if (!unbroken(a) || !unbroken(b)) return false;
  const auto pick = [&](const Anchor& anchor) -> const PairSums& {
    return a.stat != b.stat ? anchor.am : a.stat == Stat::avar ? anchor.aa : anchor.mm;
  };
  // Anchors are in the order of m: the first at or above m, and the one before it.
  const auto hi = std::lower_bound(anchors_.begin(), anchors_.end(), a.m,
                                   [](const Anchor& anchor, std::uint64_t m) { return anchor.m < m; });
  if (hi->m == a.m) {
    out = pick(*hi);
  } else {
    const Anchor& lo = *(hi - 1);
    const double w = std::log(static_cast<double>(a.m) / static_cast<double>(lo.m)) /
                     std::log(static_cast<double>(hi->m) / static_cast<double>(lo.m));
    out = interpolate(pick(lo), pick(*hi), w);
  }
  return true;  // pair_sums(b, a) is pair_sums(a, b): every pair's lag turns, not its covariance
}

}  // namespace gyrochar
