#pragma once
// The steps of a gyrochar-analyze run after its request (request.hpp), which main() calls in turn:
// plan (open the input, choose the taus and resolve the stride factor, check the memory, make the
// analyzer), run (read the values once, analyse, fit, decide the limits; nothing written yet, so
// that a refusal loses no output), write (stdout, then the files asked for). The dynamic Allan
// deviation (--dynamic) has the same three steps. Errors are thrown as ToolError.
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "analysis.hpp"
#include "analysis_report.hpp"
#include "datafile.hpp"
#include "dynamic.hpp"
#include "limits.hpp"
#include "plan.hpp"
#include "request.hpp"

namespace gyrochar {

/// A whole-record run, planned: the input opened (under --taus all read, to know N), the taus and
/// the stride factor in the request's options, the analyzer made for them.
struct RunPlan {
  std::unique_ptr<DataFile> file;
  std::vector<double> kept;  // --taus all: every value, and its line
  std::vector<std::uint64_t> kept_lines;
  std::uint64_t n_phase = 0;  // phase points: exact (all), an upper bound, or 0 (unknown)
  TauPlan taus;
  std::uint64_t budget = 0;  // bytes the history may take (memory_budget())
  std::unique_ptr<Analyzer> analyzer;
};
/// Plans the run of `r`: fills r.options' taus and stride factor ("full" resolved, plan_taus), the
/// limited taus that can be formed, and makes the analyzer. Throws ToolError for an input that
/// cannot be read, a tau list the stride factor cannot form, more memory than the process may use.
RunPlan plan_run(Request& r);

/// What a whole-record run found, ready to write: the shown rows and everything derived from
/// them. Refers to itself (report refers to shown): made in place, never moved.
struct RunOutcome {
  RunOutcome() = default;
  RunOutcome(const RunOutcome&) = delete;
  RunOutcome& operator=(const RunOutcome&) = delete;

  Analysis shown;                    // the rows of the statistics asked for
  std::optional<Report> report;      // of `shown`
  std::vector<AnalysisRow> plotted;  // OADEV and MDEV, shown or not (--plot, --report, --limits)
  std::vector<Decision> decisions;   // of r.limits
  std::string yaml;                  // --kalibr's file
  double run_s = 0;                  // the run's length, s
};
/// Reads the values once and analyses them, with the PSD, the fits and the verdicts, into `out`.
void run_analysis(const Request& r, RunPlan& plan, RunOutcome& out);
/// Writes stdout and the files asked for. Returns the exit code when stdout is written whole:
/// exit_code::ok, output_failed for a file that failed to close (said on stderr), or with limits
/// the verdicts' (acceptance.hpp). Throws ToolError for a file that cannot be written.
int write_outputs(const Request& r, const RunOutcome& out);

/// A dynamic run (--dynamic), planned: the window taus in r.options, the stride factor resolved.
struct DynamicPlan {
  std::unique_ptr<DynamicAnalyzer> analyzer;
};
DynamicPlan plan_dynamic(Request& r);
/// The windows analysed and the values read.
struct DynamicOutcome {
  std::vector<WindowAnalysis> windows;
  std::uint64_t values = 0;
};
DynamicOutcome run_dynamic(const Request& r, DynamicPlan& plan);
/// The surface on stdout, the heat maps to --plot. Throws ToolError when a plot cannot be written.
void write_dynamic(const Request& r, const DynamicOutcome& out);

}  // namespace gyrochar
