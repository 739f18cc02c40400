#include "gyrochar/ieee952.hpp"

#include <cmath>

namespace gyrochar {
namespace {

constexpr double pi = 3.14159265358979323846;

// The five basis functions: variance = sum_k coefficient_k * basis_k(tau).
std::array<double, 5> basis(double tau, Ieee952Curve curve, double tau0) {
  if (curve == Ieee952Curve::avar)
    return {3.0 / (tau * tau), 1.0 / tau, 2.0 * std::log(2.0) / pi, tau / 3.0, tau * tau / 2.0};
  const double m = tau / tau0;
  return {3.0 * tau0 / (tau * tau * tau), (m * m + 1.0) / (2.0 * m * m * tau), 0.2977, 11.0 * tau / 40.0,
          tau * tau / 2.0};
}

// Solves the n x n system a x = b (Gaussian elimination, partial pivoting) and inverts a into inv.
bool solve(std::array<std::array<double, 5>, 5> a, std::array<double, 5> b, std::size_t n, std::array<double, 5>& x,
           std::array<std::array<double, 5>, 5>& inv) {
  std::array<std::array<double, 5>, 5> id{};
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

}  // namespace

double ieee952_variance(const std::array<double, 5>& p, double tau_s, Ieee952Curve curve, double tau0_s) {
  const auto f = basis(tau_s, curve, tau0_s);
  double v = 0;
  for (std::size_t k = 0; k < 5; ++k) v += p[k] * p[k] * f[k];
  return v;
}

Ieee952Fit fit_ieee952(std::span<const VariancePoint> points, Ieee952Curve curve, double tau0_s) {
  Ieee952Fit out;
  std::array<bool, 5> active{true, true, true, true, true};
  std::array<double, 5> coef{};
  std::array<std::array<double, 5>, 5> cov{};
  for (int round = 0; round < 5; ++round) {  // active set: drop a negative coefficient, refit
    std::size_t idx[5];
    std::size_t n = 0;
    for (std::size_t k = 0; k < 5; ++k)
      if (active[k]) idx[n++] = k;
    if (n == 0) return out;
    // Column scales: the basis spans many decades; normalize for conditioning.
    std::array<double, 5> scale{};
    for (const auto& pt : points) {
      if (!(pt.edf > 0) || !(pt.variance > 0) || !(pt.tau_s > 0)) continue;
      const auto f = basis(pt.tau_s, curve, tau0_s);
      for (std::size_t j = 0; j < n; ++j) scale[j] += f[idx[j]] * f[idx[j]] / (pt.variance * pt.variance);
    }
    for (std::size_t j = 0; j < n; ++j) scale[j] = scale[j] > 0 ? 1.0 / std::sqrt(scale[j]) : 1.0;
    std::array<double, 5> x{};
    bool solved = false;
    std::size_t used = 0;
    double chi2 = 0;
    for (int iteration = 0; iteration < 8; ++iteration) {  // reweight with the model variances
      std::array<std::array<double, 5>, 5> a{};
      std::array<double, 5> b{};
      used = 0;
      for (const auto& pt : points) {
        if (!(pt.edf > 0) || !(pt.variance > 0) || !(pt.tau_s > 0)) continue;
        const auto f = basis(pt.tau_s, curve, tau0_s);
        double model = 0;
        for (std::size_t j = 0; j < n; ++j) model += x[j] * scale[j] * f[idx[j]];
        const double sigma2 = solved && model > 0 ? model : pt.variance;
        const double w = pt.edf / (2.0 * sigma2 * sigma2);
        for (std::size_t i = 0; i < n; ++i) {
          const double fi = f[idx[i]] * scale[i];
          b[i] += w * fi * pt.variance;
          for (std::size_t j = 0; j < n; ++j) a[i][j] += w * fi * f[idx[j]] * scale[j];
        }
        ++used;
      }
      if (used < n) return out;
      std::array<std::array<double, 5>, 5> inv{};
      if (!solve(a, b, n, x, inv)) return out;
      solved = true;
      chi2 = 0;
      for (const auto& pt : points) {
        if (!(pt.edf > 0) || !(pt.variance > 0) || !(pt.tau_s > 0)) continue;
        const auto f = basis(pt.tau_s, curve, tau0_s);
        double model = 0;
        for (std::size_t j = 0; j < n; ++j) model += x[j] * scale[j] * f[idx[j]];
        const double r = pt.variance - model;
        if (model > 0) chi2 += r * r * pt.edf / (2.0 * model * model);
      }
      for (std::size_t i = 0; i < n; ++i)
        for (std::size_t j = 0; j < n; ++j) cov[idx[i]][idx[j]] = inv[i][j] * scale[i] * scale[j];
      for (std::size_t j = 0; j < n; ++j) coef[idx[j]] = x[j] * scale[j];
    }
    // Drop the most negative coefficient (relative to its uncertainty) and refit.
    std::size_t worst = 5;  // none
    double worst_z = 0;
    for (std::size_t j = 0; j < n; ++j) {
      const std::size_t k = idx[j];
      const double sd = std::sqrt(std::fabs(cov[k][k]));
      const double z = sd > 0 ? coef[k] / sd : coef[k];
      if (coef[k] < 0 && (worst == 5 || z < worst_z)) {
        worst = k;
        worst_z = z;
      }
    }
    out.points = used;
    out.chi2_per_dof = used > n ? chi2 / static_cast<double>(used - n) : 0.0;
    if (worst == 5) break;
    active[worst] = false;
    coef[worst] = 0;
  }
  for (std::size_t k = 0; k < 5; ++k) {
    Ieee952Parameter& p = out.p[k];
    if (!active[k] || !(coef[k] > 0)) continue;
    p.value = std::sqrt(coef[k]);
    p.uncertainty = std::sqrt(std::fabs(cov[k][k])) / (2.0 * p.value);
    // Resolved: the coefficient stands above its own uncertainty.
    p.resolved = coef[k] > std::sqrt(std::fabs(cov[k][k]));
  }
  out.ok = true;
  return out;
}

}  // namespace gyrochar
