// The extractors (see estimates.hpp).
#include "gyrochar/estimates.hpp"

#include <cmath>

#include "gyrochar/greenhall_edf.hpp"
#include "gyrochar/noise_model.hpp"

namespace gyrochar {

const char* name(NoiseIdMethod m) {
  switch (m) {
    case NoiseIdMethod::none: return "none";
    case NoiseIdMethod::given: return "given";
    case NoiseIdMethod::lag1: return "lag1";
    case NoiseIdMethod::rn: return "rn";
    case NoiseIdMethod::neighbour: return "neighbour";
    case NoiseIdMethod::b1: return "b1";
    case NoiseIdMethod::b1_rn: return "b1_rn";
  }
  return "?";
}

namespace {

int clamp_alpha(int alpha, int dmax) {
  const int lowest = dmax == 3 ? -4 : -2;
  return alpha < lowest ? lowest : alpha > 2 ? 2 : alpha;
}

// With no tau long enough for the lag-1 rule: the B1 ratio (the standard variance of the
// m-averaged frequency over the overlapping AVAR, as Stable32 does it) against Barnes' B1(N, mu),
// nearest on a log scale; for white PM vs flicker PM, R(n) = MVAR/AVAR.
NoiseId b1_identify(const TauSums& t) {
  NoiseId out;
  const std::uint64_t points = t.noise.n[1];
  const double avar = t.variance[static_cast<std::size_t>(SumKind::avar)];
  const double mvar = t.variance[static_cast<std::size_t>(SumKind::mvar)];
  // With fewer than 3 averages every B1(N, mu) is 1: B1 cannot choose.
  if (points < 3 || !(avar > 0)) return out;
  const double scale = static_cast<double>(t.m);
  const double b1 = t.noise.variance1 / (scale * scale) / avar;
  const double n = static_cast<double>(points);
  static constexpr int alphas[] = {2, 0, -1, -2};
  static constexpr int mus[] = {-2, -1, 0, 1};
  int pick = 3;
  for (int k = 0; k < 3; ++k) {
    if (b1 < std::sqrt(b1_expected(n, mus[k]) * b1_expected(n, mus[k + 1]))) {
      pick = k;
      break;
    }
  }
  out.alpha = alphas[pick];
  out.method = NoiseIdMethod::b1;
  if (out.alpha == 2 && mvar > 0) {
    out.alpha = mvar / avar < std::sqrt(rn_expected(t.m, 2) * rn_expected(t.m, 1)) ? 2 : 1;
    out.method = NoiseIdMethod::b1_rn;
  }
  out.low = out.high = out.alpha;
  return out;
}

// The EDF of the estimate over `grid` (with `terms` formed: gaps remove some) for noise alpha.
// Allan and modified Allan: (n c(0))^2 / sum c^2 with the sum from `allan` (pair_sums of the five
// Allan noises over the grid with itself); Hadamard: exact_edf(). Greenhall's approximation on
// request.
double edf_of(Stat stat, int alpha, const TermGrid& grid, std::uint64_t terms, std::uint64_t n_phase, EdfModel model,
              const PairSums& allan) {
  if (!noise_supported(stat, alpha) || grid.n == 0 || terms == 0) return 0.0;
  double edf = 0;
  if (model == EdfModel::greenhall) {
    EdfQuery q;
    q.alpha = alpha;
    q.d = difference_order(stat);
    q.m = static_cast<double>(grid.m);
    q.modified = stat == Stat::mvar;
    q.S = static_cast<double>(grid.m) / static_cast<double>(grid.stride);
    q.N = static_cast<double>(n_phase);
    edf = edf_greenhall(q);
  } else if (stat == Stat::hvar) {
    edf = exact_edf(alpha, grid);
  } else {
    const double sum = allan.cc[static_cast<std::size_t>(2 - alpha)][static_cast<std::size_t>(2 - alpha)];
    const double c0 = term_covariance(alpha, stat, grid.m, stat, grid.m, 0);
    const double n = static_cast<double>(grid.n);
    edf = sum > 0 ? n * n * c0 * c0 / sum : 0.0;
  }
  // Gaps remove terms: scale by the share formed (0 to 4 % below the pooled EDF of independent
  // segments of 25 m or more, docs/core.md: the interval errs on the wide side).
  return terms >= grid.n ? edf : edf * static_cast<double>(terms) / static_cast<double>(grid.n);
}

// Exponent noise types are idealizations: measured statistics are allowed this relative spread
// beyond their sampling error before they count against a type.
constexpr double model_spread = 0.1;
// A power-law model changes slowly with tau: each unit of alpha away from the shorter tau's costs
// as much as one standard deviation of evidence.
constexpr double neighbour_weight = 1.0;
// Alphas whose chi-squared is within this of the best are plausible (about one standard deviation).
constexpr double plausible_chi2 = 1.0;

PairSums allan_sums(PairSumCache* cache, const TermGrid& a, const TermGrid& b) {
  return cache ? cache->get(a, b) : pair_sums(allan_noises(), a, b);
}

// How far the measured R(n) = MVAR/AVAR lies from its expectation under each pure noise alpha
// (2 .. -2), in standard deviations: ln R against ln E[MVAR]/E[AVAR] (with the second-order bias
// of the logarithms), the variance from the exact covariances of the two estimates
// (noise_model.hpp) plus the model spread. NaN where the ratio is not available.
std::array<double, 5> rn_scores(const TauSums& t, std::uint64_t n_phase, PairSumCache* cache) {
  std::array<double, 5> z;
  z.fill(std::nan(""));
  const auto A = static_cast<std::size_t>(SumKind::avar), M = static_cast<std::size_t>(SumKind::mvar);
  if (t.n[A] == 0 || t.n[M] == 0 || !(t.variance[A] > 0) || !(t.variance[M] > 0)) return z;
  const TermGrid a = unbroken_grid(Stat::avar, t.m, t.stride, n_phase);
  const TermGrid b = unbroken_grid(Stat::mvar, t.m, t.stride, n_phase);
  if (a.n == 0 || b.n == 0) return z;
  const PairSums aa = allan_sums(cache, a, a), mm = allan_sums(cache, b, b), am = allan_sums(cache, a, b);
  const double na = static_cast<double>(a.n), nm = static_cast<double>(b.n);
  // Gaps remove terms: the relative variances grow as the share of terms formed shrinks.
  const double share_a = na / static_cast<double>(t.n[A]), share_m = nm / static_cast<double>(t.n[M]);
  const double m = static_cast<double>(t.m);
  const double measured = std::log(t.variance[M] / t.variance[A]);
  for (std::size_t k = 0; k < 5; ++k) {
    const int alpha = 2 - static_cast<int>(k);
    const double ca = term_covariance(alpha, Stat::avar, t.m, Stat::avar, t.m, 0);
    const double cm = term_covariance(alpha, Stat::mvar, t.m, Stat::mvar, t.m, 0);
    const double va = 2 * aa.cc[k][k] / (na * ca * na * ca) * share_a;
    const double vm = 2 * mm.cc[k][k] / (nm * cm * nm * cm) * share_m;
    const double cov = 2 * am.cc[k][k] / (na * ca * nm * cm) * std::sqrt(share_a * share_m);
    const double expected = std::log(cm / (ca * m * m)) - vm / 2 + va / 2;
    const double var = va + vm - 2 * cov + model_spread * model_spread;
    z[k] = (measured - expected) / std::sqrt(var);
  }
  return z;
}

}  // namespace

void identify_noise(std::span<const TauSums> taus, std::uint64_t n_phase, int dmax, bool frequency_input,
                    std::span<NoiseId> out, PairSumCache* cache) {
  const int dmin = frequency_input ? 1 : 0;
  const int lowest = dmax == 3 ? -4 : -2;
  for (std::size_t i = 0; i < taus.size() && i < out.size(); ++i) {
    const TauSums& t = taus[i];
    const NoiseId* previous = i > 0 && out[i - 1].identified() ? &out[i - 1] : nullptr;
    std::array<double, 7> chi2{};  // index 2 - alpha
    bool informed = false;
    const Lag1Estimate lag1 = t.has_noise ? lag1_estimate(t.noise, dmin, dmax) : Lag1Estimate{};
    const bool use_lag1 = lag1.valid && lag1.points >= lag1_min_points;
    const std::array<double, 5> rn = rn_scores(t, n_phase, cache);
    for (int alpha = 2; alpha >= lowest; --alpha) {
      double& c = chi2[static_cast<std::size_t>(2 - alpha)];
      if (use_lag1) {
        const double z = (lag1.p - (2 - alpha)) / std::fmax(lag1.sigma, model_spread);
        c += z * z;
        informed = true;
      }
      {  // R(n) needs AVAR: below alpha = -2 (Hadamard only) score it as random-walk FM
        const double z = rn[static_cast<std::size_t>(2 - (alpha < -2 ? -2 : alpha))];
        if (std::isfinite(z)) {
          c += z * z;
          informed = true;
        }
      }
      if (previous) c += neighbour_weight * (alpha - previous->alpha) * (alpha - previous->alpha);
    }
    NoiseId id;
    if (!informed) {
      if (previous) {
        id = *previous;
        id.method = NoiseIdMethod::neighbour;
      } else if (t.has_noise) {
        id = b1_identify(t);
        id.alpha = clamp_alpha(id.alpha, dmax);
        id.low = id.high = id.alpha;
      }
      out[i] = id;
      continue;
    }
    int best = 2;
    for (int alpha = 2; alpha >= lowest; --alpha)
      if (chi2[static_cast<std::size_t>(2 - alpha)] < chi2[static_cast<std::size_t>(2 - best)]) best = alpha;
    id.alpha = best;
    id.low = id.high = best;
    for (int alpha = 2; alpha >= lowest; --alpha) {
      if (chi2[static_cast<std::size_t>(2 - alpha)] > chi2[static_cast<std::size_t>(2 - best)] + plausible_chi2) continue;
      if (alpha < id.low) id.low = alpha;
      if (alpha > id.high) id.high = alpha;
    }
    id.method = use_lag1 ? NoiseIdMethod::lag1 : NoiseIdMethod::rn;
    out[i] = id;
  }
}

Estimate estimate(const TauSums& t, std::uint64_t n_phase, DevStat stat, const NoiseId& noise, const EstimateOptions& o,
                  PairSumCache* cache) {
  Estimate e;
  e.stat = stat;
  e.m = t.m;
  e.tau_s = static_cast<double>(t.m) * o.tau0_s;
  const SumKind k = sum_kind(stat);
  e.n = t.n[static_cast<std::size_t>(k)];
  e.stride = k == SumKind::avar_nonoverlapped || k == SumKind::hvar_nonoverlapped ? t.m : t.stride;
  e.noise = noise;
  e.clean = t.clean;
  if (e.n == 0) return e;
  e.variance = t.variance[static_cast<std::size_t>(k)] * o.unit * o.unit / (o.tau0_s * o.tau0_s);
  if (stat == DevStat::tdev) e.variance *= e.tau_s * e.tau_s / 3.0;
  e.deviation = std::sqrt(e.variance);
  if (!noise.identified()) return e;
  const Stat s = stat_of(stat);
  const TermGrid grid = unbroken_grid(s, t.m, e.stride, n_phase);
  PairSums allan;
  if (o.edf == EdfModel::exact && s != Stat::hvar && grid.n > 0) allan = allan_sums(cache, grid, grid);
  if (o.edf == EdfModel::greenhall) {
    e.edf_alpha = noise.alpha;
    e.edf = edf_of(s, noise.alpha, grid, e.n, n_phase, o.edf, allan);
    return e;
  }
  for (int alpha = noise.low; alpha <= noise.high; ++alpha) {  // the smallest plausible EDF
    const double edf = edf_of(s, alpha, grid, e.n, n_phase, o.edf, allan);
    if (edf > 0 && (e.edf == 0 || edf < e.edf)) {
      e.edf = edf;
      e.edf_alpha = alpha;
    }
  }
  // The shape beyond two moments: it moves an interval by a fraction of its width of order
  // sqrt(2 / EDF) squared, nothing worth its cost above an EDF of 100. Gaps scale it as the EDF.
  if (o.skewness && e.edf > 0 && e.edf < 100) {
    const double nu3 = exact_skew_dof(e.edf_alpha, grid);
    e.skew_dof = e.n >= grid.n ? nu3 : nu3 * static_cast<double>(e.n) / static_cast<double>(grid.n);
  }
  return e;
}

}  // namespace gyrochar
