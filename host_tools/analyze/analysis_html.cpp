#include "analysis_html.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "confidence.hpp"
#include "html_report.hpp"

namespace gyrochar {
namespace {

using html::Cell;
using html::number;

constexpr const char* adev_colour = "#1f5fbf";
constexpr const char* mdev_colour = "#c0602a";
constexpr const char* model_colour = "#222222";
constexpr const char* truth_colour = "#7a3fa0";

Cell text(const std::string& s) { return {s, {}, "text"}; }

// The size of the display unit of the fits' and read-off's values (rad/s for gyro deviations).
double deviation_unit_si(const ReportUnits& u) { return u.gyro ? u.rate.rad_per_s : 1.0; }

html::LogPlot curve_plot(const Report& r, const std::vector<AnalysisRow>& curves, DevStat stat,
                         const std::vector<Limit>& limits) {
  const bool adev = stat == DevStat::oadev;
  html::LogPlot plot;
  plot.title = std::string(title(stat)) + " deviation";
  plot.x_label = "tau [s]";
  plot.y_label = fmt::format("{} [{}]", adev ? "ADEV" : "MDEV", r.units.unit(stat));
  html::PlotSeries s{adev ? "OADEV" : "MDEV", adev ? adev_colour : mdev_colour, !adev, {}};
  std::uint64_t m_max = 0;
  const double k = r.units.factor();
  for (const AnalysisRow& row : curves) {
    if (row.stat != stat) continue;
    html::PlotPoint p{row.tau_s, row.dev * k, row.ci};
    p.ci.low *= k, p.ci.high *= k;
    s.points.push_back(p);
    m_max = std::max(m_max, row.m);
  }
  if (s.points.empty()) return plot;
  plot.series.push_back(std::move(s));
  // The model of the recommended fit (when accepted) and the simulated truth, on a grid of m.
  std::vector<double> x, y, ty;
  const double unit = deviation_unit_si(r.units);
  for (double m = 1; m <= static_cast<double>(m_max) * 1.0001; m *= 1.1) {
    const auto mi = static_cast<std::uint64_t>(std::llround(m));
    x.push_back(static_cast<double>(mi) * r.tau0_s);
    if (!r.fits.empty() && r.fits.front().fit.ok())
      y.push_back(std::sqrt(fitted_variance(r.fits.front().fit, adev ? Stat::avar : Stat::mvar, mi, r.tau0_s)) / unit);
    if (r.truth && adev) {
      const Ieee952Truth& t = *r.truth;
      ty.push_back(std::sqrt(ieee952_avar({t.q_rad, t.n_rad_sqrt_s, t.b_rad_s, t.k_rad_s_sqrt_s, t.r_rad_s2}, x.back())) /
                   unit);
    }
  }
  if (!y.empty()) plot.lines.push_back({"fitted model", model_colour, false, x, y});
  if (!ty.empty()) plot.lines.push_back({"simulated truth (5 terms)", truth_colour, true, x, ty});
  for (const Limit& l : limits)
    if ((l.kind == Limit::Kind::adev) == adev && l.kind != Limit::Kind::term && r.units.gyro)
      plot.limits.push_back({l.tau_s, l.value_si / r.units.rate.rad_per_s, l.quantity() + " limit"});
  return plot;
}

void statistic_tables(html::Document& doc, const Report& r) {
  doc.heading("Statistics", 2, "statistics");
  doc.paragraph(fmt::format("Confidence intervals at {:g} % (two-sided) from each estimator's EDF.", 100 * r.confidence),
                "note");
  std::vector<DevStat> stats;
  for (const AnalysisRow& row : r.analysis.rows)
    if (std::find(stats.begin(), stats.end(), row.stat) == stats.end()) stats.push_back(row.stat);
  const double k = r.units.factor();
  for (const DevStat st : stats) {
    std::vector<std::vector<Cell>> rows;
    for (const AnalysisRow& row : r.analysis.rows) {
      if (row.stat != st) continue;
      rows.push_back({number(row.tau_s),
                      {fmt::format("{}", row.m), fmt::format("{}", row.m), {}},
                      {fmt::format("{}", row.n), fmt::format("{}", row.n), {}},
                      number(row.dev * k),
                      row.ci.valid ? number(row.ci.low * k) : Cell{},
                      row.ci.valid ? number(row.ci.high * k) : Cell{},
                      row.edf > 0 ? number(row.edf) : Cell{},
                      row.alpha ? Cell{fmt::format("{}", *row.alpha), fmt::format("{}", *row.alpha), {}} : Cell{},
                      {fmt::format("{}", row.stride), fmt::format("{}", row.stride), {}}});
    }
    doc.table(fmt::format("stat-{}", name(st)), fmt::format("{} [{}]", name(st), r.units.unit(st)),
              {"tau [s]", "m", "n", "dev", "ci low", "ci high", "edf", "alpha", "stride"}, rows);
  }
}

void fit_tables(html::Document& doc, const Report& r) {
  if (r.fits.empty()) return;
  doc.heading("IEEE-952 fit", 2, "fit");
  for (std::size_t f = 0; f < r.fits.size(); ++f) {
    const Ieee952Fit& fit = r.fits[f].fit;
    std::vector<std::vector<Cell>> rows;
    for (std::size_t i = 0; i < 5; ++i) {
      const units::Ieee952Unit& u = fit_unit(r.units, i);
      const Ieee952Parameter& p = fit.p[i];
      Cell truth;
      if (r.truth && f == 0) {
        const Ieee952Truth& t = *r.truth;
        const double tv[5] = {t.q_rad, t.n_rad_sqrt_s, t.b_rad_s, t.k_rad_s_sqrt_s, t.r_rad_s2};
        truth = number(tv[i] / u.si);
      }
      rows.push_back({text(u.letter), p.fitted ? number(p.value / u.si) : Cell{},
                      p.fitted ? number(p.uncertainty / u.si) : Cell{}, text(u.name),
                      text(!p.fitted && p.held_for_markov ? "not in model (a Markov term in its place)"
                           : !p.fitted                    ? "not in model"
                           : p.resolved                   ? "resolved"
                           : p.markov_in_place_tc_s > 0   ? "not resolved (a Markov term in its place does as well)"
                           : p.doubted                    ? "not resolved (the runner-up model does without it)"
                                                          : "not resolved")});
      if (r.truth && f == 0) rows.back().push_back(truth);
    }
    for (std::size_t i = 0; i < fit.n_markov; ++i) {
      const MarkovTerm& mt = fit.markov[i];
      const double unit = deviation_unit_si(r.units);
      rows.push_back({text(fmt::format("Markov {} sigma", i + 1)), number(mt.sigma.value / unit),
                      number(mt.sigma.uncertainty / unit), text(r.units.unit(DevStat::oadev)),
                      text(mt.sigma.resolved ? "resolved" : "not resolved")});
      rows.push_back({text(fmt::format("Markov {} Tc", i + 1)), number(mt.tc_s), number(mt.tc_uncertainty_s), text("s"),
                      text(correlation_time_interval(mt.tc_s, mt.tc_uncertainty_s))});
    }
    for (std::size_t i = 0; i < fit.n_sinusoids; ++i) {
      const SinusoidTerm& st = fit.sinusoids[i];
      const double unit = deviation_unit_si(r.units);
      rows.push_back({text(fmt::format("sinusoid {:g} Hz", st.frequency_hz)), number(st.amplitude.value / unit),
                      number(st.amplitude.uncertainty / unit), text(r.units.unit(DevStat::oadev)),
                      text(st.amplitude.resolved ? "resolved" : "not resolved")});
    }
    const char* curve = curve_title(r.fits[f].curve);
    std::string other_model;  // a model the record cannot tell from this one (ieee952.hpp)
    for (const std::string& note : model_difference_notes(fit, r.units)) other_model += "; " + note;
    doc.table(f == 0 ? "fit" : fmt::format("fit-{}", name(r.fits[f].curve)),
              fmt::format("Fit of {}: {}, chi2/dof {:.3g}, {} points, uncertainty scale {:.3g}{}", curve, name(fit.status),
                          fit.chi2_per_dof(), fit.points, fit.birge, other_model),
              r.truth && f == 0
                  ? std::vector<std::string>{"term", "value", "standard uncertainty", "unit", "status", "simulated truth"}
                  : std::vector<std::string>{"term", "value", "standard uncertainty", "unit", "status"},
              rows);
  }
}

void readoff_table(html::Document& doc, const Report& r) {
  if (!r.readoff || !r.units.gyro) return;
  const Readoff& ro = *r.readoff;
  const Ieee952Fit* fit = !r.fits.empty() && r.fits.front().fit.ok() ? &r.fits.front().fit : nullptr;
  struct Entry {
    const char* name;
    const ReadoffValue& v;
    double si;
    std::string unit;
    int term;  // -1: the floor (no term)
  };
  const Entry entries[] = {{"N", ro.n, units::ieee952[1].si, units::ieee952[1].name, 1},
                           {"floor", ro.floor, r.units.rate.rad_per_s, r.units.rate.name, -1},
                           {"B", ro.b, units::ieee952[2].si, units::ieee952[2].name, 2},
                           {"K", ro.k, units::ieee952[3].si, units::ieee952[3].name, 3}};
  std::vector<std::vector<Cell>> rows;
  for (const Entry& e : entries) {
    if (!e.v.valid) {
      rows.push_back({text(e.name), Cell{}, Cell{}, Cell{}, Cell{}, text(e.unit), text("not read")});
      continue;
    }
    std::string agrees;
    if (e.term >= 0)
      if (const auto a = readoff_agrees(e.v, fit, static_cast<std::size_t>(e.term))) agrees = *a ? "yes" : "no";
    rows.push_back({text(e.name), number(e.v.value / e.si), number(e.v.ci_low / e.si), number(e.v.ci_high / e.si),
                    number(e.v.tau_s), text(e.unit), text(agrees)});
  }
  doc.heading("Read-off values", 2, "readoff-heading");
  doc.paragraph(
      "Read off the Allan deviation as data sheets do: N on the -1/2 line at 1 s, the floor and B = floor / "
      "0.664, K on the +1/2 line at 3 s; each with the interval of the point it was read at.",
      "note");
  doc.table("readoff", "", {"value", "read off", "ci low", "ci high", "at tau [s]", "unit", "agrees with fit"}, rows);
}

}  // namespace

std::string analysis_html(const Report& r, const std::vector<AnalysisRow>& curves, const ReportProvenance& provenance,
                          const std::vector<Limit>& limits, const std::vector<Decision>& decisions) {
  html::Document doc("gyrochar report: " + r.source);
  doc.heading("Provenance", 2, "provenance");
  const Analysis& a = r.analysis;
  const double run_s = static_cast<double>(a.n_values) * r.tau0_s;
  std::vector<std::pair<std::string, std::string>> facts{
      {"input", r.source},
      {"data", fmt::format("{} ({})", name(r.type), r.units.input)},
      {"tau0", fmt::format("{:g} s", r.tau0_s)},
      {"samples", fmt::format("{}", a.n_values)},
      {"run length", fmt::format("{:g} s ({})", run_s, format_run_length(run_s))},
      {"gaps", "none: a file is one unbroken record"},
      {"stride factor", fmt::format("{}", a.stride_factor)},
      {"confidence of the tables", fmt::format("{:g} %", 100 * r.confidence)},
      {"values read", a.n_values ? fmt::format("{:g} .. {:g}, mean {:g}", r.range.min, r.range.max, r.range.mean()) : ""},
      {"command", provenance.command},
      {"software", html::software_version()},
      {"written", html::utc_now()}};
  if (!provenance.limits_path.empty()) facts.emplace_back("limits file", provenance.limits_path);
  doc.facts(facts, "provenance-facts");
  if (!limits.empty()) html::verdict_section(doc, limits, decisions);
  doc.heading("Plots", 2, "plots");
  doc.raw("<div class=\"plots\">\n");
  for (const DevStat st : {DevStat::oadev, DevStat::mdev})
    if (std::any_of(curves.begin(), curves.end(), [&](const AnalysisRow& row) { return row.stat == st; }))
      doc.raw(html::svg_log_plot(curve_plot(r, curves, st, limits)) + "\n");
  doc.raw("</div>\n");
  fit_tables(doc, r);
  readoff_table(doc, r);
  statistic_tables(doc, r);
  return doc.finish();
}

}  // namespace gyrochar
