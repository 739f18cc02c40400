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

constexpr std::size_t power_terms = 5;  // Q N B K R
constexpr std::size_t noises = 4;       // Q N B K: the random ones
constexpr std::size_t max_terms = power_terms + max_markov + max_sinusoids;
constexpr std::size_t width = max_terms + 3;  // a row: the design, y, Sigma's diagonal, y less the held terms
constexpr std::size_t y_slot = max_terms, diag_slot = max_terms + 1, offset_slot = max_terms + 2;
// A pair's exact Markov sums: sum c_j c_t (j Markov, t noise), sum c_j c_l, sum c_j.
constexpr std::size_t markov_slots = max_markov * noises + max_markov * max_markov + max_markov;
// A pair's sinusoid sums: sum c_j c_t (j sinusoid, t noise).
constexpr std::size_t sinusoid_slots = max_sinusoids * noises;
static_assert(max_markov <= max_markov_rates && max_sinusoids <= max_sinusoid_rates);
static_assert(ieee952_workspace_doubles(7) == 7 * 8 / 2 * (14 + markov_slots + sinusoid_slots) + 7 * 7 + 7 * width);
constexpr std::array<int, noises> alphas{2, 0, -1, -2};  // Q N B K
using Terms = std::array<double, max_terms>;
using Flags = std::array<bool, max_terms>;
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
constexpr double bandwidth_left_out = 0.01;     // change of white rate noise by the sensor's filter, likewise
constexpr double pi = 3.14159265358979323846;

// The terms of one candidate model beyond the five: columns 5.. are its Markov terms, then its
// sinusoids; the filter changes N's column.
struct Model {
  std::size_t markov = 0;
  std::array<double, max_markov> a{};  // tau0 / Tc of each Markov term
  std::size_t sinusoids = 0;
  std::array<double, max_sinusoids> hz{};
  double band = 0;  // tau0 / Tf of the filter on N's white noise; 0: none
  std::size_t columns() const { return power_terms + markov + sinusoids; }
  std::size_t nonlinear() const { return markov + sinusoids + (band > 0 ? 1 : 0); }
};

// Innovation variance of term t per unit squared parameter: tau0^k.
double innovation_scale(std::size_t t, double tau0) { return t == 0 ? 1.0 : std::pow(tau0, static_cast<double>(t)); }

// E[term^2] -> variance: AVAR = E[a^2] / (2 m^2 tau0^2), MVAR = E[t^2] / (2 m^4 tau0^2).
double normalization(Stat s, std::uint64_t m, double tau0) {
  const double mm = static_cast<double>(m);
  return s == Stat::mvar ? 2 * mm * mm * mm * mm * tau0 * tau0 : 2 * mm * mm * tau0 * tau0;
}

// Expected variance of a Markov term of unit sigma^2 (a = tau0 / Tc).
double markov_column(double a, Stat s, std::uint64_t m, double tau0) {
  return markov_term_covariance(a, s, m, s, m, 0) * tau0 * tau0 / normalization(s, m, tau0);
}

// Expected variance of a sinusoid of unit A^2 at hz.
double sinusoid_column(double hz, Stat s, std::uint64_t m, double tau0) {
  const double x = pi * hz * static_cast<double>(m) * tau0;
  const double sx = std::sin(x);
  if (s == Stat::avar) return sx * sx * sx * sx / (x * x);
  const double s0 = std::sin(pi * hz * tau0), mm = static_cast<double>(m);
  return sx * sx * sx * sx * sx * sx / (x * x * mm * mm * s0 * s0);
}

// The five terms' expected variance of a point per unit squared parameter.
std::array<double, power_terms> power_design(Stat s, std::uint64_t m, double tau0) {
  std::array<double, power_terms> x{};
  const double nrm = normalization(s, m, tau0);
  for (std::size_t t = 0; t < noises; ++t)
    x[t] = term_covariance(alphas[t], s, m, s, m, 0) * innovation_scale(t, tau0) / nrm;
  const double tau = static_cast<double>(m) * tau0;
  x[4] = tau * tau / 2;
  return x;
}

// The design row of a point under a model: the expected variance per unit squared parameter, from
// the five terms' row p (power_design()).
Terms design(const Model& model, const std::array<double, power_terms>& p, Stat s, std::uint64_t m, double tau0) {
  Terms x{};
  for (std::size_t t = 0; t < power_terms; ++t) x[t] = p[t];
  // Filtered white rate noise of long-tau level N^2 / tau: a Markov term of sigma^2 = N^2 tanh(a/2) / tau0.
  if (model.band > 0) x[1] = markov_column(model.band, s, m, tau0) * std::tanh(model.band / 2) / tau0;
  for (std::size_t j = 0; j < model.markov; ++j) x[power_terms + j] = markov_column(model.a[j], s, m, tau0);
  for (std::size_t j = 0; j < model.sinusoids; ++j)
    x[power_terms + model.markov + j] = sinusoid_column(model.hz[j], s, m, tau0);
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

using Matrix = std::array<std::array<double, max_terms>, max_terms>;

// Solves the small symmetric system a x = b (Gauss-Jordan, partial pivoting) and inverts a.
bool solve_small(Matrix a, Terms b, std::size_t n, Terms& x, Matrix& inv) {
  Matrix id{};
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
  const FitPoint* point[max_fit_points];
  std::array<double, power_terms> power[max_fit_points];  // each point's five-term design (power_design())
  double tau0 = 1;
  std::uint64_t n_phase = 0;
  double spread = 0;
  Model model;              // the model the rows are made for
  // Each point's place in the first fit of this call: the pair sums and the sinusoids' sums are
  // kept by place and made once (a later fit has fewer points, never new ones).
  std::size_t place[max_fit_points];
  std::size_t places = 0;
  bool sums_made = false;
  double* pair = nullptr;   // per pair of places (i <= j): 10 sums c_t c_u, then 4 sums c_t
  double* markov_pair = nullptr;  // per pair (i <= j): the Markov terms' sums (markov_slots)
  bool exact_markov = false;      // markov_pair holds the sums of model.a: Sigma is exact
  double* sinusoid_pair = nullptr;            // per pair (i <= j): the sums of the given sinusoids
  std::array<double, max_sinusoids> hz{};     // the given sinusoids (FitSetup::sinusoid_hz)
  double* sigma = nullptr;  // n x n
  double* rows = nullptr;   // per point: the design, y, Sigma's diagonal, y less the held terms
  double* row(std::size_t i) const { return rows + i * width; }
  std::size_t place_pair(std::size_t i, std::size_t j) const {
    i = place[i];
    j = place[j];
    return i > j ? i * (i + 1) / 2 + j : j * (j + 1) / 2 + i;
  }
  double* pair_at(std::size_t i, std::size_t j) const { return pair + place_pair(i, j) * 14; }
  double* markov_pair_at(std::size_t i, std::size_t j) const {
    return markov_pair + (i > j ? i * (i + 1) / 2 + j : j * (j + 1) / 2 + i) * markov_slots;
  }
  double* sinusoid_pair_at(std::size_t i, std::size_t j) const { return sinusoid_pair + place_pair(i, j) * sinusoid_slots; }
  // Keeps the points for which keep(point) is true, in order, with their places.
  template <class Keep>
  void keep_points(Keep&& keep) {
    std::size_t kept = 0;
    for (std::size_t i = 0; i < n; ++i) {
      if (!keep(*point[i])) continue;
      place[kept] = place[i];
      point[kept++] = point[i];
    }
    n = kept;
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

// The rows of the points under the problem's model.
void set_rows(Problem& pr) {
  for (std::size_t i = 0; i < pr.n; ++i) {
    const FitPoint& a = *pr.point[i];
    const Terms x = design(pr.model, pr.power[i], a.stat, a.m, pr.tau0);
    for (std::size_t t = 0; t < max_terms; ++t) pr.row(i)[t] = x[t];
    pr.row(i)[y_slot] = a.variance;
  }
}

// Each noise's innovation variance at point i under theta, the model's other terms mapped onto
// them (the header says how): the filter's N at its filtered level; a Markov term's variance
// split between white rate noise and rate random walk by its local slope on the Allan scale.
std::array<double, noises> local_noise(const Problem& pr, const Terms& theta, std::size_t i) {
  std::array<double, noises> h{};
  const double* x = pr.row(i);
  const double* w = pr.power[i].data();
  for (std::size_t t = 0; t < noises; ++t) h[t] = (theta[t] > 0 ? theta[t] : 0) * innovation_scale(t, pr.tau0);
  if (pr.model.band > 0 && w[1] > 0) h[1] *= x[1] / w[1];
  const FitPoint& p = *pr.point[i];
  for (std::size_t j = 0; j < pr.model.markov && !pr.exact_markov; ++j) {
    const double th = theta[power_terms + j];
    if (!(th > 0)) continue;
    const double v = th * x[power_terms + j];
    const double next = markov_column(pr.model.a[j], p.stat, 2 * p.m, pr.tau0);
    const double slope = std::log2(next / x[power_terms + j]);
    double white_share = (1 - slope) / 2;
    white_share = white_share < 0 ? 0 : white_share > 1 ? 1 : white_share;
    if (w[1] > 0) h[1] += white_share * v / w[1] * innovation_scale(1, pr.tau0);
    if (w[3] > 0) h[3] += (1 - white_share) * v / w[3] * innovation_scale(3, pr.tau0);
  }
  return h;
}

// The covariance of the points under squared parameters theta (the random terms and the ramp's
// cross term 4 D_p D_q sum c, D the ramp's deterministic term value).
void covariance_of_points(const Problem& pr, const Terms& theta) {
  const double ramp = theta[4] > 0 ? theta[4] : 0;
  std::array<std::array<double, noises>, max_fit_points> local{};
  for (std::size_t i = 0; i < pr.n; ++i) local[i] = local_noise(pr, theta, i);
  for (std::size_t i = 0; i < pr.n; ++i) {
    for (std::size_t j = 0; j <= i; ++j) {
      const FitPoint& a = *pr.point[i];
      const FitPoint& b = *pr.point[j];
      const double* g = pr.pair_at(i, j);
      std::array<double, noises> h{};
      for (std::size_t t = 0; t < noises; ++t) h[t] = std::sqrt(local[i][t] * local[j][t]);
      double v = 0;
      for (std::size_t t = 0; t < noises; ++t)
        for (std::size_t u = 0; u < noises; ++u) v += h[t] * h[u] * g[cc_index(t, u)];
      // Markov terms, exactly: (sum_t h_t c_t + sum_j s_j c_j)^2 summed over the pairs.
      std::array<double, max_markov> s{};
      const double* mg = pr.exact_markov ? pr.markov_pair_at(i, j) : nullptr;
      for (std::size_t k = 0; mg && k < pr.model.markov; ++k) {
        const double th = theta[power_terms + k];
        s[k] = th > 0 ? th * pr.tau0 * pr.tau0 : 0.0;
        for (std::size_t t = 0; t < noises; ++t) v += 2 * s[k] * h[t] * mg[k * noises + t];
        for (std::size_t l = 0; l < pr.model.markov; ++l) v += s[k] * s[l] * mg[max_markov * noises + k * max_markov + l];
      }
      // Sinusoids: a random phase's cross part with the noises, 2 sum_t 2 A^2 tau0^2 h_t c_j c_t.
      const double* sg = pr.sinusoid_pair_at(i, j);
      for (std::size_t k = 0; k < pr.model.sinusoids; ++k) {
        const double th = theta[power_terms + pr.model.markov + k];
        std::size_t given = 0;
        while (given < max_sinusoids && pr.hz[given] != pr.model.hz[k]) ++given;
        if (!(th > 0) || given == max_sinusoids) continue;
        for (std::size_t t = 0; t < noises; ++t) v += 2 * th * pr.tau0 * pr.tau0 * h[t] * sg[given * noises + t];
      }
      v *= 2;
      if (ramp > 0) {
        const double ta = static_cast<double>(a.m) * pr.tau0, tb = static_cast<double>(b.m) * pr.tau0;
        const double da = ta * ta * (a.stat == Stat::mvar ? static_cast<double>(a.m) : 1.0);
        const double db = tb * tb * (b.stat == Stat::mvar ? static_cast<double>(b.m) : 1.0);
        double lin = 0;
        for (std::size_t t = 0; t < noises; ++t) lin += h[t] * g[10 + t];
        for (std::size_t k = 0; mg && k < pr.model.markov; ++k) lin += s[k] * mg[max_markov * noises + max_markov * max_markov + k];
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
    // rows' diagonal slot its diagonal.
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t j = 0; j < i; ++j) a[i * n + j] = a[j * n + i];
      a[i * n + i] = pr.row(i)[diag_slot] * (1 + raise);
    }
    if (cholesky(a, n)) return true;
  }
  return false;
}

// The covariance of the points under theta, factored in place (the rows keep its diagonal).
bool weigh(const Problem& pr, const Terms& theta) {
  covariance_of_points(pr, theta);
  for (std::size_t i = 0; i < pr.n; ++i) pr.row(i)[diag_slot] = pr.sigma[i * pr.n + i];
  return factor(pr);
}

struct Solution {
  Terms theta{};
  Matrix cov{};
  Flags active{};
  Terms free_variance{};  // of each free term in the model with every free term
  double chi2 = 0;
  bool ok = false;
  bool feasible = false;  // a non-negative solution with every term beyond the five in it was found
};

// Non-negative least squares on the whitened system: every subset of the free power-law terms is
// tried, the model's other terms always in (a candidate that needs one of them negative is not
// feasible).
Solution solve(const Problem& pr, const Flags& free, const Terms& fixed) {
  Solution best;
  const std::size_t n = pr.n;
  const std::size_t columns = pr.model.columns();
  // y less the held terms (a known offset).
  for (std::size_t i = 0; i < n; ++i) {
    double v = pr.row(i)[y_slot];
    for (std::size_t t = 0; t < columns; ++t)
      if (!free[t]) v -= fixed[t] * pr.row(i)[t];
    pr.row(i)[offset_slot] = v;
  }
  // Whitened design and data: L^-1 [X y]. Column scales: the basis spans many decades.
  Terms scale{};
  double whitened[max_fit_points][max_terms + 1];
  for (std::size_t c = 0; c <= columns; ++c) {
    double col[max_fit_points];
    const std::size_t from = c == columns ? offset_slot : c;
    for (std::size_t i = 0; i < n; ++i) col[i] = pr.row(i)[from];
    forward(pr.sigma, n, col, 1);
    for (std::size_t i = 0; i < n; ++i) whitened[i][c == columns ? max_terms : c] = col[i];
  }
  for (std::size_t t = 0; t < columns; ++t) {
    double s = 0;
    for (std::size_t i = 0; i < n; ++i) s += whitened[i][t] * whitened[i][t];
    scale[t] = s > 0 ? 1 / std::sqrt(s) : 1;
  }
  std::size_t n_free = 0;
  for (std::size_t t = 0; t < columns; ++t) n_free += free[t];
  Terms free_variance{};
  const unsigned extra = ((1u << columns) - 1) & ~((1u << power_terms) - 1);
  for (unsigned power_mask = 0; power_mask < (1u << power_terms); ++power_mask) {
    const unsigned mask = power_mask | extra;
    if (mask == 0) continue;
    std::size_t idx[max_terms];
    std::size_t k = 0;
    bool allowed = true;
    for (std::size_t t = 0; t < columns; ++t) {
      if (!(mask & (1u << t))) continue;
      if (!free[t]) allowed = false;
      idx[k++] = t;
    }
    if (!allowed || k > n) continue;
    Matrix ata{};
    Terms atb{};
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t a = 0; a < k; ++a) {
        const double xa = whitened[i][idx[a]] * scale[idx[a]];
        atb[a] += xa * whitened[i][max_terms];
        for (std::size_t b = 0; b < k; ++b) ata[a][b] += xa * whitened[i][idx[b]] * scale[idx[b]];
      }
    }
    Terms x{};
    Matrix inv{};
    if (!solve_small(ata, atb, k, x, inv)) continue;
    if (k == n_free)  // every free term: its variances
      for (std::size_t a = 0; a < k; ++a) free_variance[idx[a]] = inv[a][a] * scale[idx[a]] * scale[idx[a]];
    bool feasible = true;
    for (std::size_t a = 0; a < k; ++a) feasible &= x[a] >= 0;
    if (!feasible) continue;
    double chi2 = 0;
    for (std::size_t i = 0; i < n; ++i) {
      double r = whitened[i][max_terms];
      for (std::size_t a = 0; a < k; ++a) r -= whitened[i][idx[a]] * scale[idx[a]] * x[a];
      chi2 += r * r;
    }
    if (best.ok && chi2 >= best.chi2) continue;
    best = Solution{};
    best.ok = true;
    best.feasible = true;
    best.chi2 = chi2;
    for (std::size_t t = 0; t < columns; ++t) best.theta[t] = free[t] ? 0.0 : fixed[t];
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
    for (std::size_t i = 0; i < n; ++i) chi2 += whitened[i][max_terms] * whitened[i][max_terms];
    best.chi2 = chi2;
    for (std::size_t t = 0; t < columns; ++t) best.theta[t] = free[t] ? 0.0 : fixed[t];
    best.ok = true;
    best.feasible = extra == 0;
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
  const auto x = power_design(stat, m, tau0_s);
  double v = 0;
  for (std::size_t t = 0; t < power_terms; ++t) v += p[t] * p[t] * x[t];
  return v;
}

double ieee952_avar(const std::array<double, 5>& p, double tau) {
  constexpr double flicker_floor = 0.44127120030530318;  // 2 ln 2 / pi
  return 3 * p[0] * p[0] / (tau * tau) + p[1] * p[1] / tau + flicker_floor * p[2] * p[2] + p[3] * p[3] * tau / 3 +
         p[4] * p[4] * tau * tau / 2;
}

namespace {

Model model_of(const Ieee952Fit& fit, double tau0) {
  Model model;
  model.markov = fit.n_markov;
  for (std::size_t j = 0; j < fit.n_markov; ++j) model.a[j] = tau0 / fit.markov[j].tc_s;
  model.sinusoids = fit.n_sinusoids;
  for (std::size_t j = 0; j < fit.n_sinusoids; ++j) model.hz[j] = fit.sinusoids[j].frequency_hz;
  model.band = fit.bandwidth_tc_s > 0 ? tau0 / fit.bandwidth_tc_s : 0;
  return model;
}

Terms theta_of(const Ieee952Fit& fit) {
  Terms theta{};
  for (std::size_t t = 0; t < power_terms; ++t) theta[t] = fit.p[t].value * fit.p[t].value;
  for (std::size_t j = 0; j < fit.n_markov; ++j) theta[power_terms + j] = fit.markov[j].sigma.value * fit.markov[j].sigma.value;
  for (std::size_t j = 0; j < fit.n_sinusoids; ++j)
    theta[power_terms + fit.n_markov + j] = fit.sinusoids[j].amplitude.value * fit.sinusoids[j].amplitude.value;
  return theta;
}

}  // namespace

double fitted_variance(const Ieee952Fit& fit, Stat stat, std::uint64_t m, double tau0_s) {
  const Model model = model_of(fit, tau0_s);
  const Terms x = design(model, power_design(stat, m, tau0_s), stat, m, tau0_s);
  const Terms theta = theta_of(fit);
  double v = 0;
  for (std::size_t t = 0; t < model.columns(); ++t) v += theta[t] * x[t];
  return v;
}

namespace {

// Leaves out every point whose white-quantization part is quantization_left_out or more of it, and
// holds Q at the white level: the quantization is not white.
void leave_out_quantization(Problem& pr, double qw2, Flags& free, Terms& fixed, Ieee952Fit& out) {
  out.quantization_white = false;
  pr.keep_points([&](const FitPoint& p) {
    const double white = qw2 * power_design(p.stat, p.m, pr.tau0)[0];
    if (!(white >= quantization_left_out * p.variance)) return true;
    double& below = out.excluded_below_tau_s[p.stat == Stat::avar ? 0 : 1];
    const double next_octave = 2 * static_cast<double>(p.m) * pr.tau0;
    if (next_octave > below) below = next_octave;
    return false;
  });
  free[0] = false;
  fixed[0] = qw2;
}

// Leaves out every point where a first-order filter of a = tau0 / Tf changes white rate noise by
// bandwidth_left_out or more: below the sensor's bandwidth, its own filter shapes the curve.
void leave_out_bandwidth(Problem& pr, double a, Ieee952Fit& out) {
  pr.keep_points([&](const FitPoint& p) {
    const double white = power_design(p.stat, p.m, pr.tau0)[1];
    const double filtered = markov_column(a, p.stat, p.m, pr.tau0) * std::tanh(a / 2) / pr.tau0;
    if (!(std::fabs(filtered / white - 1) >= bandwidth_left_out)) return true;
    const double next_octave = 2 * static_cast<double>(p.m) * pr.tau0;
    if (next_octave > out.bandwidth_excluded_below_tau_s) out.bandwidth_excluded_below_tau_s = next_octave;
    return false;
  });
}

// Before the fit: a point the white quantization alone would dominate lies far below it (three
// standard deviations and 2 %). Only a pattern can do that: other noise adds.
bool below_white_quantization(const Problem& pr, double qw2) {
  for (std::size_t i = 0; i < pr.n; ++i) {
    const FitPoint& p = *pr.point[i];
    const double white = qw2 * power_design(p.stat, p.m, pr.tau0)[0];
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
    for (std::size_t t = 0; t < pr.model.columns(); ++t) model += sol.theta[t] * x[t];
    if (!(sol.theta[0] * x[0] >= 0.5 * model)) continue;
    const double gap = std::fabs(x[y_slot] - model);
    if (gap > 3 * std::sqrt(x[diag_slot]) && gap > 0.02 * model) return true;
  }
  return false;
}

// The pair sums of every two points: they depend on the geometry only. Of the five Allan noises
// (index 2 - alpha) the model has four.
void pair_sums_of_points(Problem& pr, const FitSetup& setup, PairSumCache* cache) {
  constexpr std::array<std::size_t, noises> allan_index{0, 2, 3, 4};
  for (std::size_t i = 0; i < pr.n; ++i) {
    const FitPoint& a = *pr.point[i];
    const TermGrid ga = unbroken_grid(a.stat, a.m, a.stride, setup.n_phase);
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
}

// The exact Markov sums of every pair of points for the Markov terms of pr.model (the power-law
// noises' sums where pair_sums_of_points() kept them; the Markov terms' own at every pair: their c
// is an exponential, without the rounding that far-apart power-law sums suffer). O(P^2 x nodes).
void markov_sums_of_points(Problem& pr, const FitSetup& setup) {
  NoiseSet set;
  for (std::size_t t = 0; t < noises; ++t) set.alpha[t] = alphas[t];
  set.count = noises;
  const std::span<const double> rates(pr.model.a.data(), pr.model.markov);
  for (std::size_t i = 0; i < pr.n; ++i) {
    const FitPoint& a = *pr.point[i];
    const TermGrid ga = unbroken_grid(a.stat, a.m, a.stride, setup.n_phase);
    for (std::size_t j = 0; j <= i; ++j) {
      const FitPoint& b = *pr.point[j];
      const MarkovPairSums s = markov_pair_sums(set, rates, ga, unbroken_grid(b.stat, b.m, b.stride, setup.n_phase));
      const double* g = pr.pair_at(i, j);
      double* mg = pr.markov_pair_at(i, j);
      for (std::size_t k = 0; k < max_markov; ++k) {
        for (std::size_t t = 0; t < noises; ++t) mg[k * noises + t] = t == 0 || g[cc_index(t, t)] != 0 ? s.cm[k][t] : 0.0;
        for (std::size_t l = 0; l < max_markov; ++l) mg[max_markov * noises + k * max_markov + l] = s.mm[k][l];
        mg[max_markov * noises + max_markov * max_markov + k] = s.c[k];
      }
    }
  }
  pr.exact_markov = true;
}

// The sinusoid sums of every pair of points for the given sinusoids (setup.sinusoid_hz), with the
// power-law noises pair_sums_of_points() kept for that pair. O(P^2 x nodes).
void sinusoid_sums_of_points(Problem& pr, const FitSetup& setup, PairSumCache* cache) {
  NoiseSet set;
  for (std::size_t t = 0; t < noises; ++t) set.alpha[t] = alphas[t];
  set.count = noises;
  std::array<double, max_sinusoids> theta{};
  for (std::size_t k = 0; k < max_sinusoids; ++k) {
    pr.hz[k] = setup.sinusoid_hz[k] > 0 ? setup.sinusoid_hz[k] : 0.0;
    theta[k] = 2 * pi * pr.hz[k] * setup.tau0_s;
  }
  for (std::size_t i = 0; i < pr.n; ++i) {
    const FitPoint& a = *pr.point[i];
    const TermGrid ga = unbroken_grid(a.stat, a.m, a.stride, setup.n_phase);
    for (std::size_t j = 0; j <= i; ++j) {
      const FitPoint& b = *pr.point[j];
      const double* g = pr.pair_at(i, j);
      double* sg = pr.sinusoid_pair_at(i, j);
      for (std::size_t k = 0; k < sinusoid_slots; ++k) sg[k] = 0;
      if (!(pr.hz[0] > 0) && !(pr.hz[max_sinusoids - 1] > 0)) continue;  // none given
      const TermGrid gb = unbroken_grid(b.stat, b.m, b.stride, setup.n_phase);
      const SinusoidPairSums s = cache ? cache->sinusoid_sums(set, theta, ga, gb) : sinusoid_pair_sums(set, theta, ga, gb);
      for (std::size_t k = 0; k < max_sinusoids; ++k)
        for (std::size_t t = 0; t < noises; ++t) sg[k * noises + t] = t == 0 || g[cc_index(t, t)] != 0 ? s.cs[k][t] : 0.0;
    }
  }
}

// Where a fit stands: its solution, status and numbers, before they are written out.
struct Candidate {
  Model model;
  Solution sol;
  FitStatus status = FitStatus::too_few_points;
  std::size_t dof = 0;
  std::size_t parameters = 0;
  double criterion = 0;
  bool valid = false;
};

double criterion_of(double chi2, std::size_t parameters, std::size_t points) {
  return chi2 + static_cast<double>(parameters) * std::log(static_cast<double>(points));
}

// The fit of the points under pr.model: first weights from each point's own EDF (first = true) or
// the covariance pr.sigma already holds, then the exact covariance under the current parameters
// until they settle (at most `iterations` times).
Candidate fit_model(Problem& pr, const Flags& free, const Terms& fixed, bool first, int iterations) {
  Candidate c;
  c.model = pr.model;
  std::size_t n_free = 0;
  for (std::size_t t = 0; t < pr.model.columns(); ++t) n_free += free[t];
  if (pr.n <= n_free || pr.n == 0) return c;
  set_rows(pr);
  if (first) {
    for (std::size_t i = 0; i < pr.n; ++i) {
      const FitPoint& p = *pr.point[i];
      const double edf = p.edf > 0 ? p.edf : static_cast<double>(p.n);
      for (std::size_t j = 0; j < pr.n; ++j) pr.sigma[i * pr.n + j] = 0;
      pr.sigma[i * pr.n + i] = 2 * p.variance * p.variance / edf + pr.spread * pr.spread * p.variance * p.variance;
      pr.row(i)[diag_slot] = pr.sigma[i * pr.n + i];
    }
    if (!cholesky(pr.sigma, pr.n)) {
      c.status = FitStatus::singular;
      return c;
    }
  }
  c.sol = solve(pr, free, fixed);
  for (int iteration = 0; iteration < iterations; ++iteration) {
    if (!weigh(pr, c.sol.theta)) {
      c.status = FitStatus::singular;
      return c;
    }
    const Solution next = solve(pr, free, fixed);
    double change = 0;
    for (std::size_t t = 0; t < pr.model.columns(); ++t) {
      const double scale = std::fabs(next.theta[t]) + std::sqrt(std::fabs(next.cov[t][t])) + 1e-300;
      change = std::fmax(change, std::fabs(next.theta[t] - c.sol.theta[t]) / scale);
    }
    c.sol = next;
    if (change < 1e-6) break;
  }
  std::size_t fitted = 0;
  for (std::size_t t = 0; t < pr.model.columns(); ++t) fitted += c.sol.active[t];
  c.dof = pr.n > fitted ? pr.n - fitted : 0;
  c.status = rejected(c.sol.chi2, c.dof) ? FitStatus::rejected : FitStatus::ok;
  // Each correlation time or frequency counts twice: searched over the whole tau range, it buys
  // more than one degree of freedom's worth of chi2 (once, a Markov term stood in for bias
  // instability or rate random walk in 7-10 % of the recovery study's runs; twice, 0-3 %).
  c.parameters = fitted + 2 * pr.model.nonlinear();
  c.criterion = criterion_of(c.sol.chi2, c.parameters, pr.n);
  c.valid = c.sol.feasible;
  return c;
}

// chi2 of pr.model under the covariance pr.sigma holds (factored): the profile a nonlinear
// parameter is searched on. Infinite where the model needs a term negative.
double profile_chi2(Problem& pr, const Flags& free, const Terms& fixed) {
  set_rows(pr);
  const Solution s = solve(pr, free, fixed);
  return s.feasible ? s.chi2 : HUGE_VAL;
}

// Minimizes profile_chi2 over *value in log space: a grid from lo to hi (`per_octave` a factor of
// two), then golden section around the best node. Leaves *value at the minimum and returns whether
// it lies inside the range (at an end, the data want the term where the search does not allow it).
bool search(Problem& pr, const Flags& free, const Terms& fixed, double* value, double lo, double hi, int per_octave) {
  const double step = std::log(2.0) / per_octave;
  double best_log = std::log(lo), best = HUGE_VAL;
  for (double l = std::log(lo); l <= std::log(hi) + 1e-12; l += step) {
    *value = std::exp(l);
    const double chi2 = profile_chi2(pr, free, fixed);
    if (chi2 < best) best = chi2, best_log = l;
  }
  double a = std::fmax(best_log - step, std::log(lo)), b = std::fmin(best_log + step, std::log(hi));
  constexpr double golden = 0.6180339887498949;
  double x1 = b - golden * (b - a), x2 = a + golden * (b - a);
  *value = std::exp(x1);
  double f1 = profile_chi2(pr, free, fixed);
  *value = std::exp(x2);
  double f2 = profile_chi2(pr, free, fixed);
  for (int k = 0; k < 24; ++k) {
    if (f1 < f2) {
      b = x2, x2 = x1, f2 = f1, x1 = b - golden * (b - a);
      *value = std::exp(x1);
      f1 = profile_chi2(pr, free, fixed);
    } else {
      a = x1, x1 = x2, f1 = f2, x2 = a + golden * (b - a);
      *value = std::exp(x2);
      f2 = profile_chi2(pr, free, fixed);
    }
  }
  const double at = f1 < f2 ? x1 : x2;
  *value = std::exp(at);
  constexpr double margin = 0.05;
  return at > std::log(lo) + margin && at < std::log(hi) - margin;
}

// The standard deviation of ln(*value) from the curvature of chi2 on the fitted model's own
// covariance (pr holds it), the linear terms solved again at each point: ln(value) +- h with
// h = 0.2, where the profile is a parabola to a few percent (0: no curvature).
double log_sd(Problem& pr, const Flags& free, const Terms& fixed, double* value) {
  constexpr double h = 0.2;
  const double at = *value;
  const double mid = profile_chi2(pr, free, fixed);
  *value = at * std::exp(h);
  const double up = profile_chi2(pr, free, fixed);
  *value = at * std::exp(-h);
  const double down = profile_chi2(pr, free, fixed);
  *value = at;
  set_rows(pr);
  const double curvature = up + down - 2 * mid;
  return curvature > 0 && std::isfinite(curvature) ? h * std::sqrt(2 / curvature) : 0.0;
}

// The standard deviation of ln(*value) from its profile: half the width of the interval where chi2
// (the linear terms solved again at each step, on the fitted model's covariance) lies within 1 of
// its minimum, walked out in steps of 0.1 to at most 3 either side. A Markov term's profile
// flattens away from its minimum, so the curvature there (log_sd()) says too little: in the
// recovery study its Tc lay within one such sigma of the truth in 38 % of the runs, not 68 %.
double profile_log_sd(Problem& pr, const Flags& free, const Terms& fixed, double* value) {
  constexpr double step = 0.1, reach = 3.0;
  const double at = *value;
  const double mid = profile_chi2(pr, free, fixed);
  double half[2] = {reach, reach};
  for (int side = 0; side < 2; ++side) {
    double before = 0;
    for (double l = step; l <= reach + 1e-9; l += step) {
      *value = at * std::exp(side == 0 ? -l : l);
      const double rise = profile_chi2(pr, free, fixed) - mid;
      if (rise >= 1) {
        half[side] = std::isfinite(rise) ? l - step + step * (1 - before) / (rise - before) : l - step / 2;
        break;
      }
      before = std::fmax(rise, 0.0);
    }
  }
  *value = at;
  set_rows(pr);
  return std::isfinite(mid) ? (half[0] + half[1]) / 2 : 0.0;
}

// True when column t of candidate c lies more than two standard uncertainties (Birge-scaled) above
// zero. Not "resolved": a Markov term shares its rising side with K and its falling side with N,
// and need not be the largest anywhere to be there (the fit still says whether it is resolved).
bool column_significant(const Candidate& c, std::size_t t) {
  const double birge = c.dof && c.sol.chi2 > static_cast<double>(c.dof) ? std::sqrt(c.sol.chi2 / static_cast<double>(c.dof)) : 1.0;
  return c.sol.active[t] && c.sol.theta[t] > 2 * std::sqrt(std::fabs(c.sol.cov[t][t])) * birge;
}

// The search for the model: the five terms, then the filter, Markov terms and sinusoids while each
// lowers the criterion. Leaves the winner's covariance in pr; `runner_up` is the next best.
Candidate select_model(Problem& pr, const FitSetup& setup, bool filter, const Flags& free, const Terms& fixed,
                       Candidate& runner_up, std::array<double, max_markov + 1>& nonlinear_sd) {
  pr.model = Model{};
  Candidate best = fit_model(pr, free, fixed, true, 12);
  runner_up = Candidate{};
  nonlinear_sd = {};
  if (!setup.select_model || !best.valid || best.status == FitStatus::singular) return best;
  // The taus a Markov term is sought among: from the shortest where white angle noise (Q) makes up
  // less than half the five terms' model (below, a Markov term cannot be told from a quantization
  // pattern: a steady 1.5 pulses a sample made one "appear" at Tc = 0.17 s) to the longest.
  double tau_lo = 1e300, tau_hi = 0;
  for (std::size_t i = 0; i < pr.n; ++i) {
    const double tau = static_cast<double>(pr.point[i]->m) * pr.tau0;
    double model = 0;
    for (std::size_t t = 0; t < power_terms; ++t) model += best.sol.theta[t] * pr.row(i)[t];
    if (best.sol.theta[0] * pr.row(i)[0] < 0.5 * model) tau_lo = std::fmin(tau_lo, tau);
    tau_hi = std::fmax(tau_hi, tau);
  }
  // A candidate wins when it lowers the criterion and the term it adds is significant (a Markov term
  // or sinusoid) or determined (the filter's Tf within a factor e^0.5); else it may be the runner-up.
  // Both are compared on the candidate's covariance (pr holds it): under its own, a model that
  // overshoots the long taus predicts their variance too large and is hardly charged for it.
  auto consider = [&](const Candidate& c, bool added_term_holds) {
    if (!c.valid || c.status == FitStatus::singular || c.status == FitStatus::too_few_points) return false;
    pr.model = best.model;
    const double incumbent = criterion_of(profile_chi2(pr, free, fixed), best.parameters, pr.n);
    pr.model = c.model;
    if (c.criterion < incumbent && added_term_holds) {
      runner_up = best;
      best = c;
      return true;
    }
    if (!runner_up.valid || c.criterion < runner_up.criterion) runner_up = c;
    return false;
  };
  // Restores the winner's rows and covariance (the search overwrote them).
  auto settle = [&]() {
    pr.model = best.model;
    set_rows(pr);
    weigh(pr, best.sol.theta);
  };
  // The sensor's filter on its white rate noise: Tf from tau0 / 20 to 4 tau0. Only where that
  // noise dominates the shortest tau: under white angle noise a filter on N cannot be told from
  // Q's own shape, nor from a quantization pattern (a steady rate of 1.5 pulses a sample made it
  // "find" a 3 Hz filter on a simulated gyro that has none).
  std::size_t shortest = 0;
  for (std::size_t i = 1; i < pr.n; ++i)
    if (pr.point[i]->m < pr.point[shortest]->m) shortest = i;
  const bool white_rate_first = best.sol.theta[1] * pr.row(shortest)[1] > best.sol.theta[0] * pr.row(shortest)[0];
  if (filter && white_rate_first) {
    pr.model = best.model;
    const bool inside = search(pr, free, fixed, &pr.model.band, 0.25, 20.0, 4);
    const Candidate c = fit_model(pr, free, fixed, false, 12);
    const double sd = log_sd(pr, free, fixed, &pr.model.band);
    if (consider(c, inside && sd > 0 && sd < 0.5)) nonlinear_sd[max_markov] = sd;
    settle();
  }
  // Sinusoids at the frequencies given, before the Markov terms: a spectral line found in the
  // record is evidence of its own, while a Markov term searched first takes up part of a
  // sinusoid's hump and stays in the model after the sinusoid came in (a simulated gyro with a
  // sinusoid and no Markov term was given one of 0.06 +- 0.97 deg/h that way).
  for (double hz : setup.sinusoid_hz) {
    if (!(hz > 0) || best.model.sinusoids >= max_sinusoids) continue;
    pr.model = best.model;
    pr.model.hz[pr.model.sinusoids++] = hz;
    const Candidate c = fit_model(pr, free, fixed, false, 12);
    consider(c, column_significant(c, pr.model.columns() - 1));
    settle();
  }
  // Markov terms, one at a time: Tc from twice the shortest tau (shorter, the term is white rate
  // noise over the whole curve: N's double) to half the longest (its Allan peak near 1.89 Tc).
  for (std::size_t k = 0; k < setup.markov_terms && k < max_markov && 4 * tau_lo <= tau_hi; ++k) {
    pr.model = best.model;
    pr.model.markov = k + 1;
    const double lo = 2 * pr.tau0 / tau_hi, hi = pr.tau0 / (2 * tau_lo);
    bool inside = search(pr, free, fixed, &pr.model.a[k], lo, hi, 4);
    // The terms found before were placed without this one: each moves to where it belongs beside
    // it (two passes over +-2 octaves). Without this the first of two Markov terms (20 s and
    // 300 s) sat at 26-31 s, its hump taking up part of the second, which was then not
    // significant, and B and R stood in for it.
    for (int pass = 0; pass < 2 && k > 0; ++pass)
      for (std::size_t j = 0; j <= k; ++j) {
        const double at = pr.model.a[j];
        search(pr, free, fixed, &pr.model.a[j], std::fmax(lo, at / 4), std::fmin(hi, at * 4), 8);
      }
    for (std::size_t j = 0; j <= k; ++j) {
      constexpr double margin = 1.05;
      inside &= pr.model.a[j] > lo * margin && pr.model.a[j] < hi / margin;
    }
    const Candidate c = fit_model(pr, free, fixed, false, 12);
    std::array<double, max_markov + 1> sds = nonlinear_sd;
    for (std::size_t j = 0; j <= k; ++j) sds[j] = log_sd(pr, free, fixed, &pr.model.a[j]);
    const double sd = sds[k];
    // Its Tc inside the range and determined (chi2 curves around it), every Markov term significant
    // (a second one that splits the first in two is not), and none taking white rate noise's place
    // (N fitted before, not after: that is N again).
    bool holds = inside && sd > 0 && (!best.sol.active[1] || c.sol.active[1]);
    for (std::size_t j = 0; j <= k; ++j) holds &= column_significant(c, power_terms + j);
    const bool better = consider(c, holds);
    if (better) nonlinear_sd = sds;
    settle();
    if (!better) break;
  }
  // The runner-up's figures on the chosen model's covariance (pr holds it), comparable with its own.
  if (runner_up.valid) {
    pr.model = runner_up.model;
    runner_up.sol.chi2 = profile_chi2(pr, free, fixed);
    runner_up.criterion = criterion_of(runner_up.sol.chi2, runner_up.parameters, pr.n);
    settle();
  }
  return best;
}

// The linear terms' covariance given the nonlinear parameters, widened by what their uncertainty
// passes on: along the profile theta(ln a), Var(theta) = C + b b^T sd(ln a)^2 with b = d theta /
// d ln a (the Schur complement of the joint information; a central difference of +-0.1). Without
// it a Markov term's sigma was stated with the uncertainty it would have if Tc were known: in the
// recovery study it lay within one stated sigma of the truth in 47 % of the runs instead of 68 %.
void widen_by_nonlinear(Problem& pr, const Flags& free, const Terms& fixed, const std::array<double, max_markov + 1>& nl_sd,
                        Solution& sol) {
  constexpr double h = 0.1;
  auto widen = [&](double* value, double sd) {
    if (!(sd > 0) || !(*value > 0)) return;
    const double at = *value;
    *value = at * std::exp(h);
    set_rows(pr);
    const Solution up = solve(pr, free, fixed);
    *value = at * std::exp(-h);
    set_rows(pr);
    const Solution down = solve(pr, free, fixed);
    *value = at;
    set_rows(pr);
    if (!up.feasible || !down.feasible) return;
    Terms b{};
    for (std::size_t t = 0; t < pr.model.columns(); ++t) b[t] = (up.theta[t] - down.theta[t]) / (2 * h);
    for (std::size_t t = 0; t < pr.model.columns(); ++t)
      for (std::size_t u = 0; u < pr.model.columns(); ++u) sol.cov[t][u] += b[t] * b[u] * sd * sd;
  };
  for (std::size_t j = 0; j < pr.model.markov; ++j) widen(&pr.model.a[j], nl_sd[j]);
  widen(&pr.model.band, nl_sd[max_markov]);
}

ModelSummary summary_of(const Candidate& c) {
  ModelSummary s;
  s.valid = c.valid;
  s.markov = static_cast<std::uint8_t>(c.model.markov);
  s.sinusoids = static_cast<std::uint8_t>(c.model.sinusoids);
  s.bandwidth = c.model.band > 0;
  s.status = c.status;
  s.chi2 = c.sol.chi2;
  s.dof = c.dof;
  s.parameters = c.parameters;
  s.criterion = c.criterion;
  return s;
}

// A term's parameter from its squared value and variance; resolved when fitted, its square more
// than two standard uncertainties above zero and the largest contribution at some point.
Ieee952Parameter parameter(const Problem& pr, const Solution& sol, const Flags& free, std::size_t t, double birge,
                           bool rejected_model) {
  Ieee952Parameter p;
  p.fitted = sol.active[t];
  const double theta = sol.theta[t];
  p.value = theta > 0 ? std::sqrt(theta) : 0.0;
  // A free term the non-negative solution left out: the uncertainty it has in the full model.
  const double variance = p.fitted ? sol.cov[t][t] : free[t] ? sol.free_variance[t] : 0.0;
  const double sd = std::sqrt(std::fabs(variance)) * birge;
  p.uncertainty = p.value > 0 ? sd / (2 * p.value) : std::sqrt(sd);
  if (!p.fitted || !(theta > 2 * sd) || rejected_model) return p;
  for (std::size_t i = 0; i < pr.n && !p.resolved; ++i) {  // the largest contribution somewhere
    // The ramp's response is modeled exactly for Allan and modified Allan estimates only: a
    // total-family point answers a ramp otherwise (TOTVAR's reflection, TheoBR's ratio), so R is
    // never resolved on one (the recovery study found it resolved there but off by more than
    // two sigma).
    if (t == 4 && pr.point[i]->variance_scale != 1) continue;
    const double mine = theta * pr.row(i)[t];
    bool largest = true;
    for (std::size_t u = 0; u < pr.model.columns(); ++u)
      if (u != t && sol.theta[u] * pr.row(i)[u] > mine) largest = false;
    p.resolved = largest;
  }
  return p;
}

// Writes the candidate into out: status, chi2, every term, the residuals.
void write_fit(const Problem& pr, const Candidate& c, const Flags& free, const std::array<double, max_markov + 1>& nl_sd,
               Ieee952Fit& out) {
  out.points = pr.n;
  out.status = c.status;
  out.chi2 = c.sol.chi2;
  out.dof = c.dof;
  out.birge = out.chi2_per_dof() > 1 ? std::sqrt(out.chi2_per_dof()) : 1.0;
  const bool rejected_model = c.status == FitStatus::rejected;
  for (std::size_t t = 0; t < power_terms; ++t) out.p[t] = parameter(pr, c.sol, free, t, out.birge, rejected_model);
  out.n_markov = c.model.markov;
  for (std::size_t j = 0; j < c.model.markov; ++j) {
    MarkovTerm& m = out.markov[j];
    m.sigma = parameter(pr, c.sol, free, power_terms + j, out.birge, rejected_model);
    m.tc_s = pr.tau0 / c.model.a[j];
    m.tc_uncertainty_s = m.tc_s * nl_sd[j] * out.birge;
  }
  out.n_sinusoids = c.model.sinusoids;
  for (std::size_t j = 0; j < c.model.sinusoids; ++j) {
    out.sinusoids[j].amplitude = parameter(pr, c.sol, free, power_terms + c.model.markov + j, out.birge, rejected_model);
    out.sinusoids[j].frequency_hz = c.model.hz[j];
  }
  out.bandwidth_tc_s = c.model.band > 0 ? pr.tau0 / c.model.band : 0;
  out.bandwidth_tc_uncertainty_s = out.bandwidth_tc_s * nl_sd[max_markov] * out.birge;
  out.n_residuals = pr.n;
  for (std::size_t i = 0; i < pr.n; ++i) {
    double model = 0;
    for (std::size_t t = 0; t < pr.model.columns(); ++t) model += c.sol.theta[t] * pr.row(i)[t];
    const double sd = std::sqrt(pr.row(i)[diag_slot]);
    out.residuals[i] = {pr.point[i]->stat, pr.point[i]->m, pr.point[i]->variance, model,
                        sd > 0 ? (pr.point[i]->variance - model) / sd : 0.0};
  }
}

// The chosen model with Markov terms fitted again on the exact covariance (the selection used the
// approximation local_noise() makes): its terms, its correlation times' uncertainties and the
// runner-up's figures on it. Keeps the approximate fit where the exact one fails (false).
bool refit_exactly(Problem& pr, const FitSetup& setup, const Flags& free, const Terms& fixed, Candidate& chosen,
                   Candidate& runner_up, std::array<double, max_markov + 1>& nl_sd) {
  pr.model = chosen.model;
  markov_sums_of_points(pr, setup);
  Candidate exact = fit_model(pr, free, fixed, false, 12);
  if (!exact.valid || exact.status == FitStatus::singular || !weigh(pr, exact.sol.theta)) {
    pr.exact_markov = false;
    pr.model = chosen.model;
    set_rows(pr);
    weigh(pr, chosen.sol.theta);
    return false;
  }
  chosen = exact;
  for (std::size_t k = 0; k < pr.model.markov; ++k) nl_sd[k] = profile_log_sd(pr, free, fixed, &pr.model.a[k]);
  if (runner_up.valid) {
    pr.model = runner_up.model;
    runner_up.sol.chi2 = profile_chi2(pr, free, fixed);
    runner_up.criterion = criterion_of(runner_up.sol.chi2, runner_up.parameters, pr.n);
    pr.model = chosen.model;
    set_rows(pr);
  }
  return true;
}

// The fit of the points in pr with model selection; fills out and leaves the winner's solution in
// `sol` (pr's rows and covariance are the winner's).
void fit_points(Problem& pr, const FitSetup& setup, bool filter, const Flags& free, const Terms& fixed,
                std::span<double> workspace, PairSumCache* cache, Ieee952Fit& out, Solution& sol) {
  out.points = pr.n;
  std::size_t n_free = 0;
  for (std::size_t t = 0; t < power_terms; ++t) n_free += free[t];
  if (pr.n <= n_free || pr.n == 0) {
    out.status = FitStatus::too_few_points;
    return;
  }
  // Laid out for every place (a later fit of this call finds the sums of the first where they were).
  const std::size_t places = pr.places;
  pr.pair = workspace.data();
  pr.sigma = pr.pair + places * (places + 1) / 2 * 14;
  pr.rows = pr.sigma + places * places;
  pr.markov_pair = pr.rows + places * width;
  pr.sinusoid_pair = pr.markov_pair + places * (places + 1) / 2 * markov_slots;
  pr.exact_markov = false;
  for (std::size_t i = 0; i < pr.n; ++i) pr.power[i] = power_design(pr.point[i]->stat, pr.point[i]->m, setup.tau0_s);
  if (!pr.sums_made) {
    pair_sums_of_points(pr, setup, cache);
    sinusoid_sums_of_points(pr, setup, cache);
    pr.sums_made = true;
  }
  Candidate runner_up;
  std::array<double, max_markov + 1> nl_sd{};
  const Candidate best = select_model(pr, setup, filter, free, fixed, runner_up, nl_sd);
  if (best.status == FitStatus::singular || best.status == FitStatus::too_few_points) {
    out.status = best.status;
    return;
  }
  Candidate chosen = best;
  // On the exact covariance the selection is checked once more: where the runner-up with fewer
  // Markov terms has the lower criterion there, it is the model (fitted on its own covariance),
  // unless it is rejected where the other is not: an accepted model is never traded for a
  // rejected one.
  if (chosen.model.markov > 0 && refit_exactly(pr, setup, free, fixed, chosen, runner_up, nl_sd) && runner_up.valid &&
      runner_up.model.markov < chosen.model.markov && runner_up.criterion < chosen.criterion) {
    const Candidate more = chosen;
    std::array<double, max_markov + 1> fewer_sd = nl_sd;
    pr.exact_markov = false;
    pr.model = runner_up.model;
    Candidate fewer = fit_model(pr, free, fixed, false, 12);
    for (std::size_t k = fewer.model.markov; k < max_markov; ++k) fewer_sd[k] = 0;
    Candidate none;
    if (fewer.valid && fewer.model.markov > 0) refit_exactly(pr, setup, free, fixed, fewer, none, fewer_sd);
    if (fewer.valid && (fewer.status == FitStatus::ok || more.status != FitStatus::ok)) {
      chosen = fewer;
      nl_sd = fewer_sd;
      runner_up = more;
      pr.model = more.model;
      runner_up.sol.chi2 = profile_chi2(pr, free, fixed);  // on the chosen model's covariance
      runner_up.criterion = criterion_of(runner_up.sol.chi2, runner_up.parameters, pr.n);
      pr.model = chosen.model;
      set_rows(pr);
    } else {
      pr.model = more.model;
      markov_sums_of_points(pr, setup);
      set_rows(pr);
      weigh(pr, more.sol.theta);
    }
  }
  sol = chosen.sol;
  Candidate widened = chosen;
  widen_by_nonlinear(pr, free, fixed, nl_sd, widened.sol);
  write_fit(pr, widened, free, nl_sd, out);
  out.chosen = summary_of(chosen);
  out.runner_up = summary_of(runner_up);
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
    if (!wanted || (p.stat != Stat::avar && p.stat != Stat::mvar) || p.n == 0 || !(p.variance > 0) ||
        pr.n >= max_fit_points)
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
  for (std::size_t i = 0; i < pr.n; ++i) pr.place[i] = i;
  pr.places = pr.n;

  // Quantization, where its white level is known (counts): tested before the fit and after it.
  const double qw2 = setup.white_quantization * setup.white_quantization;
  Flags free{};
  for (std::size_t t = 0; t < max_terms; ++t) free[t] = true;
  Terms fixed{};
  if (qw2 > 0 && below_white_quantization(pr, qw2)) leave_out_quantization(pr, qw2, free, fixed, out);
  // The test after the fit is made on the five terms: the filter or a Markov term would otherwise
  // take up a quantization pattern's departure at the short taus.
  const bool check_quantization = qw2 > 0 && out.quantization_white;
  FitSetup first = setup;
  if (check_quantization) first.select_model = false;
  Solution sol;
  fit_points(pr, first, true, free, fixed, workspace, cache, out, sol);
  bool again = first.select_model != setup.select_model;
  if (check_quantization && out.status != FitStatus::too_few_points && out.status != FitStatus::singular &&
      quantization_departs(pr, sol)) {
    leave_out_quantization(pr, qw2, free, fixed, out);
    again = true;
  }
  if (again) fit_points(pr, setup, true, free, fixed, workspace, cache, out, sol);
  // A sensor's filter that a first-order one does not describe well enough: the taus it reaches
  // are left out, and the rest fitted without it.
  if (out.status == FitStatus::rejected && out.bandwidth_tc_s > 0) {
    leave_out_bandwidth(pr, setup.tau0_s / out.bandwidth_tc_s, out);
    fit_points(pr, setup, false, free, fixed, workspace, cache, out, sol);
  }
  return out;
}

}  // namespace gyrochar
