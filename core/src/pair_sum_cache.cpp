// What the pair sums (noise_model.cpp) are checked and kept by: the bound on their rounding, the
// exact skewness EDF of one estimate, the Allan noises' set, and the cache of pair sums the fits share.
#include <cmath>

#include "gyrochar/noise_model.hpp"
#include "noise_kernel.hpp"

namespace gyrochar {

using namespace noise_kernel;

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
    for (std::int64_t j = 0; j <= 2 * top; ++j)
      table[static_cast<std::size_t>(j)] = j * q <= reach ? covariance(k, twice_d, j * q * s) : 0.0;
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
    if (!e.used || (e.stat_a == a.stat && e.stat_b == b.stat && e.m_a == a.m && e.m_b == b.m && e.stride_a == a.stride &&
                    e.stride_b == b.stride)) {
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
  if (entry->used && !entry->linear && a.n >= entry->n_a && b.n >= entry->n_b && growth * (a.n - entry->n_a) <= entry->n_a &&
      growth * (b.n - entry->n_b) <= entry->n_b) {
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

SinusoidPairSums PairSumCache::sinusoid_sums(const NoiseSet& set, std::span<const double> thetas, const TermGrid& a,
                                             const TermGrid& b) {
  if (SinusoidPairSums found; source_ != nullptr && source_->find_sinusoids(set, thetas, a, b, found)) return found;
  return sinusoid_pair_sums(set, thetas, a, b);
}

void PairSumCache::clear() {
  for (Entry& e : entries_) e = Entry{};
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
