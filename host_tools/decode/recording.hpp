#pragma once
// gyrochar-decode's recordings: CSV and JSON lines (columns in host_tools/decode/README.md).
#include <fmt/format.h>

#include <cstdio>
#include <string>
#include <string_view>

#include "rows.hpp"

namespace gyrochar::decoding {

// The writers write to a FILE* they do not own; the caller checks ferror().
// Each call writes whole lines; O(size of the line); no allocation once the line buffer has grown
// (the JSON report, event and summary records are built with nlohmann::json and do allocate).

/// CSV, one row per tau per closed report, header first. Empty fields for unknown values. The
/// window rows of the dynamic Allan deviation share the columns and fill the window_ ones; the
/// column `type` tells them apart (tau, window).
class CsvWriter {
 public:
  /// Writes the header. `confidence` is the level of the intervals (column ci_level).
  /// `extra_header` names `extra_columns` columns after the others, each with its leading comma
  /// (--limits: the verdict columns, node_report.hpp); none by default.
  CsvWriter(std::FILE* out, double confidence, const std::string& extra_header = {}, std::size_t extra_columns = 0);
  /// `extra`: the row's extra fields, each with its leading comma (empty without extra columns).
  void row(const TauRow& r, const Units& units, std::string_view extra = {});
  void row(const WindowRow& r, const Units& units);  // the extra fields empty

 private:
  template <class T>
  void field(bool known, T value);                             // the value (or nothing) and a comma
  void model_fields(const std::optional<FitModelRow>& model);  // the fit_model columns, each with its comma
  void begin(double time_s, std::uint8_t node, std::uint8_t seq, std::uint8_t tau_index, std::uint64_t m, double tau_s);
  std::FILE* out_;
  double confidence_;
  std::size_t extra_columns_;
  fmt::memory_buffer line_;
};

/// JSON lines, one object per line, told apart by "type": "tau" (the CSV row but its fit_ columns),
/// "window" (a window row), "report" (one per closed report: status, node faults, link health,
/// metadata, IEEE-952 terms and the fit's summary with, from protocol version 4, its model), "event" (restart, offline, online, duplicate)
/// and "summary" (once, at the end: input counters and every node's link health).
class JsonlWriter {
 public:
  /// `confidence` is the level of the intervals ("ci_level").
  JsonlWriter(std::FILE* out, double confidence) : out_(out), confidence_(confidence) {}
  void row(const TauRow& r, const Units& units);
  void row(const WindowRow& r, const Units& units);
  void report(double time_s, const NodeView& node, std::uint8_t seq, const Units& units);
  void event(double time_s, DecoderEvent e, const NodeView& node);
  void summary(const Decoder& decoder, const InputCounters& input, const NodeFilter& shown);
  /// A record built elsewhere (one JSON object without '\n'), as one line: the acceptance records.
  void line(const std::string& text);

 private:
  template <class T>
  void member(const char* key, bool known, T value);  // ,"key":value (or null) into line_
  std::FILE* out_;
  double confidence_;
  fmt::memory_buffer line_;
};

}  // namespace gyrochar::decoding
