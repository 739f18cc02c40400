// Stable32's result table ("--format stable32"): for each statistic its header lines and one row a
// tau in Stable32's own columns, so that a Stable32 user's scripts and eyes read gyrochar's numbers.
#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <iterator>
#include <string>
#include <vector>

#include "analysis_report.hpp"

namespace gyrochar {

namespace {

// Stable32's column line of a statistic (its name, the "Sigma Type", is the statistic's title()).
const char* stable32_columns(DevStat s) {
  constexpr const char* allan = "#  AF        Tau        #    Alpha  Min Sigma      Sigma         Max Sigma";
  constexpr const char* hadamard = "#  AF        Tau         #    Alpha  Min Sigma   Hadamard Sig     Max Sigma";
  // The columns as a table, one statistic a line (kept as written):
  // clang-format off
  switch (s) {
    case DevStat::adev:
    case DevStat::oadev: return allan;
    case DevStat::mdev: return "#  AF        Tau         #    Alpha  Min Sigma     Mod Sigma      Max Sigma";
    case DevStat::tdev: return "#  AF        Tau         #    Alpha  Min Sigma    Time Sigma      Max Sigma";
    case DevStat::hdev:
    case DevStat::ohdev:
    case DevStat::htotdev: return hadamard;
    case DevStat::totdev: return "#  AF        Tau         #    Alpha  Min Sigma    Total Sigma     Max Sigma";
    case DevStat::mtotdev: return "# AF          Tau        #     Alpha  Min Sigma     Mod Totdev      Max Sigma";
    case DevStat::ttotdev: return "#AF          Tau       #      Alpha  Min Sigma    Time Totdev    Max Sigma";
    case DevStat::theo1: return "#  AF   Th\u00eao1 Tau   Th\u00eao1 #    Alpha   Min Th\u00eao1    Th\u00eao1    Max Th\u00eao1";
    case DevStat::theoh: return "#  AF   Th\u00eaoH Tau   Th\u00eaoH #    Alpha   Min Th\u00eaoH    Th\u00eaoH    Max Th\u00eaoH";
  }
  // clang-format on
  return allan;
}

}  // namespace

std::string format_stable32(const Report& r) {
  const Analysis& a = r.analysis;
  const ReportUnits& u = r.units;
  const double k = u.factor();
  std::vector<DevStat> stats;  // in the order of the rows
  for (const AnalysisRow& row : a.rows)
    if (std::find(stats.begin(), stats.end(), row.stat) == stats.end()) stats.push_back(row.stat);
  std::string s;
  auto to = std::back_inserter(s);
  for (const DevStat stat : stats) {
    if (!s.empty()) s += '\n';
    fmt::format_to(to, "# STATISTICS FOR FILE: {}\n", std::filesystem::path(r.source).filename().string());
    fmt::format_to(to, "# {} Data Points 1 thru {} of {}\n", r.type == DataType::phase ? "Phase" : "Frequency",
                   r.range.count, r.range.count);
    fmt::format_to(to, "# Maximum = {:e}\n# Minimum = {:e}\n# Average = {:e}\n", r.range.max, r.range.min, r.range.mean());
    fmt::format_to(to, "# Sigma Type: {}\n# Confidence Factor = {:.3f}\n# Deadtime T/Tau = 1.000000\n", title(stat),
                   r.confidence);
    if (u.gyro) fmt::format_to(to, "# Units: {}\n", u.unit(stat));
    fmt::format_to(to, "#\n{}\n", stable32_columns(stat));
    for (const AnalysisRow& row : a.rows) {
      if (row.stat != stat) continue;
      fmt::format_to(to, "{:5d}{:13.4e}{:9d}{:6d}{:13.4e}{:14.4e}{:15.4e}\n", row.m, row.tau_s, row.n, row.alpha.value_or(0),
                     row.ci.valid ? row.ci.low * k : 0.0, row.dev * k, row.ci.valid ? row.ci.high * k : 0.0);
    }
  }
  return s;
}

}  // namespace gyrochar
