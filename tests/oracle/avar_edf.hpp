#pragma once
// Exact equivalent degrees of freedom of the fully overlapped AVAR estimator for Gaussian noise
// that is a sum of white phase (PM), white frequency (FM) and random-walk frequency noise, from the
// covariance of its terms (design brief, section 3): with n terms t_j = x[j+2m] - 2x[j+m] + x[j]
// of autocovariance c(k), E[sum t^2] = n c(0) and Var[sum t^2] = 2 sum_{|k|<n} (n - |k|) c(k)^2, so
//   EDF = n^2 c(0)^2 / sum_{|k|<n} (n - |k|) c(k)^2.
// c(k) = sum_{a,b} w_a w_b G(k + (b - a) m), weights w = (1, -2, 1) at 0, m, 2m, where G is a
// generalized covariance of the phase in samples (valid for weights that cancel constants and
// lines): white PM of variance s2: G = s2 [s = 0]; white FM of increment variance s2 per sample:
// G = -s2 |s| / 2; random-walk FM (the continuous integral of a Brownian rate, sampled; K^2 tau0^3
// = s2): G = s2 |s|^3 / 12. All three vanish for |k| >= 2m + 1 (the terms then share no noise),
// so the sum is O(m).
// The chi-squared law with EDF degrees of freedom is then the usual approximation of the
// estimate's distribution: AVAR_hat ~ AVAR chi2_EDF / EDF.
#include <algorithm>
#include <cmath>
#include <cstdint>

namespace gyrochar::oracle {

struct NoiseLevels {
  double white_pm = 0;  // variance of each phase point's own noise (phase unit^2)
  double white_fm = 0;  // variance of each tau0 phase increment (phase unit^2)
  double rw_fm = 0;     // K^2 tau0^3 (phase unit^2)
};

inline double avar_term_autocovariance(const NoiseLevels& v, std::uint64_t m, std::int64_t k) {
  const std::int64_t mm = static_cast<std::int64_t>(m);
  const double w[3] = {1, -2, 1};
  double c = 0;
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) {
      const double s = std::fabs(static_cast<double>(k + (b - a) * mm));
      const double g = (s == 0 ? v.white_pm : 0.0) - v.white_fm * s / 2 + v.rw_fm * s * s * s / 12;
      c += w[a] * w[b] * g;
    }
  return c;
}

/// EDF of the overlapped AVAR at m with n_terms terms. O(m).
inline double avar_edf(const NoiseLevels& v, std::uint64_t m, std::uint64_t n_terms) {
  const double n = static_cast<double>(n_terms);
  const double c0 = avar_term_autocovariance(v, m, 0);
  double denominator = n * c0 * c0;
  const std::int64_t last = static_cast<std::int64_t>(std::min<std::uint64_t>(2 * m, n_terms - 1));
  for (std::int64_t k = 1; k <= last; ++k) {
    const double c = avar_term_autocovariance(v, m, k);
    denominator += 2 * (n - static_cast<double>(k)) * c * c;
  }
  return n * n * c0 * c0 / denominator;
}

}  // namespace gyrochar::oracle
