#include "noise_gen.hpp"

#include <random>

namespace gyrochar {

std::vector<double> power_law_phase(int alpha, std::size_t n, std::uint64_t seed) {
  const double d = (2.0 - alpha) / 2.0;
  std::vector<double> h(n);
  h[0] = 1.0;
  for (std::size_t k = 1; k < n; ++k) h[k] = h[k - 1] * (static_cast<double>(k) - 1.0 + d) / static_cast<double>(k);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<double> w(n), x(n, 0.0);
  for (auto& v : w) v = normal(rng);
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t k = 0; k <= i; ++k) x[i] += h[k] * w[i - k];
  return x;
}

}  // namespace gyrochar
