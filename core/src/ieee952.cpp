// The IEEE-952 fit by generalized least squares (see ieee952.hpp).
#include "gyrochar/ieee952.hpp"

#include <cmath>

#include "gyrochar/noise_model.hpp"

namespace gyrochar {

const char* name(FitCurve c) {
  switch (c) {
    case FitCurve::avar: return "avar";
    case FitCurve::mvar: return "mvar";
    case FitCurve::both: return "both";
  }
  return "?";
}

const char* name(FitStatus s) {
  switch (s) {
    case FitStatus::ok: return "ok";
    case FitStatus::too_few_points: return "too few points";
    case FitStatus::rejected: return "model rejected";
    case FitStatus::singular: return "singular";
  }
  return "?";
}

namespace {

constexpr std::size_t terms = 5;    // Q N B K R
constexpr std::size_t noises = 4;   // Q N B K: the random ones
constexpr std::array<int, noises> alphas{2, 0, -1, -2};  // Q N B K
// Two estimates keep a noise's part of their covariance when they lie at most band_octaves apart
// and double precision evaluates it: pair_sums_rounding() bounds the rounding of its correlation
// at covariance_rounding_kept. Far apart, the closed forms of the flicker and random-walk FM sums
// are differences of nearly equal huge numbers (on a 120 h record at tau0 0.1 s the random-walk FM
// sum of the modified Allan estimate at 512 tau0 and the Allan one at 2^19 tau0, ten octaves
// apart, came out wrong by more than its value, and the matrix indefinite: the fit was singular);
// their correlations there are small (0.04 for that pair, by an exact computation without the
// closed forms). The bound is loose (typically far above the actual error): at 1e-3 it dropped
// accurate parts of neighbouring estimates and the fit of short records was rejected where it had
// been fine, so only parts it cannot vouch for to 0.1 go. White PM is exact at any distance and
// need not decay: fully overlapped Allan estimates share the sum of x^2 and stay correlated by
// about 0.24 across every tau up to the stride factor; it is always kept.
constexpr double covariance_rounding_kept = 0.1;
constexpr int band_octaves = 10;
constexpr double quantization_left_out = 0.01;  // share of a point that makes it unusable (non-white)

// Innovation variance of term t per unit squared parameter: tau0^k.
double innovation_scale(std::size_t t, double tau0) { return t == 0 ? 1.0 : std::pow(tau0, static_cast<double>(t)); }

// E[term^2] -> variance: AVAR = E[a^2] / (2 m^2 tau0^2), MVAR = E[t^2] / (2 m^4 tau0^2).
double normalization(Stat s, std::uint64_t m, double tau0) {
  const double mm = static_cast<double>(m);
  return s == Stat::mvar ? 2 * mm * mm * mm * mm * tau0 * tau0 : 2 * mm * mm * tau0 * tau0;
}

// The model's expected variance of a point per unit squared parameter: the design matrix row.
std::array<double, terms> design(Stat s, std::uint64_t m, double tau0) {
  std::array<double, terms> x{};
  const double nrm = normalization(s, m, tau0);
  for (std::size_t t = 0; t < noises; ++t)
    x[t] = term_covariance(alphas[t], s, m, s, m, 0) * innovation_scale(t, tau0) / nrm;
  const double tau = static_cast<double>(m) * tau0;
  x[4] = tau * tau / 2;
  return x;
}

int octave(std::uint64_t m) { return 63 - __builtin_clzll(m); }

// In-place Cholesky of the n x n matrix a (row-major, lower triangle used). False when not positive
// definite.
bool cholesky(double* a, std::size_t n) {
  for (std::size_t j = 0; j < n; ++j) {
    double d = a[j * n + j];
    for (std::size_t k = 0; k < j; ++k) d -= a[j * n + k] * a[j * n + k];
    if (!(d > 0)) return false;
    d = std::sqrt(d);
    a[j * n + j] = d;
    for (std::size_t i = j + 1; i < n; ++i) {
      double s = a[i * n + j];
      for (std::size_t k = 0; k < j; ++k) s -= a[i * n + k] * a[j * n + k];
      a[i * n + j] = s / d;
    }
  }
  return true;
}

// Solves L z = b in place (L the lower triangle of a).
void forward(const double* a, std::size_t n, double* b, std::size_t stride_b) {
  for (std::size_t i = 0; i < n; ++i) {
    double s = b[i * stride_b];
    for (std::size_t k = 0; k < i; ++k) s -= a[i * n + k] * b[k * stride_b];
    b[i * stride_b] = s / a[i * n + i];
  }
}

// Solves the small symmetric system a x = b (Gauss-Jordan, partial pivoting) and inverts a.
bool solve_small(std::array<std::array<double, terms>, terms> a, std::array<double, terms> b, std::size_t n,
                 std::array<double, terms>& x, std::array<std::array<double, terms>, terms>& inv) {
  std::array<std::array<double, terms>, terms> id{};
  for (std::size_t i = 0; i < n; ++i) id[i][i] = 1.0;
  for (std::size_t c = 0; c < n; ++c) {
    std::size_t pivot = c;
    for (std::size_t r = c + 1; r < n; ++r)
      if (std::fabs(a[r][c]) > std::fabs(a[pivot][c])) pivot = r;
    if (!(std::fabs(a[pivot][c]) > 1e-300)) return false;
    std::swap(a[c], a[pivot]);
    std::swap(b[c], b[pivot]);
    std::swap(id[c], id[pivot]);
    for (std::size_t r = 0; r < n; ++r) {
      if (r == c) continue;
      const double f = a[r][c] / a[c][c];
      for (std::size_t k = 0; k < n; ++k) {
        a[r][k] -= f * a[c][k];
        id[r][k] -= f * id[c][k];
      }
      b[r] -= f * b[c];
    }
  }
  for (std::size_t r = 0; r < n; ++r) {
    x[r] = b[r] / a[r][r];
    for (std::size_t k = 0; k < n; ++k) inv[r][k] = id[r][k] / a[r][r];
  }
  return true;
}

// The points in use, with their design rows and the workspace views.
struct Problem {
  std::size_t n = 0;
  const FitPoint* point[128];
  double tau0 = 1;
  std::uint64_t n_phase = 0;
  double spread = 0;
  double* pair = nullptr;   // per pair (i <= j): 10 sums c_t c_u, then 4 sums c_t
  double* sigma = nullptr;  // n x n
  double* rows = nullptr;   // per point: x[5], y, spare
  double* row(std::size_t i) const { return rows + i * 8; }
  double* pair_at(std::size_t i, std::size_t j) const {
    if (i > j) {
      const std::size_t t = i;
      i = j;
      j = t;
    }
    return pair + (j * (j + 1) / 2 + i) * 14;
  }
};

std::size_t cc_index(std::size_t t, std::size_t u) {
  if (t < u) {
    const std::size_t s = t;
    t = u;
    u = s;
  }
  return t * (t + 1) / 2 + u;  // 0..9
}

// The covariance of the points under squared parameters theta (the random terms and the ramp's
// cross term 4 D_p D_q sum c, D the ramp's deterministic term value).
void covariance_of_points(const Problem& pr, const std::array<double, terms>& theta) {
  std::array<double, noises> h{};
  for (std::size_t t = 0; t < noises; ++t) h[t] = (theta[t] > 0 ? theta[t] : 0) * innovation_scale(t, pr.tau0);
  const double ramp = theta[4] > 0 ? theta[4] : 0;
  for (std::size_t i = 0; i < pr.n; ++i) {
    for (std::size_t j = 0; j <= i; ++j) {
      const FitPoint& a = *pr.point[i];
      const FitPoint& b = *pr.point[j];
      const double* g = pr.pair_at(i, j);
      double v = 0;
      for (std::size_t t = 0; t < noises; ++t)
        for (std::size_t u = 0; u < noises; ++u) v += h[t] * h[u] * g[cc_index(t, u)];
      v *= 2;
      if (ramp > 0) {
        const double ta = static_cast<double>(a.m) * pr.tau0, tb = static_cast<double>(b.m) * pr.tau0;
        const double da = ta * ta * (a.stat == Stat::mvar ? static_cast<double>(a.m) : 1.0);
        const double db = tb * tb * (b.stat == Stat::mvar ? static_cast<double>(b.m) : 1.0);
        double lin = 0;
        for (std::size_t t = 0; t < noises; ++t) lin += h[t] * g[10 + t];
        v += 4 * ramp * da * db * lin;
      }
      // Sums over the unbroken grids; gaps removed terms (share = grid terms / terms formed).
      const TermGrid ga = unbroken_grid(a.stat, a.m, a.stride, pr.n_phase);
      const TermGrid gb = unbroken_grid(b.stat, b.m, b.stride, pr.n_phase);
      const double na = static_cast<double>(a.n), nb = static_cast<double>(b.n);
      const double share = std::sqrt(static_cast<double>(ga.n) / na * static_cast<double>(gb.n) / nb);
      v *= share / (static_cast<double>(ga.n) * static_cast<double>(gb.n) * normalization(a.stat, a.m, pr.tau0) *
                    normalization(b.stat, b.m, pr.tau0));
      v *= std::sqrt(a.variance_scale * b.variance_scale);  // a total-family estimate in an Allan point's place
      if (i == j) v += pr.spread * pr.spread * a.variance * a.variance;
      pr.sigma[i * pr.n + j] = v;
      pr.sigma[j * pr.n + i] = v;
    }
  }
}

// Factors Sigma; where the covariance parts left out leave it indefinite, raises its diagonal by the least relative
// amount that makes it definite (from 1e-6, doubling): the points then weigh a little less, their
// correlations are kept.
bool factor(const Problem& pr) {
  const std::size_t n = pr.n;
  double* a = pr.sigma;
  for (double raise = 0; raise < 1; raise = raise == 0 ? 1e-6 : 2 * raise) {
    // Cholesky writes the lower triangle and the diagonal; the upper triangle keeps Sigma, the
    // rows' slot 6 its diagonal.
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t j = 0; j < i; ++j) a[i * n + j] = a[j * n + i];
      a[i * n + i] = pr.row(i)[6] * (1 + raise);
    }
    if (cholesky(a, n)) return true;
  }
  return false;
}

struct Solution {
  std::array<double, terms> theta{};
  std::array<std::array<double, terms>, terms> cov{};
  std::array<bool, terms> active{};
  std::array<double, terms> free_variance{};  // of each free term in the model with every free term
  double chi2 = 0;
  bool ok = false;
};

// Non-negative least squares on the whitened system by trying every subset of the free terms.
Solution solve(const Problem& pr, const std::array<bool, terms>& free, const std::array<double, terms>& fixed) {
  Solution best;
  const std::size_t n = pr.n;
  // Whitened design (columns 0..4) and data (column 5): L^-1 [X y].
  for (std::size_t c = 0; c < 6; ++c) {
    for (std::size_t i = 0; i < n; ++i) {
      double v = pr.row(i)[c];
      if (c == 5) {
        for (std::size_t t = 0; t < terms; ++t)
          if (!free[t]) v -= fixed[t] * pr.row(i)[t];  // held terms are a known offset
      }
      pr.row(i)[c == 5 ? 7 : c] = v;  // y offset kept in slot 7 during whitening
    }
  }
  // Column scales: the basis spans many decades.
  std::array<double, terms> scale{};
  double whitened[128][6];
  for (std::size_t c = 0; c < 6; ++c) {
    double col[128];
    for (std::size_t i = 0; i < n; ++i) col[i] = pr.row(i)[c == 5 ? 7 : c];
    forward(pr.sigma, n, col, 1);
    for (std::size_t i = 0; i < n; ++i) whitened[i][c] = col[i];
  }
  for (std::size_t t = 0; t < terms; ++t) {
    double s = 0;
    for (std::size_t i = 0; i < n; ++i) s += whitened[i][t] * whitened[i][t];
    scale[t] = s > 0 ? 1 / std::sqrt(s) : 1;
  }
  std::size_t n_free = 0;
  for (bool f : free) n_free += f;
  std::array<double, terms> free_variance{};
  for (unsigned mask = 1; mask < (1u << terms); ++mask) {
    std::size_t idx[terms];
    std::size_t k = 0;
    bool allowed = true;
    for (std::size_t t = 0; t < terms; ++t) {
      if (!(mask & (1u << t))) continue;
      if (!free[t]) allowed = false;
      idx[k++] = t;
    }
    if (!allowed || k > n) continue;
    std::array<std::array<double, terms>, terms> ata{};
    std::array<double, terms> atb{};
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t a = 0; a < k; ++a) {
        const double xa = whitened[i][idx[a]] * scale[idx[a]];
        atb[a] += xa * whitened[i][5];
        for (std::size_t b = 0; b < k; ++b) ata[a][b] += xa * whitened[i][idx[b]] * scale[idx[b]];
      }
    }
    std::array<double, terms> x{};
    std::array<std::array<double, terms>, terms> inv{};
    if (!solve_small(ata, atb, k, x, inv)) continue;
    if (static_cast<std::size_t>(__builtin_popcount(mask)) == n_free)  // every free term: its variances
      for (std::size_t a = 0; a < k; ++a) free_variance[idx[a]] = inv[a][a] * scale[idx[a]] * scale[idx[a]];
    bool feasible = true;
    for (std::size_t a = 0; a < k; ++a) feasible &= x[a] >= 0;
    if (!feasible) continue;
    double chi2 = 0;
    for (std::size_t i = 0; i < n; ++i) {
      double r = whitened[i][5];
      for (std::size_t a = 0; a < k; ++a) r -= whitened[i][idx[a]] * scale[idx[a]] * x[a];
      chi2 += r * r;
    }
    if (best.ok && chi2 >= best.chi2) continue;
    best = Solution{};
    best.ok = true;
    best.chi2 = chi2;
    for (std::size_t t = 0; t < terms; ++t) best.theta[t] = free[t] ? 0.0 : fixed[t];
    for (std::size_t a = 0; a < k; ++a) {
      best.theta[idx[a]] = x[a] * scale[idx[a]];
      best.active[idx[a]] = true;
      for (std::size_t b = 0; b < k; ++b) best.cov[idx[a]][idx[b]] = inv[a][b] * scale[idx[a]] * scale[idx[b]];
    }
  }
  best.free_variance = free_variance;
  // With no free term (or none feasible) the held terms alone are the model.
  if (!best.ok) {
    double chi2 = 0;
    for (std::size_t i = 0; i < n; ++i) chi2 += whitened[i][5] * whitened[i][5];
    best.chi2 = chi2;
    for (std::size_t t = 0; t < terms; ++t) best.theta[t] = free[t] ? 0.0 : fixed[t];
    best.ok = true;
  }
  return best;
}

// Upper tail of chi-squared with dof degrees of freedom below 1e-4 (Wilson-Hilferty).
bool rejected(double chi2, std::size_t dof) {
  if (dof == 0) return false;
  const double k = static_cast<double>(dof);
  const double z = (std::cbrt(chi2 / k) - (1 - 2 / (9 * k))) / std::sqrt(2 / (9 * k));
  return chi2 / k > 2 && z > 3.719;
}

}  // namespace

double ieee952_variance(const std::array<double, 5>& p, Stat stat, std::uint64_t m, double tau0_s) {
  const auto x = design(stat, m, tau0_s);
  double v = 0;
  for (std::size_t t = 0; t < terms; ++t) v += p[t] * p[t] * x[t];
  return v;
}

double ieee952_avar(const std::array<double, 5>& p, double tau) {
  constexpr double flicker_floor = 0.44127120030530318;  // 2 ln 2 / pi
  return 3 * p[0] * p[0] / (tau * tau) + p[1] * p[1] / tau + flicker_floor * p[2] * p[2] + p[3] * p[3] * tau / 3 +
         p[4] * p[4] * tau * tau / 2;
}

namespace {

// Leaves out every point whose white-quantization part is quantization_left_out or more of it, and
// holds Q at the white level: the quantization is not white.
void leave_out_quantization(Problem& pr, double qw2, std::array<bool, terms>& free, std::array<double, terms>& fixed,
                            Ieee952Fit& out) {
  out.quantization_white = false;
  std::size_t kept = 0;
  for (std::size_t i = 0; i < pr.n; ++i) {
    const FitPoint& p = *pr.point[i];
    const double white = qw2 * design(p.stat, p.m, pr.tau0)[0];
    if (white >= quantization_left_out * p.variance) {
      double& below = out.excluded_below_tau_s[p.stat == Stat::avar ? 0 : 1];
      const double next_octave = 2 * static_cast<double>(p.m) * pr.tau0;
      if (next_octave > below) below = next_octave;
      continue;
    }
    pr.point[kept++] = pr.point[i];
  }
  pr.n = kept;
  free[0] = false;
  fixed[0] = qw2;
}

// Before the fit: a point the white quantization alone would dominate lies far below it (three
// standard deviations and 2 %). Only a pattern can do that: other noise adds.
bool below_white_quantization(const Problem& pr, double qw2) {
  for (std::size_t i = 0; i < pr.n; ++i) {
    const FitPoint& p = *pr.point[i];
    const double white = qw2 * design(p.stat, p.m, pr.tau0)[0];
    if (white < 0.5 * p.variance) continue;
    const TermGrid grid = unbroken_grid(p.stat, p.m, p.stride, pr.n_phase);
    const double edf = exact_edf(2, grid) * static_cast<double>(p.n) / static_cast<double>(grid.n);
    const double sd = white * std::sqrt(2 * p.variance_scale / edf);
    if (p.variance < white - 3 * sd && p.variance < 0.98 * white) return true;
  }
  return false;
}

// After the fit: a point the fitted Q dominates departs from the model, either way, by three of its
// standard deviations and 2 %. With Q free, white angle noise beyond quantization is in the model,
// so the 1/tau^2 shape itself fails there: a pattern (a rate a little above a pulse per sample
// quantizes into one as well), a dither, or anything else no IEEE-952 term describes.
bool quantization_departs(const Problem& pr, const Solution& sol) {
  for (std::size_t i = 0; i < pr.n; ++i) {
    const double* x = pr.row(i);
    double model = 0;
    for (std::size_t t = 0; t < terms; ++t) model += sol.theta[t] * x[t];
    if (!(sol.theta[0] * x[0] >= 0.5 * model)) continue;
    const double gap = std::fabs(x[5] - model);
    if (gap > 3 * std::sqrt(x[6]) && gap > 0.02 * model) return true;
  }
  return false;
}

// The fit of the points in pr: their pair sums, first weights, then the exact covariance until
// the parameters settle. Fills out's status, chi2 and parameters; leaves the solution in `sol`.
void fit_points(Problem& pr, const FitSetup& setup, const std::array<bool, terms>& free,
                const std::array<double, terms>& fixed, std::span<double> workspace, PairSumCache* cache,
                Ieee952Fit& out, Solution& sol) {
  out.points = pr.n;
  std::size_t n_free = 0;
  for (bool f : free) n_free += f;
  if (pr.n <= n_free || pr.n == 0) {
    out.status = FitStatus::too_few_points;
    return;
  }
  pr.pair = workspace.data();
  pr.sigma = pr.pair + pr.n * (pr.n + 1) / 2 * 14;
  pr.rows = pr.sigma + pr.n * pr.n;

  // The pair sums of every two points: they depend on the geometry only. Of the
  // five Allan noises (index 2 - alpha) the model has four.
  constexpr std::array<std::size_t, noises> allan_index{0, 2, 3, 4};
  for (std::size_t i = 0; i < pr.n; ++i) {
    const FitPoint& a = *pr.point[i];
    const TermGrid ga = unbroken_grid(a.stat, a.m, a.stride, setup.n_phase);
    const auto x = design(a.stat, a.m, setup.tau0_s);
    for (std::size_t t = 0; t < terms; ++t) pr.row(i)[t] = x[t];
    pr.row(i)[5] = a.variance;
    for (std::size_t j = 0; j <= i; ++j) {
      const FitPoint& b = *pr.point[j];
      double* g = pr.pair_at(i, j);
      for (std::size_t k = 0; k < 14; ++k) g[k] = 0;
      const TermGrid gb = unbroken_grid(b.stat, b.m, b.stride, setup.n_phase);
      const PairSums s = cache ? cache->get(ga, gb) : pair_sums(allan_noises(), ga, gb);
      std::array<bool, noises> kept{};
      const int apart = octave(a.m) - octave(b.m);
      const bool near = apart <= band_octaves && apart >= -band_octaves;
      for (std::size_t t = 0; t < noises; ++t)
        kept[t] = t == 0 || (near && pair_sums_rounding(alphas[t], ga, gb) <= covariance_rounding_kept);
      for (std::size_t t = 0; t < noises; ++t) {
        if (!kept[t]) continue;
        for (std::size_t u = 0; u <= t; ++u)
          if (kept[u]) g[cc_index(t, u)] = s.cc[allan_index[t]][allan_index[u]];
        g[10 + t] = s.c[allan_index[t]];
      }
    }
  }

  // First weights: each point's own EDF, no correlation.
  for (std::size_t i = 0; i < pr.n; ++i) {
    const FitPoint& p = *pr.point[i];
    const double edf = p.edf > 0 ? p.edf : static_cast<double>(p.n);
    for (std::size_t j = 0; j < pr.n; ++j) pr.sigma[i * pr.n + j] = 0;
    pr.sigma[i * pr.n + i] = 2 * p.variance * p.variance / edf + pr.spread * pr.spread * p.variance * p.variance;
  }
  if (!cholesky(pr.sigma, pr.n)) {
    out.status = FitStatus::singular;
    return;
  }
  sol = solve(pr, free, fixed);
  // Then the exact covariance under the current parameters, until they settle.
  for (int iteration = 0; iteration < 12; ++iteration) {
    covariance_of_points(pr, sol.theta);
    for (std::size_t i = 0; i < pr.n; ++i) pr.row(i)[6] = pr.sigma[i * pr.n + i];
    if (!factor(pr)) {
      out.status = FitStatus::singular;
      return;
    }
    const Solution next = solve(pr, free, fixed);
    double change = 0;
    for (std::size_t t = 0; t < terms; ++t) {
      const double scale = std::fabs(next.theta[t]) + std::sqrt(std::fabs(next.cov[t][t])) + 1e-300;
      change = std::fmax(change, std::fabs(next.theta[t] - sol.theta[t]) / scale);
    }
    sol = next;
    if (change < 1e-6) break;
  }

  std::size_t fitted = 0;
  for (bool a : sol.active) fitted += a;
  out.chi2 = sol.chi2;
  out.dof = pr.n > fitted ? pr.n - fitted : 0;
  out.birge = out.chi2_per_dof() > 1 ? std::sqrt(out.chi2_per_dof()) : 1.0;
  out.status = rejected(out.chi2, out.dof) ? FitStatus::rejected : FitStatus::ok;
  for (std::size_t t = 0; t < terms; ++t) {
    Ieee952Parameter& p = out.p[t];
    p = Ieee952Parameter{};
    p.fitted = sol.active[t];
    const double theta = sol.theta[t];
    p.value = theta > 0 ? std::sqrt(theta) : 0.0;
    // A free term the non-negative solution left out: the uncertainty it has in the full model.
    const double variance = p.fitted ? sol.cov[t][t] : free[t] ? sol.free_variance[t] : 0.0;
    const double sd = std::sqrt(std::fabs(variance)) * out.birge;
    p.uncertainty = p.value > 0 ? sd / (2 * p.value) : std::sqrt(sd);
    if (!p.fitted || !(theta > 2 * sd)) continue;
    for (std::size_t i = 0; i < pr.n && !p.resolved; ++i) {  // the largest contribution somewhere
      // The ramp's response is modeled exactly for Allan and modified Allan estimates only: a
      // total-family point answers a ramp otherwise (TOTVAR's reflection, TheoBR's ratio), so R is
      // never resolved on one (the recovery study found it resolved there but off by more than
      // two sigma).
      if (t == 4 && pr.point[i]->variance_scale != 1) continue;
      const double mine = theta * pr.row(i)[t];
      bool largest = true;
      for (std::size_t u = 0; u < terms; ++u)
        if (u != t && sol.theta[u] * pr.row(i)[u] > mine) largest = false;
      p.resolved = largest;
    }
  }
}

}  // namespace

Ieee952Fit fit_ieee952(std::span<const FitPoint> points, const FitSetup& setup, FitCurve curve,
                       std::span<double> workspace, PairSumCache* cache) {
  Ieee952Fit out;
  out.curve = curve;
  Problem pr;
  pr.tau0 = setup.tau0_s;
  pr.n_phase = setup.n_phase;
  pr.spread = setup.model_spread;
  for (const FitPoint& p : points) {
    const bool wanted = curve == FitCurve::both || (curve == FitCurve::avar) == (p.stat == Stat::avar);
    if (!wanted || (p.stat != Stat::avar && p.stat != Stat::mvar) || p.n == 0 || !(p.variance > 0) || pr.n >= 128)
      continue;
    if (unbroken_grid(p.stat, p.m, p.stride, setup.n_phase).n == 0) continue;
    pr.point[pr.n++] = &p;
  }
  // At m = 1 the modified Allan estimate is the Allan one, term for term: keep it once.
  if (curve == FitCurve::both) {
    bool avar_at_1 = false;
    for (std::size_t i = 0; i < pr.n; ++i) avar_at_1 |= pr.point[i]->m == 1 && pr.point[i]->stat == Stat::avar;
    std::size_t kept = 0;
    for (std::size_t i = 0; i < pr.n; ++i)
      if (!(avar_at_1 && pr.point[i]->m == 1 && pr.point[i]->stat == Stat::mvar)) pr.point[kept++] = pr.point[i];
    pr.n = kept;
  }
  if (workspace.size() < ieee952_workspace_doubles(pr.n) || !(setup.tau0_s > 0)) return out;

  // Quantization, where its white level is known (counts): tested before the fit and after it.
  const double qw2 = setup.white_quantization * setup.white_quantization;
  std::array<bool, terms> free{true, true, true, true, true};
  std::array<double, terms> fixed{};
  if (qw2 > 0 && below_white_quantization(pr, qw2)) leave_out_quantization(pr, qw2, free, fixed, out);
  Solution sol;
  fit_points(pr, setup, free, fixed, workspace, cache, out, sol);
  if (qw2 > 0 && out.quantization_white && out.status != FitStatus::too_few_points &&
      out.status != FitStatus::singular && quantization_departs(pr, sol)) {
    leave_out_quantization(pr, qw2, free, fixed, out);
    fit_points(pr, setup, free, fixed, workspace, cache, out, sol);
  }
  return out;
}

}  // namespace gyrochar
