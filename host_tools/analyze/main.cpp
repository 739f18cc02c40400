// gyrochar-analyze: Allan-family deviations of a recorded file, with EDF, confidence intervals,
// noise identification and the IEEE-952 fit, computed by the same streaming core as the board.
// main() is the run's path: parse the command line into a request (request.hpp), plan the run,
// run it, write its outputs (run.hpp), and the one place that ends the program: the steps throw a
// ToolError, which it prints and returns as the exit code (hal/program/exit_codes.hpp). The engine
// is host_tools/analyze/analysis.*, the output formats host_tools/analyze/analysis_report.*.
#include <fmt/format.h>

#include <new>
#include <stdexcept>

#include "plan.hpp"
#include "read_pass.hpp"
#include "request.hpp"
#include "run.hpp"
#include "hal/program/exit_codes.hpp"

namespace {

using namespace gyrochar;

constexpr const char* program = analyze_program;

// The steps after the request; the exit code while standard output is still open.
int plan_run_write(Request& r) {
  if (r.dynamic) {
    DynamicPlan plan = plan_dynamic(r);
    const DynamicOutcome out = run_dynamic(r, plan);
    write_dynamic(r, out);
    return exit_code::ok;
  }
  RunPlan plan = plan_run(r);
  RunOutcome out;
  run_analysis(r, plan, out);
  return write_outputs(r, out);
}

// An error line after a progress line left open, and the step's exit code. (Standard output is
// flushed as the process ends, as it was written.)
int failed(int code, const std::string& what, const std::string& why) {
  end_progress_line();
  print_error(program, what, why);
  return code;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    Request r;
    if (const auto code = parse_request(argc, argv, r)) return finish(program, *code);
    const int code = plan_run_write(r);
    const int closed = finish(program, exit_code::ok);  // a lost output (4) comes before the verdict
    return closed != exit_code::ok ? closed : code;
  } catch (const ToolError& e) {
    return failed(e.code, e.what, e.why);
  } catch (const std::bad_alloc&) {  // beyond the plan's own check (too_big): say what limits memory
    return failed(exit_code::internal, "out of memory",
                  fmt::format("an allocation failed: this process may use {} MiB ({})", memory_budget() >> 20,
                              memory_budget_reason()));
  } catch (const std::exception& e) {
    return failed(exit_code::internal, "internal error", e.what());
  }
}
