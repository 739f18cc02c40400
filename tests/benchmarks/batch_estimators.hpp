#pragma once
// The textbook batch estimators, the way batch tools compute them: the whole phase series in memory,
// O(N) work per tau, fully overlapped. The benchmark's point of comparison (not used by the product).
#include <cstdint>
#include <vector>

namespace gyrochar::bench {

struct BatchSums {
  double avar = 0, mvar = 0, hvar = 0;  // sums of squared terms
};

/// Phase from counts (x_0 = 0), then per tau: overlapped AVAR, MVAR (via prefix sums) and HVAR.
inline std::vector<BatchSums> batch_estimators(const std::vector<std::int32_t>& counts,
                                               const std::vector<std::uint64_t>& m_list) {
  const std::size_t n = counts.size() + 1;
  std::vector<double> x(n, 0.0), p(n + 1, 0.0);
  for (std::size_t k = 1; k < n; ++k) x[k] = x[k - 1] + counts[k - 1];
  for (std::size_t k = 0; k < n; ++k) p[k + 1] = p[k] + x[k];
  std::vector<BatchSums> out;
  for (const std::uint64_t m : m_list) {
    BatchSums s;
    for (std::size_t e = 2 * m; e < n; ++e) {
      const double a = x[e] - 2 * x[e - m] + x[e - 2 * m];
      s.avar += a * a;
      if (e + 1 >= 3 * m) {
        const double t = p[e + 1] - 3 * p[e + 1 - m] + 3 * p[e + 1 - 2 * m] - p[e + 1 - 3 * m];
        s.mvar += t * t;
      }
      if (e >= 3 * m) {
        const double h = x[e] - 3 * x[e - m] + 3 * x[e - 2 * m] - x[e - 3 * m];
        s.hvar += h * h;
      }
    }
    out.push_back(s);
  }
  return out;
}

}  // namespace gyrochar::bench
