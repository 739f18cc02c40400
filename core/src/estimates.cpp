// The extractors (see estimates.hpp).
#include "gyrochar/estimates.hpp"

#include <cmath>

#include "gyrochar/greenhall_edf.hpp"
#include "gyrochar/noise_model.hpp"

namespace gyrochar {

const char* name(DevStat s) {
  switch (s) {
    case DevStat::adev: return "adev";
    case DevStat::oadev: return "oadev";
    case DevStat::mdev: return "mdev";
    case DevStat::tdev: return "tdev";
    case DevStat::hdev: return "hdev";
    case DevStat::ohdev: return "ohdev";
  }
  return "?";
}

const char* name(NoiseIdMethod m) {
  switch (m) {
    case NoiseIdMethod::none: return "none";
    case NoiseIdMethod::given: return "given";
    case NoiseIdMethod::lag1: return "lag1";
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

int alpha_of(double p) { return 2 - static_cast<int>(std::lround(p)); }

// With no tau long enough for the lag-1 rule: the B1 ratio (the standard variance of the
// m-averaged frequency over the overlapping AVAR, as Stable32 does it) against Barnes' B1(N, mu),
// nearest on a log scale; for white PM vs flicker PM, R(n) = MVAR/AVAR.
NoiseId b1_identify(const TauSums& t) {
  NoiseId out;
  const Lag1Sums& y = t.noise->order(1);
  const double avar = t.variance[static_cast<std::size_t>(SumKind::avar)];
  const double mvar = t.variance[static_cast<std::size_t>(SumKind::mvar)];
  // With fewer than 3 averages every B1(N, mu) is 1: B1 cannot choose.
  if (y.n < 3 || !(avar > 0)) return out;
  const double scale = static_cast<double>(t.m);
  const double b1 = y.variance() / (scale * scale) / avar;
  const double n = static_cast<double>(y.n);
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

double edf_of(Stat stat, int alpha, std::uint64_t m, std::uint64_t stride, std::uint64_t n_phase, std::uint64_t terms,
              EdfModel model) {
  if (!noise_supported(stat, alpha)) return 0.0;
  const TermGrid grid = unbroken_grid(stat, m, stride, n_phase);
  if (grid.n == 0 || terms == 0) return 0.0;
  double edf = 0;
  if (model == EdfModel::greenhall) {
    EdfQuery q;
    q.alpha = alpha;
    q.d = difference_order(stat);
    q.m = static_cast<double>(m);
    q.modified = stat == Stat::mvar;
    q.S = static_cast<double>(m) / static_cast<double>(stride);
    q.N = static_cast<double>(n_phase);
    edf = edf_greenhall(q);
  } else {
    edf = exact_edf(alpha, grid);
  }
  // Gaps remove terms: scale by the share formed (0 to 4 % below the pooled EDF of independent
  // segments of 25 m or more, docs/core.md: the interval errs on the wide side).
  return terms >= grid.n ? edf : edf * static_cast<double>(terms) / static_cast<double>(grid.n);
}

}  // namespace

void identify_noise(std::span<const TauSums> taus, int dmax, bool frequency_input, std::span<NoiseId> out) {
  const int dmin = frequency_input ? 1 : 0;
  std::size_t last_lag1 = taus.size();  // none yet
  for (std::size_t i = 0; i < taus.size() && i < out.size(); ++i) {
    NoiseId id;
    const Lag1Estimate e = taus[i].noise ? lag1_estimate(*taus[i].noise, dmin, dmax) : Lag1Estimate{};
    if (e.valid && taus[i].noise->points() >= lag1_min_points) {
      id.method = NoiseIdMethod::lag1;
      id.alpha = clamp_alpha(alpha_of(e.p), dmax);
      id.low = clamp_alpha(alpha_of(e.p + e.sigma), dmax);
      id.high = clamp_alpha(alpha_of(e.p - e.sigma), dmax);
      last_lag1 = i;
    } else if (last_lag1 < taus.size()) {
      id = out[last_lag1];
      id.method = NoiseIdMethod::neighbour;
    } else if (taus[i].noise) {
      id = b1_identify(taus[i]);
      id.alpha = clamp_alpha(id.alpha, dmax);
      id.low = id.high = id.alpha;
    }
    out[i] = id;
  }
}

Estimate estimate(const TauSums& t, std::uint64_t n_phase, DevStat stat, const NoiseId& noise,
                  const EstimateOptions& o) {
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
  if (o.edf == EdfModel::greenhall) {
    e.edf_alpha = noise.alpha;
    e.edf = edf_of(s, noise.alpha, t.m, e.stride, n_phase, e.n, o.edf);
    return e;
  }
  for (int alpha = noise.low; alpha <= noise.high; ++alpha) {  // the smallest plausible EDF
    const double edf = edf_of(s, alpha, t.m, e.stride, n_phase, e.n, o.edf);
    if (edf > 0 && (e.edf == 0 || edf < e.edf)) {
      e.edf = edf;
      e.edf_alpha = alpha;
    }
  }
  return e;
}

}  // namespace gyrochar
