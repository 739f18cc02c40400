#pragma once
// What the characterizer (and the batch paths) give per tau: the sums of squared terms of the
// overlapping and non-overlapped statistics, their term counts, and the variances made of them.
#include <array>
#include <cstddef>
#include <cstdint>

#include "gyrochar/stat.hpp"
#include "gyrochar/wide.hpp"

namespace gyrochar {

/// The sums of one tau, indexed by SumKind (stat.hpp): overlapping sums (terms every `stride`
/// points) and non-overlapped sums (terms every m points, on the decimated series). variance()
/// turns them into variances.

template <class Sum>
struct TauResult {
  std::uint64_t m = 0;                       // averaging factor, tau = m * tau0
  std::uint64_t stride = 1;                  // overlapping sums: terms every `stride` points
  std::array<Sum, sum_kinds> sum{};          // sums of squared terms, indexed by SumKind
  std::array<std::uint64_t, sum_kinds> n{};  // number of terms, indexed by SumKind
  std::uint32_t out_of_range = 0;            // terms skipped: value beyond int64 (CountArith)
  bool sum_overflow = false;                 // a sum of squares reached 2^127 (CountArith)
};

/// A sum's term stride.
template <class Sum>
constexpr std::uint64_t term_stride(const TauResult<Sum>& r, SumKind k) {
  return k == SumKind::avar_nonoverlapped || k == SumKind::hvar_nonoverlapped ? r.m : r.stride;
}

/// Variance in (phase unit / s)^2 from the sums of kind k: tau0_s the sample interval, unit the
/// phase unit per x step (e.g. the pulse weight in rad for counts, 1 for phase in s). 0 when
/// n = 0. O(1), no allocation. TVAR is tau^2 MVAR / 3.
template <class Sum>
constexpr double variance(const TauResult<Sum>& r, SumKind k, double tau0_s, double unit = 1.0) {
  const auto i = static_cast<std::size_t>(k);
  if (r.n[i] == 0) return 0.0;
  const double m = static_cast<double>(r.m);
  const double tau = m * tau0_s;
  double sum = 0.0;
  if constexpr (sizeof(Sum) == sizeof(UInt128)) {
    sum = gyrochar::to_double(r.sum[i]);
  } else {
    sum = r.sum[i];
  }
  const Stat s = stat_of(k);
  const double scale = s == Stat::avar ? 2.0 : s == Stat::mvar ? 2.0 * m * m : 6.0;
  return sum * unit * unit / (scale * static_cast<double>(r.n[i]) * tau * tau);
}

}  // namespace gyrochar
