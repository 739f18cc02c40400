#pragma once
// gyrochar-analyze's command line as a typed request: every option parsed and checked before any
// data is read (parse_request), then the run's steps (run.hpp): plan, run, write. main() is the
// only place that ends the program; a step that meets an error throws a ToolError, which main()
// prints as "gyrochar-analyze: what: why" and returns as the exit code (hal/program/exit_codes.hpp).
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "analysis.hpp"
#include "analysis_report.hpp"
#include "limits.hpp"
#include "plan.hpp"

namespace gyrochar {

inline constexpr const char* analyze_program = "gyrochar-analyze";

/// An error of a step of gyrochar-analyze: the exit code and the line "program: what: why". Thrown
/// by the steps (bad(), fail()), caught by main() alone. Not a std::exception, so that no handler
/// of the engine's exceptions takes it for an internal error.
struct ToolError {
  int code;
  std::string what, why;
};
/// Throws ToolError{exit_code::bad_input, what, why}: an option or the input data.
[[noreturn]] void bad(const std::string& what, const std::string& why);
/// Throws ToolError{code, what, why}.
[[noreturn]] void fail(int code, const std::string& what, const std::string& why);

enum class OutputFormat { table, csv, json, stable32 };

/// --dynamic WINDOW[,STEP] in values of tau0.
struct DynamicSpec {
  std::uint64_t window = 0, step = 0;
};

struct Request {
  std::string path;     // the data file, "-" for standard input
  std::string source;   // its name in messages: the path, or "standard input"
  std::string command;  // the command line, quoted, for the report's provenance
  unsigned column = 0;  // 0: the reader chooses
  double nominal_hz = 0;
  // The engine's options as asked: type, tau0, confidence, alpha, the statistics computed (those
  // shown and those the fit, the limits and the plot need), the total family's settings, threads.
  // Its taus and stride factor are the planning step's (plan_taus).
  AnalysisOptions options;
  std::vector<DevStat> shown;  // the statistics asked for, in order
  TauRule taus = TauRule::octave;
  std::vector<std::uint64_t> listed;  // TauRule::list: the averaging factors
  StrideFactor stride = StrideFactor::full();
  ReportUnits units;
  OutputFormat format = OutputFormat::table;
  bool fit = false;  // --fit ieee952
  LongTau long_tau = LongTau::oadev;
  std::optional<DynamicSpec> dynamic;
  std::string plot_prefix, psd_path, kalibr_path, report_path, summary_path, limits_path;
  std::size_t psd_segment = 0;  // 0: the default
  bool sinusoid_search = true;
  std::vector<double> sinusoid_hz;
  bool want_psd = false;  // --psd, the static --plot, or the fit's sinusoid search
  std::vector<Limit> limits;
  bool show_progress = false;
};

/// Parses and checks the command line into `r`. Returns an exit code when the program ends here
/// (--help: 0; an option CLI11 refuses: 2, said on stderr), std::nullopt when it goes on. Throws
/// ToolError for an option the analyzer refuses (with its reason), in the order the options are
/// checked. Reads the limits file and the summary's header. O(argc + limits).
std::optional<int> parse_request(int argc, const char* const* argv, Request& r);

}  // namespace gyrochar
