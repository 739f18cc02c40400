#pragma once
// The statistics whose terms the pyramid sums, and where their first term falls.
//   AVAR  x[e] - 2 x[e-m] + x[e-2m]                       overlapping Allan
//   MVAR  P[e+1] - 3 P[e+1-m] + 3 P[e+1-2m] - P[e+1-3m]   modified Allan (P: prefix sums of x)
//   HVAR  x[e] - 3 x[e-m] + 3 x[e-2m] - x[e-3m]           overlapping Hadamard
// TVAR derives from MVAR (tau^2 MVAR / 3).
#include <cstddef>
#include <cstdint>

namespace gyrochar {

enum class Stat : std::uint8_t { avar = 0, mvar = 1, hvar = 2 };
inline constexpr std::size_t stat_count = 3;

/// Order D of the difference in a statistic's terms: 2 (Allan, modified Allan) or 3 (Hadamard).
constexpr int difference_order(Stat s) { return s == Stat::hvar ? 3 : 2; }

/// Newest phase index of a statistic's first term in a run that starts at point 0: 2m (AVAR),
/// 3m - 1 (MVAR, whose term reaches P[e + 1]), 3m (HVAR).
constexpr std::uint64_t first_newest_point(Stat s, std::uint64_t m) {
  return s == Stat::avar ? 2 * m : s == Stat::mvar ? 3 * m - 1 : 3 * m;
}

}  // namespace gyrochar
