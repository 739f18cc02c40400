// The IEEE-952 fit's linear algebra (see ieee952_problem.hpp): each point's design row, the
// covariance of the points under given parameters, and the non-negative generalized least squares.
#include <cmath>

#include "ieee952_problem.hpp"

namespace gyrochar::ieee952_fit {

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
        for (std::size_t k = 0; mg && k < pr.model.markov; ++k)
          lin += s[k] * mg[max_markov * noises + max_markov * max_markov + k];
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
  Terms free_theta{}, free_variance{};
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
    const bool in_model = (mask & pr.model.held) == 0;  // else only the unconstrained estimates
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
    if (k == n_free)  // every free term: the unconstrained estimates and their variances
      for (std::size_t a = 0; a < k; ++a) {
        free_theta[idx[a]] = x[a] * scale[idx[a]];
        free_variance[idx[a]] = inv[a][a] * scale[idx[a]] * scale[idx[a]];
      }
    bool feasible = in_model;
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
  best.free_theta = free_theta;
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
// A pair's sums are made for the noises kept there alone: the nodes do not depend on the noises,
// so the kept sums are the bits they would be beside the others, and where the flicker noise is
// not kept its digamma values at every node are saved. Rows are independent: row i writes the
// pairs (i, j), j <= i, alone, so a RowRunner may run them on several threads. The longest rows
// first, so that threads finish together.
void markov_sums_of_points(Problem& pr, const FitSetup& setup) {
  struct MarkovRows {
    Problem& pr;
    const FitSetup& setup;
    void row(std::size_t r) const {
      const std::span<const double> rates(pr.model.a.data(), pr.model.markov);
      const std::size_t i = pr.n - 1 - r;
      const FitPoint& a = *pr.point[i];
      const TermGrid ga = unbroken_grid(a.stat, a.m, a.stride, setup.n_phase);
      for (std::size_t j = 0; j <= i; ++j) {
        const FitPoint& b = *pr.point[j];
        const double* g = pr.pair_at(i, j);
        NoiseSet kept;
        std::array<std::size_t, noises> noise_of{};  // kept noise p is the model's noise noise_of[p]
        for (std::size_t t = 0; t < noises; ++t)
          if (t == 0 || g[cc_index(t, t)] != 0) {
            noise_of[kept.count] = t;
            kept.alpha[kept.count++] = alphas[t];
          }
        const MarkovPairSums s = markov_pair_sums(kept, rates, ga, unbroken_grid(b.stat, b.m, b.stride, setup.n_phase));
        double* mg = pr.markov_pair_at(i, j);
        for (std::size_t k = 0; k < max_markov; ++k) {
          for (std::size_t t = 0; t < noises; ++t) mg[k * noises + t] = 0.0;
          for (std::size_t p = 0; p < kept.count; ++p) mg[k * noises + noise_of[p]] = s.cm[k][p];
          for (std::size_t l = 0; l < max_markov; ++l) mg[max_markov * noises + k * max_markov + l] = s.mm[k][l];
          mg[max_markov * noises + max_markov * max_markov + k] = s.c[k];
        }
      }
    }
  } rows{pr, setup};
  run_rows(setup.rows, {[](void* context, std::size_t r) { static_cast<const MarkovRows*>(context)->row(r); }, &rows}, pr.n);
  pr.exact_markov = true;
}

// The sinusoid sums of every pair of points for the given sinusoids (setup.sinusoid_hz), with the
// power-law noises pair_sums_of_points() kept for that pair. O(P^2 x nodes).
void sinusoid_sums_of_points(Problem& pr, const FitSetup& setup, PairSumCache* cache) {
  const SinusoidSumInputs in = ieee952_sinusoid_inputs(setup);
  for (std::size_t k = 0; k < max_sinusoids; ++k) pr.hz[k] = setup.sinusoid_hz[k] > 0 ? setup.sinusoid_hz[k] : 0.0;
  for (std::size_t i = 0; i < pr.n; ++i) {
    const FitPoint& a = *pr.point[i];
    const TermGrid ga = unbroken_grid(a.stat, a.m, a.stride, setup.n_phase);
    for (std::size_t j = 0; j <= i; ++j) {
      const FitPoint& b = *pr.point[j];
      const double* g = pr.pair_at(i, j);
      double* sg = pr.sinusoid_pair_at(i, j);
      for (std::size_t k = 0; k < sinusoid_slots; ++k) sg[k] = 0;
      if (!in.any()) continue;
      const TermGrid gb = unbroken_grid(b.stat, b.m, b.stride, setup.n_phase);
      const SinusoidPairSums s = cache ? cache->sinusoid_sums(in.set, in.thetas, ga, gb)
                                       : sinusoid_pair_sums(in.set, in.thetas, ga, gb);
      for (std::size_t k = 0; k < max_sinusoids; ++k)
        for (std::size_t t = 0; t < noises; ++t) sg[k * noises + t] = t == 0 || g[cc_index(t, t)] != 0 ? s.cs[k][t] : 0.0;
    }
  }
}

// ln det Sigma of the covariance pr.sigma holds, factored (twice the sum of ln L_ii).
double log_det(const Problem& pr) {
  double sum = 0;
  for (std::size_t i = 0; i < pr.n; ++i) sum += 2 * std::log(pr.sigma[i * pr.n + i]);
  return sum;
}

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

}  // namespace gyrochar::ieee952_fit
