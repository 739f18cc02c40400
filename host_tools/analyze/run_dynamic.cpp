// The dynamic Allan deviation run of gyrochar-analyze (--dynamic, run.hpp): one pass over the
// file, the surface on stdout, the heat maps to --plot.
#include <fmt/format.h>

#include <algorithm>
#include <cstdio>
#include <span>
#include <stdexcept>

#include "heat_map.hpp"
#include "read_pass.hpp"
#include "run.hpp"
#include "hal/program/exit_codes.hpp"

namespace gyrochar {

DynamicPlan plan_dynamic(Request& r) {
  AnalysisOptions& o = r.options;
  const DynamicSpec& d = *r.dynamic;
  // The windows' taus: --taus over the phase points of one window, those with 4 m <= its values.
  const std::uint64_t window_phase = o.type == DataType::phase ? d.window : d.window + 1;
  const std::size_t asked = r.taus == TauRule::list ? r.listed.size() : 0;
  plan_window_taus(o, r.taus, r.stride, r.listed, d.window, window_phase);
  if (o.m_list.empty()) bad("--taus", fmt::format("no tau with 4 m <= the window's {} values", d.window));
  if (r.taus == TauRule::list && o.m_list.size() != asked)
    bad("--taus", fmt::format("averaging factors above {} do not fit a quarter of the window", d.window / 4));
  DynamicPlan p;
  try {
    p.analyzer = std::make_unique<DynamicAnalyzer>(o, d.window, d.step);
  } catch (const std::invalid_argument& e) {
    bad("--dynamic", e.what());
  }
  return p;
}

DynamicOutcome run_dynamic(const Request& r, DynamicPlan& p) {
  DynamicOutcome out;
  InputShape shape(r.options.type, r.nominal_hz);
  try {
    DataFile file(r.path, r.column);
    Progress progress(r.show_progress, file);
    std::vector<double> block(1 << 14);
    while (const std::size_t n = file.read(block)) {
      const std::span<double> values(block.data(), n);
      try {
        shape.add(values);
        p.analyzer->add(values);
      } catch (const BadValue& e) {
        bad(r.source, fmt::format("line {}: {}", file.line_of(e.index()), e.what()));
      } catch (const std::range_error& e) {
        bad(r.source, fmt::format("by line {}: {}", file.line_of(n - 1), e.what()));
      }
      for (WindowAnalysis& w : p.analyzer->take_completed()) out.windows.push_back(std::move(w));
      progress.values(n, file.bytes_read());
    }
  } catch (const DataFileError& e) {
    bad_data(r.source, e);
  }
  shape.check_conversion();
  out.values = p.analyzer->values();
  if (out.windows.empty())
    bad(r.source, fmt::format("{} values are fewer than one window of {} values", out.values, r.dynamic->window));
  check_zeros(std::all_of(out.windows.begin(), out.windows.end(),
                          [](const WindowAnalysis& w) { return all_zero(w.analysis.rows); }),
              shape, r.source);
  return out;
}

void write_dynamic(const Request& r, const DynamicOutcome& out) {
  const AnalysisOptions& o = r.options;
  const DynamicReport report{out.windows,       o.type,          o.tau0_s,   o.confidence, r.units,
                             r.dynamic->window, r.dynamic->step, out.values, o.stats};
  const std::string text = r.format == OutputFormat::json  ? dynamic_to_json(report).dump(2) + "\n"
                           : r.format == OutputFormat::csv ? format_dynamic_csv(report)
                                                           : format_dynamic_table(report);
  std::fwrite(text.data(), 1, text.size(), stdout);
  if (!r.plot_prefix.empty()) {
    std::string why;
    if (!write_heat_maps(r.plot_prefix, dynamic_heat_maps(report), why)) fail(exit_code::output_failed, "--plot", why);
  }
}

}  // namespace gyrochar
