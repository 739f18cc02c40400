// The whole-record run of gyrochar-analyze (run.hpp): plan, run, write.
#include "run.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cerrno>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <future>
#include <iterator>
#include <new>
#include <span>
#include <stdexcept>

#include "acceptance.hpp"
#include "analysis_html.hpp"
#include "html_report.hpp"
#include "psd.hpp"
#include "read_ahead.hpp"
#include "read_pass.hpp"
#include "static_plot.hpp"
#include "threads.hpp"
#include "verdict_output.hpp"
#include "hal/program/exit_codes.hpp"

namespace gyrochar {

namespace {

constexpr const char* program = analyze_program;

// The input opened; under --taus all its values read into memory, to know N.
void open_input(const Request& r, RunPlan& p) {
  const auto phase_points = [&](std::uint64_t values) { return r.options.type == DataType::phase ? values : values + 1; };
  try {
    p.file = std::make_unique<DataFile>(r.path, r.column);
    if (r.taus == TauRule::all) {
      std::vector<double> block(1 << 14);
      while (const std::size_t n = p.file->read(block)) {
        p.kept.insert(p.kept.end(), block.begin(), block.begin() + static_cast<std::ptrdiff_t>(n));
        for (std::size_t i = 0; i < n; ++i) p.kept_lines.push_back(p.file->line_of(i));
      }
      if (p.kept.empty()) bad(r.source, "no data (empty, or only comments and blank lines)");
      p.n_phase = phase_points(p.kept.size());
    } else if (p.file->values_bound() > 0) {
      p.n_phase = phase_points(p.file->values_bound());
    }
  } catch (const DataFileError& e) {
    bad_data(r.source, e);
  }
}

// More memory than the process may use, or an allocation that failed: a stride factor given is
// the user's choice (bad input); under the default the cause is the memory limit (exit 1).
[[noreturn]] void too_big(const Request& r, const RunPlan& p) {
  const AnalysisOptions& o = r.options;
  const std::uint64_t bytes = o.hold_counts  ? 12 * o.values_hint
                              : o.hold_phase ? 24 * o.values_hint
                                             : history_bytes(o.type, o.stride_factor, o.m_list.back());
  if (!r.stride.is_full())
    bad("--stride-factor", fmt::format("{} with taus up to {} needs {} MiB of history, more than the {} MiB this "
                                       "process may use: give a smaller stride factor or fewer taus",
                                       o.stride_factor, o.m_list.back(), bytes >> 20, p.budget >> 20));
  fail(exit_code::internal, r.source,
       fmt::format("{} values{} need {} MiB of memory with every tau up to N/4 fully overlapped (--stride-factor "
                   "full, the default), more than the {} MiB this process may use ({}): raise the limit, or give "
                   "--stride-factor 8 (a few MiB whatever the length)",
                   o.values_hint, r.taus == TauRule::all ? "" : " (at most, from the file's size)",
                   std::max<std::uint64_t>(bytes >> 20, 1), p.budget >> 20, memory_budget_reason()));
}

}  // namespace

RunPlan plan_run(Request& r) {
  RunPlan p;
  open_input(r, p);
  AnalysisOptions& o = r.options;
  // The taus, the stride factor "full" resolves to and the held record (plan.hpp).
  o.values_hint = r.taus == TauRule::all ? p.kept.size() : p.file->values_bound();
  if (r.show_progress) o.on_progress = stage_progress();
  p.budget = memory_budget();
  p.taus = plan_taus(o, r.taus, r.stride, r.listed, p.n_phase, p.budget);
  if (o.m_list.empty()) bad(r.source, fmt::format("{} phase points are too few for any tau", p.n_phase));
  for (const Limit& l : r.limits) {  // a limited tau joins the taus when the pyramid can form it
    const std::uint64_t m = limit_m(l, o.tau0_s);
    if (m == 0 || std::binary_search(o.m_list.begin(), o.m_list.end(), m)) continue;
    if ((p.n_phase == 0 || m <= p.n_phase / 2) && (p.taus.held || tau_representable(m, o.stride_factor)))
      o.m_list.insert(std::upper_bound(o.m_list.begin(), o.m_list.end(), m), m);
  }
  if (!p.taus.held && history_bytes(o.type, o.stride_factor, o.m_list.back()) > p.budget) too_big(r, p);
  try {
    p.analyzer = std::make_unique<Analyzer>(o);
  } catch (const std::invalid_argument& e) {
    bad("--taus", e.what());
  } catch (const std::bad_alloc&) {
    too_big(r, p);
  }
  return p;
}

namespace {

// The one pass over the values: each block through the shape check, the range, the PSD's rate
// record and the analyzer.
void read_values(const Request& r, RunPlan& p, DataRange& range, std::optional<RateRecord>& rates, InputShape& shape) {
  const auto add = [&](std::span<double> values, auto line_of) {
    try {
      shape.add(values);
      range.add(values);
      if (rates) rates->add(values);
      p.analyzer->add(values);
    } catch (const BadValue& e) {
      bad(r.source, fmt::format("line {}: {}", line_of(e.index()), e.what()));
    } catch (const std::range_error& e) {
      bad(r.source, fmt::format("by line {}: {}", line_of(values.size() - 1), e.what()));
    }
  };
  try {
    Progress progress(r.show_progress, *p.file);
    if (r.taus == TauRule::all) {
      for (std::size_t i = 0; i < p.kept.size(); i += 1 << 14) {
        const std::size_t n = std::min<std::size_t>(p.kept.size() - i, 1 << 14);
        add({p.kept.data() + i, n}, [&](std::size_t k) { return p.kept_lines[i + k]; });
      }
    } else if (p.file->size_bytes() > 0) {  // a file: parsed on a thread of its own, ahead of the checks and the analyzer
      ReadAhead ahead(*p.file, 1 << 14);
      for (std::span<double> values; !(values = ahead.next()).empty();) {
        add(values, [&](std::size_t k) { return ahead.line_of(k); });
        progress.values(values.size(), ahead.bytes_read());
      }
    } else {  // standard input or a pipe: in turn (a thread blocked on it could not be stopped)
      std::vector<double> block(1 << 14);
      while (const std::size_t n = p.file->read(block)) {
        add({block.data(), n}, [&](std::size_t k) { return p.file->line_of(k); });
        progress.values(n, p.file->bytes_read());
      }
    }
  } catch (const DataFileError& e) {
    bad_data(r.source, e);
  }
}

// No PSD (the rate is shorter than the Welch segment, or too short for any): refused when one was
// asked for, else a note.
void no_spectrum(const Request& r, std::size_t rate_values, std::size_t segment) {
  if (!r.psd_path.empty() || r.psd_segment != 0)
    bad(r.psd_segment ? "--psd-segment" : "--psd",
        fmt::format("{} rate values are too few for a segment of {}", rate_values, segment ? segment : 16));
  print_error(program, "note", fmt::format("no PSD: {} rate values are too few for a spectrum", rate_values));
}

// The rate's PSD with its sinusoid search, in the run's units.
Spectrum spectrum_of_run(const Request& r, RateView rate, std::size_t segment) {
  Spectrum sp = spectrum_of(rate, r.options.type == DataType::counts, r.options.tau0_s, segment, r.options.confidence,
                            r.sinusoid_search);
  sp.given_hz = r.sinusoid_hz;
  sp.factor = r.units.factor();
  sp.unit = r.units.unit(DevStat::oadev);
  return sp;
}

// The Allan curve's nulls at tau = 1/f of the peaks found, on the analysis' dense taus.
void check_nulls(Spectrum& sp, const Analysis& a) {
  if (!sp.searched) return;
  std::vector<std::pair<double, double>> oadev;
  for (const AnalysisRow& row : a.rows)
    if (row.stat == DevStat::oadev) oadev.emplace_back(row.tau_s, row.dev);
  check_adev_nulls(sp.search, oadev);
}

// A tau asked for by number but too long for the data has no row: say so. (The octave, decade
// and all lists stop where the data end by design.)
void note_missing_taus(const Request& r, const Analysis& shown) {
  if (r.taus != TauRule::list) return;
  for (const std::uint64_t m : r.options.m_list) {
    std::string missing;
    for (const DevStat stat : r.shown)
      if (std::none_of(shown.rows.begin(), shown.rows.end(),
                       [&](const AnalysisRow& row) { return row.stat == stat && row.m == m; }))
        missing += (missing.empty() ? "" : ", ") + std::string(name(stat));
    if (!missing.empty())
      print_error(program, "note",
                  fmt::format("m = {} (tau = {:g} s) left out of {}: {} phase points are too few for a term", m,
                              static_cast<double>(m) * r.options.tau0_s, missing, shown.n_phase));
  }
}

// The output unit must not take a value out of a double's range.
void check_output_range(const Request& r, const Analysis& shown) {
  const ReportUnits& units = r.units;
  for (const AnalysisRow& row : shown.rows) {
    if (!std::isfinite(row.dev * units.factor()) || (row.ci.valid && !std::isfinite(row.ci.high * units.factor())))
      bad(r.source,
          fmt::format("{} at tau = {:g} s (m = {}): {:g} times the unit factor {:g} ({}) overflows a double", name(row.stat),
                      row.tau_s, row.m, row.ci.valid ? row.ci.high : row.dev, units.factor(), units.unit(row.stat)));
    if (row.dev != 0 && !(row.dev * units.factor() >= DBL_MIN))
      bad(r.source, fmt::format("{} at tau = {:g} s (m = {}): {:g} times the unit factor {:g} ({}) underflows a double "
                                "(smallest normal 2.2e-308)",
                                name(row.stat), row.tau_s, row.m, row.dev, units.factor(), units.unit(row.stat)));
  }
}

// The analysis once the values are read: refused when empty, when a decade tau the stride factor
// cannot form is reached, or when no tau has a row; notes on stderr.
Analysis checked_result(const Request& r, const RunPlan& p, const InputShape& shape) {
  Analysis a = [&] {
    try {
      return p.analyzer->result();
    } catch (const std::range_error& e) {  // a deviation that is not a finite number, and why
      bad(r.source, e.what());
    }
  }();
  const std::uint32_t s = r.options.stride_factor;
  if (a.n_values == 0) bad(r.source, "no data (empty, or only comments and blank lines)");
  for (const std::uint64_t m : p.taus.not_formed)
    if (m <= a.n_phase / 2)
      bad("--taus", fmt::format("averaging factor {} cannot be formed with stride factor {}: above S it must be a "
                                "multiple of its stride (m/S rounded up to a power of two)",
                                m, s));
  if (a.rows.empty()) bad(r.source, fmt::format("{} values are too few for any of the taus asked", a.n_values));
  check_zeros(all_zero(a.rows), shape, r.source);
  if (!p.file->layout_note().empty()) print_error(program, r.source, "values from " + p.file->layout_note());
  if (p.taus.cut_above > 0 && p.taus.cut_above <= a.n_phase / 2)
    print_error(program, r.source,
                fmt::format("taus stop below m = {}: with stride factor {} more would need more than "
                            "{} MiB of history",
                            p.taus.cut_above, s, p.budget >> 20));
  return a;
}

// --kalibr's file, made before anything is written: a refusal loses no output.
std::string kalibr_text(const Request& r, const Report& report) {
  std::string why;
  const auto text = kalibr_yaml(report, why);
  if (!text) bad("--kalibr", why);
  if (!why.empty()) print_error(program, "note", r.kalibr_path + ": " + why);
  if (const std::string beyond = kalibr_left_out(report.fits.front().fit); !beyond.empty())
    print_error(program, "note",
                "--kalibr: gyroscope_noise_density is the fitted white-rate N, gyroscope_random_walk the "
                "fitted rate random walk K; Kalibr's model has no place for the model's " +
                    beyond);
  return *text;
}

}  // namespace

void run_analysis(const Request& r, RunPlan& p, RunOutcome& out) {
  const AnalysisOptions& o = r.options;
  DataRange range;
  // The rate for the PSD: the counts the analyzer holds where it holds them (no copy), else a
  // record of its own.
  std::optional<RateRecord> rates;
  if (r.want_psd && !p.analyzer->held_counts().held)
    rates.emplace(o.type == DataType::phase, o.type == DataType::counts, o.tau0_s);
  InputShape shape(o.type, r.nominal_hz);
  read_values(r, p, range, rates, shape);
  shape.check_conversion();
  // The PSD reads the record the analysis reads, and neither writes it: on a thread of its own
  // while the analysis runs, unless one thread was asked for (the 120 h record: its transforms are
  // about 25 s of one core, which the analysis leaves idle in its single-threaded parts).
  std::future<Spectrum> spectrum_job;
  std::size_t rate_values = 0;
  std::size_t segment = 0;  // the Welch segment of the PSD (--psd, the static plot, the sinusoid search)
  if (r.want_psd) {
    const RateView rate = rates ? rates->rate() : RateView(p.analyzer->held_counts(), o.tau0_s);
    rate_values = rate.size();
    segment = r.psd_segment ? r.psd_segment : default_psd_segment(rate_values);
    if (segment != 0 && segment <= rate_values)
      spectrum_job = std::async(thread_count(o.threads) > 1 ? std::launch::async : std::launch::deferred,
                                [&r, rate, segment] { return spectrum_of_run(r, rate, segment); });
  }
  Analysis a = checked_result(r, p, shape);
  const std::vector<std::string>& header = p.file->header();

  std::optional<Spectrum> spectrum;
  if (spectrum_job.valid()) {
    spectrum = spectrum_job.get();
    check_nulls(*spectrum, a);
  } else if (r.want_psd) {
    no_spectrum(r, rate_values, segment);
  }
  rates.reset();
  std::array<double, max_sinusoids> offered_hz{};
  for (std::size_t k = 0; k < r.sinusoid_hz.size(); ++k) offered_hz[k] = r.sinusoid_hz[k];
  if (spectrum) offered_hz = spectrum->fit_hz();
  std::vector<CurveFit> fits;
  if (r.fit)
    fits = fit_curves(a, r.units, o.tau0_s, o.type == DataType::counts ? r.units.phase_unit_si / std::sqrt(12.0) : 0.0,
                      r.long_tau, p.analyzer->record(), offered_hz);
  std::optional<Readoff> readoff = readoff_of(a, r.units);  // every OADEV row, shown or computed for the fit
  // --plot and --report draw OADEV and MDEV, shown or not; limits read them.
  if (!r.plot_prefix.empty() || !r.report_path.empty() || !r.limits.empty())
    std::copy_if(a.rows.begin(), a.rows.end(), std::back_inserter(out.plotted),
                 [](const AnalysisRow& row) { return row.stat == DevStat::oadev || row.stat == DevStat::mdev; });
  out.shown = std::move(a);  // (a --taus all run has millions of rows: not copied)
  std::erase_if(out.shown.rows, [&](const AnalysisRow& row) {
    return std::find(r.shown.begin(), r.shown.end(), row.stat) == r.shown.end();
  });
  note_missing_taus(r, out.shown);
  check_output_range(r, out.shown);
  Report& report = out.report.emplace(Report{out.shown, o.type, o.tau0_s, o.confidence, r.units, std::move(fits),
                                             std::nullopt, r.source, range, std::move(readoff), std::nullopt});
  if (!report.fits.empty()) report.truth = truth_of(header, o.type, o.tau0_s, r.units.phase_unit_si);
  report.spectrum = std::move(spectrum);
  out.run_s = static_cast<double>(report.analysis.n_values) * o.tau0_s;
  out.decisions = decide_limits(r.limits, report, out.plotted, out.run_s);
  if (!r.kalibr_path.empty()) out.yaml = kalibr_text(r, report);
}

namespace {

// The result on stdout in the format asked for (the verdicts after it; stable32's on stderr).
void write_stdout(const Request& r, const RunOutcome& out) {
  const Report& report = *out.report;
  const auto json_text = [&] {
    nlohmann::json j = to_json(report);
    if (!r.limits.empty()) j["acceptance"] = acceptance_json(r.limits, out.decisions);
    return j.dump(2) + "\n";
  };
  const std::string verdicts = r.limits.empty() ? std::string() : acceptance_table(r.limits, out.decisions);
  std::string text;
  switch (r.format) {
    case OutputFormat::json: text = json_text(); break;
    case OutputFormat::csv:
      text = format_csv(report) + (r.limits.empty() ? "" : acceptance_csv(r.limits, out.decisions));
      break;
    case OutputFormat::stable32: text = format_stable32(report); break;
    case OutputFormat::table: text = format_table(report) + verdicts; break;
  }
  if (r.format == OutputFormat::stable32 && !r.limits.empty())
    std::fputs(verdicts.c_str(), stderr);  // its format has no place
  std::fwrite(text.data(), 1, text.size(), stdout);
}

// `text` to file `path`; false when it did not close whole (said on stderr).
bool write_text_file(const std::string& path, const std::string& text) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) fail(exit_code::output_failed, path, std::strerror(errno));
  std::fputs(text.c_str(), f);
  return close_output(f, program, path);
}

// --summary's row for the file: the fit's terms and the verdicts.
GyroSummary summary_row(const Request& r, const RunOutcome& out) {
  const Report& report = *out.report;
  GyroSummary g{r.source, "", out.run_s, report.analysis.n_values, "", 0, {}, out.decisions};
  if (!report.fits.empty()) {
    const Ieee952Fit& fit = report.fits.front().fit;
    g.fit_status = name(fit.status);
    g.chi2_per_dof = fit.chi2_per_dof();
    for (std::size_t k = 0; k < 5; ++k) {
      const Ieee952Parameter& p = fit.p[k];
      g.terms[k] = {p.fitted, p.value / units::ieee952[k].si, p.uncertainty / units::ieee952[k].si,
                    !p.fitted    ? "not in model"
                    : p.resolved ? "resolved"
                                 : "not resolved"};
    }
  }
  return g;
}

}  // namespace

int write_outputs(const Request& r, const RunOutcome& out) {
  const Report& report = *out.report;
  write_stdout(r, out);
  if (!r.psd_path.empty() && !write_text_file(r.psd_path, spectrum_csv(*report.spectrum))) return exit_code::output_failed;
  if (!r.plot_prefix.empty()) {
    std::string why;
    if (!write_static_plot(r.plot_prefix, report, out.plotted, why)) fail(exit_code::output_failed, "--plot", why);
  }
  if (!r.kalibr_path.empty() && !write_text_file(r.kalibr_path, out.yaml)) return exit_code::output_failed;
  if (!r.report_path.empty()) {
    std::string why;
    const std::string page = analysis_html(report, out.plotted, {r.command, r.limits_path}, r.limits, out.decisions);
    if (!html::write_file_atomically(r.report_path, page, why)) fail(exit_code::output_failed, "--report", why);
  }
  if (!r.summary_path.empty()) {
    std::string why;
    if (!append_summary(r.summary_path, r.limits, {summary_row(r, out)}, why))
      fail(exit_code::output_failed, "--summary", r.summary_path + ": " + why);
  }
  return r.limits.empty() ? exit_code::ok : exit_code_of(overall(out.decisions));
}

}  // namespace gyrochar
