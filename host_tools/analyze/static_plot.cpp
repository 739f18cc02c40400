#include "static_plot.hpp"

#include <fmt/format.h>
#include <plplot/plstream.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <functional>

#include "deviation_plot.hpp"
#include "figure.hpp"

namespace gyrochar {
namespace {

constexpr std::size_t line_points = 600;

// The model lines of one curve: a term, or the sum.
struct ModelLine {
  std::string label;
  int colour = sum_colour;
  int style = 2;
  std::vector<double> tau_s, dev;
};

// One deviation panel's content, in the output unit.
struct CurvePanel {
  std::string title, unit;
  Stat stat = Stat::avar;
  std::vector<DevPoint> points;
  std::vector<ModelLine> lines;
  std::vector<std::string> notes;
  double tau_lo = 0, tau_hi = 0;
};

const Ieee952Fit* recommended(const Report& r) {
  for (const CurveFit& f : r.fits)
    if (f.curve == FitCurve::both) return &f.fit;
  return nullptr;
}

// The fit with every term but those `keep` says zeroed: one term's own expectation.
Ieee952Fit only(const Ieee952Fit& fit, const std::function<bool(int kind, std::size_t index)>& keep) {
  Ieee952Fit one = fit;
  for (std::size_t k = 0; k < 5; ++k)
    if (!keep(0, k)) one.p[k].value = 0;
  for (std::size_t j = 0; j < one.n_markov; ++j)
    if (!keep(1, j)) one.markov[j].sigma.value = 0;
  for (std::size_t j = 0; j < one.n_sinusoids; ++j)
    if (!keep(2, j)) one.sinusoids[j].amplitude.value = 0;
  return one;
}

CurvePanel curve_panel(const Report& r, const std::vector<AnalysisRow>& rows, DevStat stat) {
  CurvePanel p;
  const ReportUnits& u = r.units;
  p.stat = stat == DevStat::oadev ? Stat::avar : Stat::mvar;
  p.unit = u.unit(stat);
  p.title = fmt::format("{}: {}", stat == DevStat::oadev ? "overlapping Allan deviation" : "modified Allan deviation",
                        std::filesystem::path(r.source).filename().string());
  double last_log = -INFINITY;
  for (const AnalysisRow& row : rows) {
    if (row.stat != stat || !(row.dev > 0)) continue;
    const double lt = std::log10(row.tau_s);
    if (lt < last_log + 0.01) continue;  // at most 100 points a decade
    last_log = lt;
    const double k = u.factor();
    p.points.push_back(
        {row.tau_s, row.dev * k, row.ci.valid ? Interval{row.ci.low * k, row.ci.high * k, true} : Interval{}});
  }
  if (p.points.empty()) return p;
  p.tau_lo = p.points.front().tau_s / 2;
  p.tau_hi = p.points.back().tau_s * 2;
  const Ieee952Fit* fit = recommended(r);
  if (fit == nullptr) return p;
  if (!fit->ok()) {
    p.notes.push_back(fit->status == FitStatus::rejected
                          ? fmt::format("IEEE-952 fit REJECTED (chi2/dof {:.3g}):", fit->chi2_per_dof())
                          : fmt::format("no IEEE-952 fit: {}", name(fit->status)));
    if (fit->status == FitStatus::rejected) p.notes.push_back("the model does not describe the curve");
    return p;
  }
  // The lines over the taus the curve has: m on a log grid from 1 to the last point's.
  const double tau0 = r.tau0_s, si_to_out = u.factor() / u.phase_unit_si;
  const double m_hi = p.points.back().tau_s / tau0;
  std::vector<std::uint64_t> ms;
  for (std::size_t i = 0; i < line_points; ++i) {
    const auto m = static_cast<std::uint64_t>(std::llround(std::pow(m_hi, static_cast<double>(i) / (line_points - 1))));
    if (ms.empty() || m > ms.back()) ms.push_back(m);
  }
  const auto line = [&](const Ieee952Fit& model, std::string label, int colour, int style) {
    ModelLine l{std::move(label), colour, style, {}, {}};
    for (const std::uint64_t m : ms) {
      l.tau_s.push_back(static_cast<double>(m) * tau0);
      l.dev.push_back(std::sqrt(std::max(fitted_variance(model, p.stat, m, tau0), 0.0)) * si_to_out);
    }
    p.lines.push_back(std::move(l));
  };
  bool not_resolved = false;
  for (std::size_t k = 0; k < 5; ++k) {
    const Ieee952Parameter& q = fit->p[k];
    if (!(q.value > 0)) continue;
    const units::Ieee952Unit& fu = fit_unit(u, k);
    const double percent = 100 * q.uncertainty / q.value;
    std::string label = q.fitted ? fmt::format("{} {:.3g} {} ±{}{}", fu.letter, q.value / fu.si, fu.name,
                                               percent < 100 ? fmt::format("{:.2g}%", percent) : std::string(">100%"),
                                               q.resolved ? "" : " (nr)")
                                 : fmt::format("{} {:.3g} {} (held)", fu.letter, q.value / fu.si, fu.name);
    if (q.fitted && !q.resolved) not_resolved = true;
    if (k == 1 && fit->bandwidth_tc_s > 0) label += fmt::format(", filtered (Tf {:.3g} s)", fit->bandwidth_tc_s);
    line(only(*fit, [k](int kind, std::size_t i) { return kind == 0 && i == k; }), label, term_colour(k), 2);
  }
  const units::Ieee952Unit& rate = fit_unit(u, 2);
  for (std::size_t j = 0; j < fit->n_markov; ++j) {
    if (!fit->markov[j].sigma.resolved) not_resolved = true;
    line(only(*fit, [j](int kind, std::size_t i) { return kind == 1 && i == j; }),
         fmt::format("Markov {}: sigma {:.3g} {}, Tc {:.3g} s{}", j + 1, fit->markov[j].sigma.value / rate.si, rate.name,
                     fit->markov[j].tc_s, fit->markov[j].sigma.resolved ? "" : " (nr)"),
         markov_colour, 2);
  }
  for (std::size_t j = 0; j < fit->n_sinusoids; ++j)
    line(only(*fit, [j](int kind, std::size_t i) { return kind == 2 && i == j; }),
         fmt::format("sinusoid {:.3g} {} at {:.4g} Hz", fit->sinusoids[j].amplitude.value / rate.si, rate.name,
                     fit->sinusoids[j].frequency_hz),
         sinusoid_colour, 2);
  line(*fit, fmt::format("IEEE-952 model, chi2/dof {:.2g}", fit->chi2_per_dof()), sum_colour, 1);
  if (not_resolved) p.notes.push_back("(nr): not resolved");
  if (fit->bandwidth_excluded_below_tau_s > 0)
    p.notes.push_back(fmt::format("fit leaves out tau < {:.3g} s (filter)", fit->bandwidth_excluded_below_tau_s));
  return p;
}

void draw_curve_panel(plstream& pls, const CurvePanel& p, const Report& r) {
  pls.adv(0);
  pls.schr(0, plot_text_scale);
  pls.col0(ink_colour);
  if (p.points.empty()) return draw_empty_panel(pls, p.title, "no deviation to draw");
  double lo = INFINITY, hi = 0;
  for (const DevPoint& q : p.points) {
    lo = std::min({lo, q.dev, q.ci.valid && q.ci.low > 0 ? q.ci.low : q.dev});
    hi = std::max({hi, q.dev, q.ci.valid ? q.ci.high : q.dev});
  }
  const double y_lo = std::floor(std::log10(lo) - 0.05), y_hi = std::ceil(std::log10(hi) + 0.05);
  const double x_lo = std::log10(p.tau_lo), x_hi = std::log10(p.tau_hi);
  const bool allan = p.stat == Stat::avar;
  draw_log_frame(pls, x_lo, x_hi, y_lo, y_hi, "averaging time #gt [s]",
                 fmt::format("{} [{}], error bars: {:.1f}% confidence", allan ? "ADEV" : "MDEV", p.unit, 100 * r.confidence),
                 p.title);
  PlotLegend legend;
  legend.symbol(allan ? "ADEV (overlapping)" : "MDEV", allan ? adev_colour : mdev_colour, allan ? adev_glyph : mdev_glyph);
  for (const ModelLine& l : p.lines) {
    draw_log_line(pls, l.tau_s, l.dev, l.colour, l.style, l.colour == sum_colour ? 2.0 : 1.5);
    legend.line(l.label, l.colour, l.style);
  }
  draw_points(pls, p.points, allan ? adev_colour : mdev_colour, allan ? adev_glyph : mdev_glyph);
  if (allan && r.readoff && r.units.gyro) {
    // The read-off: the -1/2 line through N at 1 s, the floor, the +1/2 line through K at 3 s.
    const double to_out = 1 / r.units.rate.rad_per_s;
    const Readoff& ro = *r.readoff;
    const auto slope_line = [&](double at_1s, double slope) {
      std::vector<double> x{p.tau_lo, p.tau_hi}, y{at_1s * std::pow(p.tau_lo, slope), at_1s * std::pow(p.tau_hi, slope)};
      draw_log_line(pls, x, y, ink_colour, 3, 0.6);
    };
    const auto mark = [&](double tau, double dev, const std::string& label) {
      if (tau >= p.tau_lo && tau <= p.tau_hi && dev > 0)
        draw_labelled_marker(pls, std::log10(tau), std::log10(dev), read_off_glyph, label, ink_colour, x_lo, x_hi);
    };
    if (ro.n.valid) {
      slope_line(ro.n.value * to_out, -0.5);
      mark(1.0, ro.n.value * to_out,
           fmt::format("read-off N {:.3g} {}", ro.n.value / units::ieee952[1].si, units::ieee952[1].name));
    }
    if (ro.floor.valid)
      mark(ro.floor.tau_s, ro.floor.value * to_out,
           fmt::format("floor: B {:.3g} {}", ro.b.value / units::ieee952[2].si, units::ieee952[2].name));
    if (ro.k.valid) {
      slope_line(ro.k.value * to_out / std::sqrt(3.0), 0.5);
      mark(3.0, ro.k.value * to_out,
           fmt::format("read-off K {:.3g} {}", ro.k.value / units::ieee952[3].si, units::ieee952[3].name));
    }
    if (ro.n.valid || ro.floor.valid || ro.k.valid)
      legend.symbol("read-off (dotted: slopes -1/2, +1/2)", ink_colour, read_off_glyph);
  }
  for (const std::string& note : p.notes) legend.note(note);
  legend.draw(pls);
}

void draw_psd_panel(plstream& pls, const Report& r) {
  pls.adv(0);
  pls.schr(0, plot_text_scale);
  pls.col0(ink_colour);
  const Spectrum& s = *r.spectrum;
  const Psd& p = s.psd;
  const double k2 = s.factor * s.factor;
  const std::string title = fmt::format("PSD of the rate (Welch: {} segments of {} values, EDF {:.3g})", p.segments,
                                        p.segment, p.edf);
  double lo = INFINITY, hi = 0;
  std::vector<PLFLT> x, y, band_x, band_y;
  for (std::size_t i = 0; i < p.psd.size(); ++i) {
    if (!(p.psd[i] > 0)) continue;
    x.push_back(std::log10(p.freq_hz(i)));
    y.push_back(std::log10(p.psd[i] * k2));
    lo = std::min(lo, p.psd[i] * k2);
    hi = std::max(hi, p.psd[i] * k2);
  }
  if (x.empty()) return draw_empty_panel(pls, title, "no positive PSD");
  const bool band = std::isfinite(p.low) && p.low > 0 &&
                    std::all_of(p.psd.begin(), p.psd.end(), [](double v) { return v > 0; });
  if (band) {  // the band's polygon: up along the upper bound, back along the lower
    for (std::size_t i = 0; i < p.psd.size(); ++i)
      band_x.push_back(std::log10(p.freq_hz(i))), band_y.push_back(std::log10(p.ci_high(i) * k2));
    for (std::size_t i = p.psd.size(); i-- > 0;)
      band_x.push_back(std::log10(p.freq_hz(i))), band_y.push_back(std::log10(p.ci_low(i) * k2));
    lo = std::min(lo, *std::min_element(p.psd.begin(), p.psd.end()) * p.low * p.low * k2);
  }
  const double x_lo = std::log10(p.freq_hz(0)) - 0.1, x_hi = std::log10(p.freq_hz(p.psd.size() - 1)) + 0.1;
  const double y_lo = std::floor(std::log10(lo) - 0.05), y_hi = std::ceil(std::log10(hi) + 0.3);
  draw_log_frame(pls, x_lo, x_hi, y_lo, y_hi, "frequency [Hz]",
                 fmt::format("PSD [{}], band: {:.1f}% confidence", s.psd_unit(), 100 * r.confidence), title);
  PlotLegend legend;
  if (band) {
    pls.col0(band_colour);
    pls.fill(static_cast<PLINT>(band_x.size()), band_x.data(), band_y.data());
    legend.line(fmt::format("{:.1f}% band (chi2, EDF {:.3g})", 100 * r.confidence, p.edf), band_colour, 1);
  }
  pls.col0(psd_colour);
  pls.width(1.0);
  pls.line(static_cast<PLINT>(x.size()), x.data(), y.data());
  legend.line("PSD", psd_colour, 1);
  if (s.searched) {
    std::vector<double> f, b;
    for (std::size_t i = 0; i < p.psd.size(); ++i)
      if (std::isfinite(s.search.background[i])) f.push_back(p.freq_hz(i)), b.push_back(s.search.background[i] * k2);
    draw_log_line(pls, f, b, sum_colour, 2, 1.2);
    legend.line("background (running median)", sum_colour, 2);
    for (std::size_t i = 0; i < b.size(); ++i) b[i] *= s.search.threshold;
    draw_log_line(pls, f, b, sum_colour, 3, 0.8);
    legend.line(fmt::format("detection threshold (false alarms {:.2g} %)", 100 * s.search.false_alarm), sum_colour, 3);
    for (const SpectralPeak& q : s.search.peaks)
      draw_labelled_marker(pls, std::log10(q.frequency_hz), std::log10(p.psd[q.bin] * k2) + 0.12, peak_glyph,
                           fmt::format("{:.3g} ± {:.2g} {} at {:.4g} Hz", q.amplitude * s.factor,
                                       q.amplitude_uncertainty * s.factor, s.unit, q.frequency_hz),
                           sinusoid_colour, x_lo, x_hi);
    if (!s.search.peaks.empty()) legend.symbol("sinusoid found", sinusoid_colour, peak_glyph);
    else legend.note("no sinusoid found");
  }
  const Ieee952Fit* fit = recommended(r);
  if (fit != nullptr && fit->ok() && fit->p[1].value > 0) {  // white rate noise: one-sided PSD 2 N^2
    const double n_out = fit->p[1].value * r.units.factor() / r.units.phase_unit_si;
    const double level = 2 * n_out * n_out;
    draw_log_line(pls, {p.freq_hz(0), p.freq_hz(p.psd.size() - 1)}, {level, level}, n_colour, 2, 1.5);
    legend.line("2 N^2: the fit's white rate noise", n_colour, 2);
  }
  legend.draw(pls);
}

void draw_residual_panel(plstream& pls, const Report& r, double tau_lo, double tau_hi) {
  pls.adv(0);
  pls.schr(0, plot_text_scale);
  pls.col0(ink_colour);
  const Ieee952Fit& fit = *recommended(r);
  const std::string title = fmt::format("IEEE-952 fit of both curves: residuals ({}, chi2/dof {:.3g})", name(fit.status),
                                        fit.chi2_per_dof());
  if (fit.n_residuals == 0) return draw_empty_panel(pls, title, "no point fitted");
  double extreme = 3;
  for (std::size_t i = 0; i < fit.n_residuals; ++i) extreme = std::max(extreme, std::fabs(fit.residuals[i].normalized));
  extreme = std::ceil(extreme * 1.1);
  draw_log_frame(pls, std::log10(tau_lo), std::log10(tau_hi), -extreme, extreme, "averaging time #gt [s]",
                 "(estimate - model) / its standard deviation", title, false);
  for (const double level : {-2.0, 2.0}) {
    const PLFLT lx[2] = {std::log10(tau_lo), std::log10(tau_hi)}, ly[2] = {level, level};
    pls.col0(sum_colour);
    pls.lsty(2);
    pls.line(2, lx, ly);
    pls.lsty(1);
  }
  PlotLegend legend;
  for (const Stat stat : {Stat::avar, Stat::mvar}) {
    std::vector<PLFLT> x, y;
    for (std::size_t i = 0; i < fit.n_residuals; ++i) {
      const FitResidual& q = fit.residuals[i];
      if (q.stat != stat) continue;
      x.push_back(std::log10(static_cast<double>(q.m) * r.tau0_s));
      y.push_back(q.normalized);
    }
    const bool allan = stat == Stat::avar;
    pls.col0(allan ? adev_colour : mdev_colour);
    pls.schr(0, plot_glyph_scale);
    pls.string(static_cast<PLINT>(x.size()), x.data(), y.data(), allan ? adev_glyph : mdev_glyph);
    pls.schr(0, plot_text_scale);
    legend.symbol(allan ? "Allan points" : "modified Allan points", allan ? adev_colour : mdev_colour,
                  allan ? adev_glyph : mdev_glyph);
  }
  legend.line("±2 standard deviations", sum_colour, 2);
  legend.draw(pls);
}

}  // namespace

bool write_static_plot(const std::string& prefix, const Report& report, const std::vector<AnalysisRow>& curves,
                       std::string& why) {
  const CurvePanel adev = curve_panel(report, curves, DevStat::oadev), mdev = curve_panel(report, curves, DevStat::mdev);
  std::vector<std::function<void(plstream&)>> panels;
  panels.push_back([&](plstream& pls) { draw_curve_panel(pls, adev, report); });
  panels.push_back([&](plstream& pls) { draw_curve_panel(pls, mdev, report); });
  if (report.spectrum) panels.push_back([&](plstream& pls) { draw_psd_panel(pls, report); });
  const Ieee952Fit* fit = recommended(report);
  if (fit != nullptr && fit->n_residuals > 0 && adev.tau_lo > 0)
    panels.push_back([&](plstream& pls) { draw_residual_panel(pls, report, adev.tau_lo, adev.tau_hi); });
  return write_figure(
      prefix, panels.size(), deviation_palette(), 1500, 900, [&](plstream& pls, std::size_t k) { panels[k](pls); }, why);
}

}  // namespace gyrochar
