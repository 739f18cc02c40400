#pragma once
// gyrochar-analyze --report FILE.html: the run as one self-contained HTML page
// (common/html_report.hpp): provenance, ADEV and MDEV plots with their intervals and the fitted
// model, a table per statistic with its intervals, the fits' terms with uncertainties and status,
// the read-off values, and the acceptance verdicts. Every table number carries the value the CSV
// and JSON give (data-value, shortest round trip, output units).
#include <string>
#include <vector>

#include "analysis_report.hpp"
#include "limits.hpp"

namespace gyrochar {

struct ReportProvenance {
  std::string command;      // the command line, as given
  std::string limits_path;  // --limits FILE; empty: none
};

/// The page. `curves`: the OADEV and MDEV rows to plot (engine units; every row computed, not only
/// those shown). O(rows).
std::string analysis_html(const Report& r, const std::vector<AnalysisRow>& curves, const ReportProvenance& provenance,
                          const std::vector<Limit>& limits, const std::vector<Decision>& decisions);

}  // namespace gyrochar
