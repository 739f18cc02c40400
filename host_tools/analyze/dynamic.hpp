#pragma once
// The dynamic Allan deviation offline (gyrochar-analyze --dynamic WINDOW[,STEP]): the analysis of
// every window of `window` values, one window starting every `step` values, each exactly what the
// analyzer gives for those values cut out into a file of their own (analysis.hpp: deviations,
// terms, identified noise, exact EDF, intervals). Window j holds values j step .. j step + window
// - 1; with step = window the windows follow each other, as the board's do (firmware/window.hpp).
//
// One pass, streaming: the windows that overlap are analysed side by side, ceil(window / step) at a
// time, each by its own Analyzer, so memory is that many pyramids whatever the length of the data,
// and the work per value that many times the analyzer's. docs/dynamic.md says what the surface
// shows and what it costs.
#include <cstdint>
#include <deque>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "analysis.hpp"
#include "analysis_report.hpp"
#include "heat_map.hpp"

namespace gyrochar {

/// The taus of a window of `window_values` values: those of `m_list` with 4 m <= window_values
/// (an MVAR estimate of a quarter of the window's terms at least), as the board chooses them.
std::vector<std::uint64_t> window_taus(const std::vector<std::uint64_t>& m_list, std::uint64_t window_values);

struct WindowAnalysis {
  std::uint64_t index = 0;        // j
  std::uint64_t first_value = 0;  // j step
  Analysis analysis;              // of values j step .. j step + window - 1
};

class DynamicAnalyzer {
 public:
  /// `options` as for an Analyzer, its m_list the window taus; window >= 1, step >= 1 values.
  /// Throws std::invalid_argument as Analyzer does, or for a window or step of 0.
  DynamicAnalyzer(const AnalysisOptions& options, std::uint64_t window, std::uint64_t step);
  /// The next values, each to every window it belongs to (in pieces that end where a window starts
  /// or completes). O(ceil(window / step)) times the analyzer's work per value; starting a window
  /// allocates its pyramid, completing one its rows. Throws as Analyzer::add (BadValue's index
  /// counts from the start of `values`).
  void add(std::span<const double> values);
  void add(double value) { add(std::span<const double>(&value, 1)); }
  /// The windows completed since the last call, in order (moved out).
  std::vector<WindowAnalysis> take_completed();
  std::uint64_t values() const { return values_; }

 private:
  struct Open {
    std::uint64_t index = 0, added = 0;
    std::unique_ptr<Analyzer> analyzer;
  };
  AnalysisOptions options_;
  std::uint64_t window_, step_, values_ = 0, next_index_ = 0;
  std::deque<Open> open_;  // oldest first: windows complete in the order they start
  std::vector<WindowAnalysis> completed_;
};

/// Everything the surface's outputs show.
struct DynamicReport {
  const std::vector<WindowAnalysis>& windows;
  DataType type = DataType::phase;
  double tau0_s = 1.0;
  double confidence = 0.683;
  ReportUnits units;
  std::uint64_t window = 0, step = 0;  // in values
  std::uint64_t values = 0;            // values read (those after the last complete window included)
  std::vector<DevStat> stats;          // in the order asked
};

/// A window's time span in the run, s: from its first value to its last (phase points) or over its
/// intervals (frequency and counts: value k averages over (k, k+1) tau0). O(1).
double window_start_s(const DynamicReport& r, const WindowAnalysis& w);
double window_end_s(const DynamicReport& r, const WindowAnalysis& w);

/// Aligned table for people: per statistic, one line per window (its start and end) and one column
/// per tau with the deviation. O(windows x rows).
std::string format_dynamic_table(const DynamicReport& r);
/// CSV: "window,start,end," followed by csv_header's columns (analysis_report.hpp), one row per
/// window, statistic and tau. O(windows x rows).
std::string format_dynamic_csv(const DynamicReport& r);
/// JSON: {"tau0", "type", "units", "confidence", "dynamic": {"window", "step", "window_s", "step_s",
/// "values"}, "windows": [{"index", "start", "end", "stride_factor", "results": [as to_json's]}]}.
nlohmann::json dynamic_to_json(const DynamicReport& r);
/// One heat map per statistic: rows the taus, a column per window, drawn over the window's centre
/// plus or minus half a step. O(windows x rows).
std::vector<HeatMap> dynamic_heat_maps(const DynamicReport& r);

}  // namespace gyrochar
