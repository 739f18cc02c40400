#pragma once
// The vocabulary of statistics: every statistic gyrochar computes, in ONE table (dev_stats below)
// with its name (the word --stats, the CSV, the JSON and the Python package use), its title and
// the sums it is made of. DevStat is the statistic; the other enums that name one are narrower,
// each for its own job, and none has names of its own:
//   Stat          (here)            the three term families the pyramid sums: a difference, not a statistic
//   SumKind       (here)            the five sums of one tau (a family, overlapping or not): a sum
//   FitCurve      (ieee952.hpp)     which curve the IEEE-952 fit reads: OADEV's (avar), MDEV's (mvar), both
//   LongTau       (host_tools/analyze/analysis_report.hpp)  what the fit reads at long tau
//   protocol::DevKind (core/wire)   the two deviations a node sends. Its `adev` is the OVERLAPPING
//                 Allan deviation (DevStat::oadev), as is the decoder's `adev` column and a limit's
//                 adev(TAU); DevStat::adev is the non-overlapped one. docs/architecture.md, "Names
//                 of statistics", is where this double meaning (kept for compatibility) is explained.
//
// The term families:
//   AVAR  x[e] - 2 x[e-m] + x[e-2m]                       Allan
//   MVAR  P[e+1] - 3 P[e+1-m] + 3 P[e+1-2m] - P[e+1-3m]   modified Allan (P: prefix sums of x)
//   HVAR  x[e] - 3 x[e-m] + 3 x[e-2m] - x[e-3m]           Hadamard
// TVAR derives from MVAR (tau^2 MVAR / 3).
#include <array>
#include <cstddef>
#include <cstdint>

namespace gyrochar {

/// The term family of a statistic: which difference of the phase its terms are.
enum class Stat : std::uint8_t { avar = 0, mvar = 1, hvar = 2 };
inline constexpr std::size_t stat_count = 3;

/// Order D of the difference in a statistic's terms: 2 (Allan, modified Allan) or 3 (Hadamard).
constexpr int difference_order(Stat s) { return s == Stat::hvar ? 3 : 2; }

/// Newest phase index of a statistic's first term in a run that starts at point 0: 2m (AVAR),
/// 3m - 1 (MVAR, whose term reaches P[e + 1]), 3m (HVAR).
constexpr std::uint64_t first_newest_point(Stat s, std::uint64_t m) {
  return s == Stat::avar ? 2 * m : s == Stat::mvar ? 3 * m - 1 : 3 * m;
}

/// The sums of one tau (tau_result.hpp): overlapping sums of each family (terms every `stride`
/// points) and non-overlapped sums (terms every m points, on the decimated series).
enum class SumKind : std::uint8_t { avar = 0, mvar = 1, hvar = 2, avar_nonoverlapped = 3, hvar_nonoverlapped = 4 };
inline constexpr std::size_t sum_kinds = 5;

/// The family a sum belongs to.
constexpr Stat stat_of(SumKind k) {
  return k == SumKind::mvar                                         ? Stat::mvar
         : (k == SumKind::hvar || k == SumKind::hvar_nonoverlapped) ? Stat::hvar
                                                                    : Stat::avar;
}

/// The statistics: the six deviations the characterizer's sums give, Allan (non-overlapped),
/// overlapping Allan, modified Allan, time, Hadamard (non-overlapped), overlapping Hadamard; then
/// the total and Theo family (total.hpp), which need the whole record and are computed offline only
/// (estimate() in estimates.hpp does not take them).
enum class DevStat : std::uint8_t { adev, oadev, mdev, tdev, hdev, ohdev, totdev, mtotdev, ttotdev, htotdev, theo1, theoh };

struct DevStatInfo {
  DevStat stat;
  const char* name;   // "oadev": --stats, CSV, JSON keys, Python attributes
  const char* title;  // "Overlapping Allan": Stable32's name of it (its "Sigma Type")
  SumKind sums;       // its sums; for the total family, those of the statistic it stands for
  bool time;          // a time deviation: in phase units (TDEV, TTOTDEV), the others in rate units
};

/// Every statistic, in DevStat's order: the one table of their names.
inline constexpr std::array<DevStatInfo, 12> dev_stats{{
    {DevStat::adev, "adev", "Allan", SumKind::avar_nonoverlapped, false},
    {DevStat::oadev, "oadev", "Overlapping Allan", SumKind::avar, false},
    {DevStat::mdev, "mdev", "Modified Allan", SumKind::mvar, false},
    {DevStat::tdev, "tdev", "Time", SumKind::mvar, true},
    {DevStat::hdev, "hdev", "Hadamard", SumKind::hvar_nonoverlapped, false},
    {DevStat::ohdev, "ohdev", "Overlapping Hadamard", SumKind::hvar, false},
    {DevStat::totdev, "totdev", "Total", SumKind::avar, false},
    {DevStat::mtotdev, "mtotdev", "Modified Total", SumKind::mvar, false},
    {DevStat::ttotdev, "ttotdev", "Time Total", SumKind::mvar, true},
    {DevStat::htotdev, "htotdev", "Hadamard Total", SumKind::hvar, false},
    {DevStat::theo1, "theo1", "Th\u00eao1", SumKind::avar, false},
    {DevStat::theoh, "theoh", "Th\u00eaoH", SumKind::avar, false},
}};
constexpr bool dev_stats_in_order() {
  for (std::size_t i = 0; i < dev_stats.size(); ++i)
    if (static_cast<std::size_t>(dev_stats[i].stat) != i) return false;
  return true;
}
static_assert(dev_stats_in_order(), "dev_stats lists every DevStat once, in its order");

inline constexpr std::array<DevStat, 6> all_dev_stats{DevStat::adev, DevStat::oadev, DevStat::mdev,
                                                      DevStat::tdev, DevStat::hdev,  DevStat::ohdev};
inline constexpr std::array<DevStat, 6> total_dev_stats{DevStat::totdev,  DevStat::mtotdev, DevStat::ttotdev,
                                                        DevStat::htotdev, DevStat::theo1,   DevStat::theoh};
constexpr bool is_total(DevStat s) { return s >= DevStat::totdev; }

/// The table's row of s (the first row for a value outside the enumeration).
constexpr const DevStatInfo& info(DevStat s) {
  const auto i = static_cast<std::size_t>(s);
  return dev_stats[i < dev_stats.size() ? i : 0];
}
/// "adev", "oadev", ..., "theoh": a static string.
constexpr const char* name(DevStat s) { return info(s).name; }
/// "Allan", "Overlapping Allan", ..., "Th\u00eaoH" (UTF-8): a static string.
constexpr const char* title(DevStat s) { return info(s).title; }
/// The sums of a statistic; for the total family, the Allan-family statistic it stands for
/// (TOTDEV, Theo1, TheoH: overlapping AVAR; MTOTDEV, TTOTDEV: MVAR; HTOTDEV: overlapping HVAR).
constexpr SumKind sum_kind(DevStat s) { return info(s).sums; }
constexpr Stat stat_of(DevStat s) { return stat_of(sum_kind(s)); }

}  // namespace gyrochar
