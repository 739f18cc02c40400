#pragma once
// The estimator definitions evaluated directly over one segment of phase points with exact
// 128-bit integers (the oracle of the pyramid tests): sums of squared second differences (AVAR),
// of squared third differences of the phase sums (MVAR) and of squared third differences (HVAR),
// with their term counts. Terms whose newest point e has (offset + e) a multiple of `stride`
// (stride 1: fully overlapped; offset: the segment's first global phase index), or (offset + e) a
// multiple of m when nonoverlapping (the decimated series x[k m] on the global grid).
#include <array>
#include <cstdint>
#include <vector>

namespace gyrochar::oracle {

using i128 = __int128;
using u128 = unsigned __int128;

struct Exact {
  std::array<u128, 3> sum{};
  std::array<std::uint64_t, 3> n{};
  Exact& operator+=(const Exact& o) {
    for (int s = 0; s < 3; ++s) {
      sum[s] += o.sum[s];
      n[s] += o.n[s];
    }
    return *this;
  }
};

inline Exact brute_force(const std::vector<std::int64_t>& x, std::uint64_t m, std::uint64_t stride,
                         bool nonoverlapping = false, std::uint64_t offset = 0) {
  Exact r;
  std::vector<i128> p(x.size() + 1, 0);  // p[k] = sum_{i<k} x_i
  for (std::size_t k = 0; k < x.size(); ++k) p[k + 1] = p[k] + x[k];
  for (std::uint64_t e = 0; e < x.size(); ++e) {
    if ((offset + e) % (nonoverlapping ? m : stride) != 0) continue;
    if (e >= 2 * m) {
      const i128 a = i128{x[e]} - 2 * i128{x[e - m]} + x[e - 2 * m];
      r.sum[0] += static_cast<u128>(a * a);
      ++r.n[0];
    }
    if (e + 1 >= 3 * m) {
      const i128 t = p[e + 1] - 3 * p[e + 1 - m] + 3 * p[e + 1 - 2 * m] - p[e + 1 - 3 * m];
      r.sum[1] += static_cast<u128>(t * t);
      ++r.n[1];
    }
    if (e >= 3 * m) {
      const i128 h = i128{x[e]} - 3 * i128{x[e - m]} + 3 * i128{x[e - 2 * m]} - x[e - 3 * m];
      r.sum[2] += static_cast<u128>(h * h);
      ++r.n[2];
    }
  }
  return r;
}

}  // namespace gyrochar::oracle
