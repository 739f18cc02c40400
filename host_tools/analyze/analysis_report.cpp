#include "analysis_report.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <filesystem>
#include <iterator>
#include <limits>
#include <numbers>

#include "confidence.hpp"

namespace gyrochar {

namespace {

// IEEE-952 parameters Q, N, B, K, R: letter, unit and size of the unit in SI.
using FitUnit = units::Ieee952Unit;
constexpr const FitUnit* gyro_fit_units = units::ieee952.data();
constexpr FitUnit clock_fit_units[5] = {
    {"Q", "s", 1}, {"N", "s^0.5", 1}, {"B", "1", 1}, {"K", "s^-0.5", 1}, {"R", "1/s", 1}};

const FitUnit* fit_units(const ReportUnits& u) { return u.gyro ? gyro_fit_units : clock_fit_units; }

// How the noise at a row was identified, and the plausible range when it is wider than one type:
// "lag1", "rn -1..0", "given".
std::string identification(const AnalysisRow& row) {
  if (!row.noise.identified()) return "-";
  std::string s = name(row.noise.method);
  if (row.noise.low != row.noise.high) s += fmt::format(" {}..{}", row.noise.low, row.noise.high);
  return s;
}

// "AVAR below 655 s, MVAR below 5.12 s"
std::string excluded_text(const Ieee952Fit& fit) {
  std::string s;
  for (std::size_t k = 0; k < 2; ++k) {
    if (!(fit.excluded_below_tau_s[k] > 0)) continue;
    if (!s.empty()) s += ", ";
    s += fmt::format("{} below {:.4g} s", k == 0 ? "AVAR" : "MVAR", fit.excluded_below_tau_s[k]);
  }
  return s.empty() ? "none" : s;
}

std::string fit_summary(const CurveFit& f) {
  const Ieee952Fit& fit = f.fit;
  std::string s = fmt::format("IEEE-952 fit of {}{}: {} points", curve_title(f.curve),
                              f.long_tau != 0 ? fmt::format(", long taus from {}", name(static_cast<LongTau>(f.long_tau)))
                                              : std::string(),
                              fit.points);
  if (fit.status == FitStatus::too_few_points || fit.status == FitStatus::singular)
    return s + fmt::format(": not identified ({})", name(fit.status));
  s += fmt::format(", chi2/dof {:.3g} on {} dof", fit.chi2_per_dof(), fit.dof);
  if (fit.birge > 1) s += fmt::format(", uncertainties scaled by {:.3g}", fit.birge);
  if (fit.status == FitStatus::rejected) s += ": MODEL REJECTED, the model does not describe this curve";
  return s;
}

// The unit of a correlation time and its 68 % interval, "s (68 %: 250 .. 1620 s)", or that no
// uncertainty was determined.
std::string with_interval(double tc_s, double sd_s) {
  const std::string interval = correlation_time_interval(tc_s, sd_s);
  return interval.empty() ? std::string("s (uncertainty not determined)") : "s (" + interval + ")";
}

// "5 terms + filter + 1 Markov (criterion 41.2); runner-up 5 terms + filter (criterion 96.3, chi2/dof 2.6)"
std::string candidate_text(const ModelSummary& m) {
  std::string s = "five terms";
  if (m.bandwidth) s += " + filter";
  if (m.markov) s += fmt::format(" + {} Markov", m.markov);
  if (m.sinusoids) s += fmt::format(" + {} sinusoid{}", m.sinusoids, m.sinusoids > 1 ? "s" : "");
  return s;
}

std::string model_text(const Ieee952Fit& fit) {
  std::string s = fmt::format("{} (criterion chi2 + p ln n = {:.4g}, p = {})", candidate_text(fit.chosen),
                              fit.chosen.criterion, fit.chosen.parameters);
  if (fit.runner_up.valid)
    s += fmt::format("; runner-up {} (criterion {:.4g} on the same covariance{})", candidate_text(fit.runner_up),
                     fit.runner_up.criterion,
                     fit.runner_up.criterion < fit.chosen.criterion
                         ? ": lower, but a term it adds is not two standard uncertainties above zero, its time lies "
                           "at the end of its search range, or it takes N's place"
                         : "");
  return s;
}

}  // namespace

// Out of line: inlined into main's read loop, GCC kept the three running values in memory.
void DataRange::add(std::span<const double> values) {
  if (values.empty()) return;
  double lo = count == 0 ? values[0] : min, hi = count == 0 ? values[0] : max, s = sum;
  for (const double v : values) {
    lo = v < lo ? v : lo;
    hi = v > hi ? v : hi;
    s += v;
  }
  min = lo;
  max = hi;
  sum = s;
  count += values.size();
}

std::string ReportUnits::unit(DevStat s) const {
  const bool time = info(s).time;  // in phase units
  if (gyro) return time ? rate.angle : rate.name;
  return time ? "s" : "1";
}

const units::Ieee952Unit& fit_unit(const ReportUnits& u, std::size_t k) { return fit_units(u)[k]; }

const char* curve_title(FitCurve c) {
  switch (c) {
    case FitCurve::both: return "both curves (recommended)";
    case FitCurve::avar: return "the Allan curve alone";
    case FitCurve::mvar: return "the modified Allan curve alone";
  }
  return "?";
}

const char* name(LongTau l) {
  switch (l) {
    case LongTau::oadev: return name(DevStat::oadev);
    case LongTau::totdev: return name(DevStat::totdev);
    case LongTau::theoh: return name(DevStat::theoh);
  }
  return "?";
}

namespace {

// "   simulated sigma 0.5 deg/h, Tc 300 s": the simulated Markov term nearest in ln Tc, if any.
std::string simulated_markov(const std::optional<Ieee952Truth>& truth, double tc_s, const units::Ieee952Unit& rate) {
  if (!truth || truth->markov.empty()) return "";
  const MarkovRate* nearest = &truth->markov.front();
  for (const MarkovRate& m : truth->markov)
    if (std::fabs(std::log(m.tc_s / tc_s)) < std::fabs(std::log(nearest->tc_s / tc_s))) nearest = &m;
  return fmt::format("   simulated sigma {:.4g} {}, Tc {:.4g} s", nearest->sigma_rad_s / rate.si, rate.name, nearest->tc_s);
}

// "   simulated 2 deg/h at 0.05 Hz": the simulated sinusoid nearest in frequency, if any.
std::string simulated_sinusoid(const std::optional<Ieee952Truth>& truth, double hz, const units::Ieee952Unit& rate) {
  if (!truth || truth->sinusoids.empty()) return "";
  const SinusoidRate* nearest = &truth->sinusoids.front();
  for (const SinusoidRate& s : truth->sinusoids)
    if (std::fabs(s.frequency_hz - hz) < std::fabs(nearest->frequency_hz - hz)) nearest = &s;
  return fmt::format("   simulated {:.4g} {} at {:.6g} Hz", nearest->amplitude_rad_s / rate.si, rate.name,
                     nearest->frequency_hz);
}

std::array<double, 5> truth_values(const Ieee952Truth& t) {
  return {t.q_rad, t.n_rad_sqrt_s, t.b_rad_s, t.k_rad_s_sqrt_s, t.r_rad_s2};
}

}  // namespace

std::optional<Readoff> readoff_of(const Analysis& a, const ReportUnits& units) {
  if (!units.gyro) return std::nullopt;
  constexpr double none = std::numeric_limits<double>::quiet_NaN();
  const double k = units.phase_unit_si;  // engine deviations -> rad/s
  std::vector<AdevPoint> points;
  for (const AnalysisRow& r : a.rows)
    if (r.stat == DevStat::oadev)
      points.push_back({r.tau_s, r.dev * k, r.ci.valid ? r.ci.low * k : none, r.ci.valid ? r.ci.high * k : none});
  if (points.empty()) return std::nullopt;
  return read_off(points);
}

std::optional<bool> readoff_agrees(const ReadoffValue& v, const Ieee952Fit* fit, std::size_t term) {
  if (fit == nullptr || !fit->ok() || !v.valid || term >= fit->p.size() || !fit->p[term].fitted) return std::nullopt;
  const double half_width = (v.ci_high - v.ci_low) / 2;
  if (!std::isfinite(half_width)) return std::nullopt;
  const Ieee952Parameter& p = fit->p[term];
  return std::fabs(v.value - p.value) <= std::hypot(p.uncertainty, half_width);
}

std::vector<std::string> model_difference_notes(const Ieee952Fit& fit, const ReportUnits& u) {
  std::vector<std::string> notes;
  for (std::size_t i = 2; i < 4; ++i)
    if (fit.p[i].markov_in_place_tc_s > 0)
      notes.push_back(
          fmt::format("the uncertainties include each term's difference to the model with a Markov term of Tc "
                      "{:.4g} s in {}'s place",
                      fit.p[i].markov_in_place_tc_s, fit_unit(u, i).letter));
  return notes;
}

namespace {

// The recommended fit (both curves), or nullptr when none was made.
const Ieee952Fit* recommended_fit(const Report& r) {
  const auto both = std::find_if(r.fits.begin(), r.fits.end(), [](const CurveFit& f) { return f.curve == FitCurve::both; });
  return both == r.fits.end() ? nullptr : &both->fit;
}

// The read-off values that are IEEE-952 terms: the fit's term index (Q N B K R), the member.
struct ReadoffTerm {
  std::size_t term;
  const ReadoffValue Readoff::*value;
  const char* above;  // why a read-off above the fit need not be an error
  const char* below;  // and one below it
};
constexpr std::array<ReadoffTerm, 3> readoff_terms{{
    {1, &Readoff::n, "the read-off N carries the other terms at its tau",
     "a filter or correlated noise bends the curve below the line, or the read-off took the lowest of scattered points"},
    {2, &Readoff::b, "the read-off B is an upper bound when other terms add at the floor (N, K, correlated noise)",
     "the read-off B is an upper bound when other terms add at the floor, but the floor is the lowest of scattered "
     "points, which biases it low"},
    {3, &Readoff::k, "the read-off K carries the other terms at its tau",
     "the read-off takes the lowest of scattered points, which biases it low"},
}};

// "2.313 [2.31, 2.316] deg/sqrt(h)": a value and its interval in a unit of `si` SI units.
std::string readoff_text(const ReadoffValue& v, double si, const char* unit) {
  const bool ci = std::isfinite(v.ci_low) && std::isfinite(v.ci_high);
  return fmt::format("{:.4g}{} {}", v.value / si,
                     ci ? fmt::format(" [{:.4g}, {:.4g}]", v.ci_low / si, v.ci_high / si) : std::string(" (no interval)"),
                     unit);
}

void format_readoff(std::string& out, const Report& r) {
  const Readoff& ro = *r.readoff;
  const FitUnit* fu = fit_units(r.units);
  const RateUnit& rate = r.units.rate;
  const std::string n = ro.n.valid
                            ? fmt::format("N = {} at tau {:.4g} s", readoff_text(ro.n, fu[1].si, fu[1].name), ro.n.tau_s)
                            : "N not read (no point up to the floor follows slope -1/2)";
  const std::string floor = fmt::format("bias floor {} at tau {:.4g} s{}, B = floor/0.664 = {}",
                                        readoff_text(ro.floor, rate.rad_per_s, rate.name), ro.floor.tau_s,
                                        ro.floor_at_end ? " (an end of the curve: it has not turned there)" : "",
                                        readoff_text(ro.b, fu[2].si, fu[2].name));
  const std::string k = ro.k.valid
                            ? fmt::format("K = {} at tau {:.4g} s", readoff_text(ro.k, fu[3].si, fu[3].name), ro.k.tau_s)
                            : "K not read (the curve never rises at slope +1/2 after its floor)";
  fmt::format_to(std::back_inserter(out), "# read-off (IEEE-952 graphical, data-sheet style): {}; {}; {}\n", n, floor, k);
  const Ieee952Fit* fit = recommended_fit(r);
  for (const ReadoffTerm& t : readoff_terms) {
    const std::optional<bool> agrees = readoff_agrees(ro.*t.value, fit, t.term);
    if (!agrees || *agrees) continue;
    const Ieee952Parameter& p = fit->p[t.term];
    const ReadoffValue& v = ro.*t.value;
    const double si = fu[t.term].si;
    fmt::format_to(std::back_inserter(out),
                   "#   read-off {} disagrees with the recommended fit's {:.4g} +- {:.2g} {}: they differ by {:.3g}, more "
                   "than their combined uncertainty {:.3g} (the fit's standard uncertainty and the read-off's half "
                   "interval in quadrature); {}\n",
                   fu[t.term].letter, p.value / si, p.uncertainty / si, fu[t.term].name, std::fabs(v.value - p.value) / si,
                   std::hypot(p.uncertainty, (v.ci_high - v.ci_low) / 2) / si, v.value > p.value ? t.above : t.below);
  }
}

nlohmann::json readoff_json(const Report& r) {
  using nlohmann::json;
  const Readoff& ro = *r.readoff;
  const FitUnit* fu = fit_units(r.units);
  const auto entry = [](const ReadoffValue& v, double si, const char* unit) {
    const auto number = [&](double x) { return v.valid && std::isfinite(x) ? json(x / si) : json(nullptr); };
    return json{{"value", number(v.value)},
                {"ci_low", number(v.ci_low)},
                {"ci_high", number(v.ci_high)},
                {"tau", v.valid ? json(v.tau_s) : json(nullptr)},
                {"unit", unit}};
  };
  json j = {{"method", "IEEE-952 graphical read-off of the OADEV curve (data-sheet style)"},
            {"slope_band", ReadoffOptions{}.slope_band}};
  const Ieee952Fit* fit = recommended_fit(r);
  for (const ReadoffTerm& t : readoff_terms) {
    json e = entry(ro.*t.value, fu[t.term].si, fu[t.term].name);
    const std::optional<bool> agrees = readoff_agrees(ro.*t.value, fit, t.term);
    e["agrees_with_fit"] = agrees ? json(*agrees) : json(nullptr);
    j[fu[t.term].letter] = std::move(e);
  }
  json floor = entry(ro.floor, r.units.rate.rad_per_s, r.units.rate.name);
  floor["at_end"] = ro.floor_at_end;
  j["floor"] = std::move(floor);
  return j;
}

}  // namespace

std::string format_table(const Report& r) {
  const Analysis& a = r.analysis;
  const ReportUnits& u = r.units;
  std::string out;
  auto to = std::back_inserter(out);
  fmt::format_to(to, "# {} data: {}; {} values, tau0 = {} s; stride factor {}; {:.1f} % confidence intervals\n",
                 name(r.type), u.input, a.n_values, r.tau0_s, a.stride_factor, 100.0 * r.confidence);
  fmt::format_to(to, "# deviations in {}{}\n", u.gyro ? u.rate.name : "fractional frequency",
                 u.gyro ? fmt::format(", TDEV in {}", u.rate.angle) : std::string(", TDEV in s"));
  fmt::format_to(to, "{:<6} {:>12} {:>12} {:>12} {:>13} {:>13} {:>13} {:>6} {:>12} {:>9}  {}\n", "stat", "m", "tau [s]", "n",
                 "ci low", "dev", "ci high", "alpha", "noise id", "edf", "unit");
  const double k = u.factor();
  for (const AnalysisRow& row : a.rows) {
    fmt::format_to(to, "{:<6} {:>12} {:>12.6g} {:>12} {:>13} {:>13.5e} {:>13} {:>6} {:>12} {:>9}  {}\n", name(row.stat),
                   row.m, row.tau_s, row.n, row.ci.valid ? fmt::format("{:.5e}", row.ci.low * k) : "-", row.dev * k,
                   row.ci.valid ? fmt::format("{:.5e}", row.ci.high * k) : "-",
                   row.alpha ? fmt::format("{}", *row.alpha) : "-", identification(row),
                   row.edf > 0 ? fmt::format("{:.4g}", row.edf) : "-", u.unit(row.stat));
  }
  for (const CurveFit& f : r.fits) {
    fmt::format_to(to, "# {}\n", fit_summary(f));
    if (!f.fit.quantization_white)
      fmt::format_to(to,
                     "#   quantization is not white (the angle moves too little between samples: a steady rate "
                     "quantizes into a pattern, white rate noise of less than about a pulse a sample into a "
                     "correlated error; dither whitens it): points it reaches left out ({}), Q held at "
                     "pulse weight / sqrt(12)\n",
                     excluded_text(f.fit));
    if (f.fit.status == FitStatus::too_few_points || f.fit.status == FitStatus::singular) continue;
    fmt::format_to(to, "#   model: {}\n", model_text(f.fit));
    if (f.fit.bandwidth_excluded_below_tau_s > 0)
      fmt::format_to(to,
                     "#   the sensor's own filter shapes the curve below {:.4g} s (a first-order filter does not describe "
                     "it there): those points left out\n",
                     f.fit.bandwidth_excluded_below_tau_s);
    if (f.fit.status == FitStatus::rejected) {
      fmt::format_to(to,
                     "#   no term is given as a result: even the best model found does not describe this curve (the "
                     "residuals per tau are in --format json)\n");
      continue;
    }
    for (std::size_t i = 0; i < 5; ++i) {
      const FitUnit& fu = fit_units(u)[i];
      const Ieee952Parameter& p = f.fit.p[i];
      if (!p.fitted && !(i == 0 && !f.fit.quantization_white)) {
        fmt::format_to(to, "#   {} not in the model ({}){}\n", fu.letter,
                       p.held_for_markov ? "held at zero: a Markov term stands in its place"
                                         : "the fit is better without it",
                       r.truth ? fmt::format("   simulated {:.4g} {}", truth_values(*r.truth)[i] / fu.si, fu.name) : "");
        continue;
      }
      const std::string truth = r.truth ? fmt::format("   simulated {:.4g}", truth_values(*r.truth)[i] / fu.si) : "";
      if (!p.fitted)
        fmt::format_to(to, "#   {} = {:.4g} {}  (held, not fitted){}\n", fu.letter, p.value / fu.si, fu.name, truth);
      else
        fmt::format_to(to, "#   {} = {:.4g} +- {:.2g} {}{}{}\n", fu.letter, p.value / fu.si, p.uncertainty / fu.si, fu.name,
                       p.resolved ? ""
                       : p.markov_in_place_tc_s > 0
                           ? fmt::format("  (not resolved: a Markov term of Tc {:.4g} s in its place describes the curve "
                                         "as well, its chi2 within 2 ln 19)",
                                         p.markov_in_place_tc_s)
                       : p.doubted ? "  (not resolved: the runner-up model, close by the criterion, does without it)"
                                   : "  (not resolved)",
                       truth);
    }
    for (const std::string& note : model_difference_notes(f.fit, u))
      fmt::format_to(to, "#   {} (it describes the curve as well)\n", note);
    const FitUnit& rate = fit_units(u)[2];  // B's unit: a rate
    if (f.fit.bandwidth_tc_s > 0)
      fmt::format_to(to,
                     "#   sensor bandwidth: N's white noise through a first-order filter, Tf = {:.3g} {} "
                     "(corner {:.4g} Hz)\n",
                     f.fit.bandwidth_tc_s, with_interval(f.fit.bandwidth_tc_s, f.fit.bandwidth_tc_uncertainty_s),
                     1 / (2 * std::numbers::pi * f.fit.bandwidth_tc_s));
    for (std::size_t j = 0; j < f.fit.n_markov; ++j) {
      const MarkovTerm& m = f.fit.markov[j];
      fmt::format_to(to, "#   Markov {}: sigma = {:.4g} +- {:.2g} {}, Tc = {:.4g} {}{}{}\n", j + 1, m.sigma.value / rate.si,
                     m.sigma.uncertainty / rate.si, rate.name, m.tc_s, with_interval(m.tc_s, m.tc_uncertainty_s),
                     m.sigma.resolved ? "" : "  (not resolved)", simulated_markov(r.truth, m.tc_s, rate));
    }
    if (r.truth && f.fit.n_markov == 0)
      for (const MarkovRate& m : r.truth->markov)
        fmt::format_to(to, "#   no Markov term in the model   simulated sigma {:.4g} {}, Tc {:.4g} s\n",
                       m.sigma_rad_s / rate.si, rate.name, m.tc_s);
    for (std::size_t j = 0; j < f.fit.n_sinusoids; ++j) {
      const SinusoidTerm& sn = f.fit.sinusoids[j];
      fmt::format_to(to, "#   sinusoid {}: amplitude = {:.4g} +- {:.2g} {} at {:.6g} Hz{}{}\n", j + 1,
                     sn.amplitude.value / rate.si, sn.amplitude.uncertainty / rate.si, rate.name, sn.frequency_hz,
                     sn.amplitude.resolved ? "" : "  (not resolved)", simulated_sinusoid(r.truth, sn.frequency_hz, rate));
    }
  }
  if (r.readoff) format_readoff(out, r);
  if (r.spectrum) out += spectrum_table(*r.spectrum);
  return out;
}

std::string csv_fields(const AnalysisRow& row, const ReportUnits& u) {
  const double k = u.factor();
  return fmt::format("{},{},{},{},{},{},{},{},{},{},{}", name(row.stat), row.m, row.tau_s, row.n, row.dev * k,
                     u.unit(row.stat), row.alpha ? fmt::format("{}", *row.alpha) : "",
                     row.edf > 0 ? fmt::format("{}", row.edf) : "", row.ci.valid ? fmt::format("{}", row.ci.low * k) : "",
                     row.ci.valid ? fmt::format("{}", row.ci.high * k) : "", row.stride);
}

std::string format_csv(const Report& r) {
  std::string out = std::string(csv_header) + "\n";
  for (const AnalysisRow& row : r.analysis.rows) out += csv_fields(row, r.units) + "\n";
  return out;
}

nlohmann::json row_json(const AnalysisRow& row, const ReportUnits& u) {
  using nlohmann::json;
  const double k = u.factor();
  return {{"stat", name(row.stat)},
          {"m", row.m},
          {"tau", row.tau_s},
          {"n", row.n},
          {"dev", row.dev * k},
          {"unit", u.unit(row.stat)},
          {"alpha", row.alpha ? json(*row.alpha) : json(nullptr)},
          {"noise_id", row.noise.identified() ? json(name(row.noise.method)) : json(nullptr)},
          {"alpha_range", row.noise.identified() ? json({row.noise.low, row.noise.high}) : json(nullptr)},
          {"edf_alpha", row.edf > 0 ? json(row.edf_alpha) : json(nullptr)},
          {"edf", row.edf > 0 ? json(row.edf) : json(nullptr)},
          {"ci_low", row.ci.valid ? json(row.ci.low * k) : json(nullptr)},
          {"ci_high", row.ci.valid ? json(row.ci.high * k) : json(nullptr)},
          {"stride", row.stride}};
}

nlohmann::json units_json(const ReportUnits& u) {
  return {{"input", u.input}, {"dev", u.gyro ? u.rate.name : "1"}, {"tdev", u.gyro ? u.rate.angle : "s"}};
}

namespace {

nlohmann::json positive_or_null(double v) { return v > 0 ? nlohmann::json(v) : nlohmann::json(nullptr); }

nlohmann::json summary_json(const ModelSummary& m) {
  using nlohmann::json;
  if (!m.valid) return json(nullptr);
  return {{"markov", m.markov},         {"sinusoids", m.sinusoids}, {"bandwidth", m.bandwidth},
          {"status", name(m.status)},   {"chi2", m.chi2},           {"dof", m.dof},
          {"parameters", m.parameters}, {"criterion", m.criterion}};
}

nlohmann::json parameter_json(const Ieee952Parameter& p, double si, const std::string& unit) {
  return {{"value", p.value / si},
          {"uncertainty", p.uncertainty / si},
          {"unit", unit},
          {"fitted", p.fitted},
          {"resolved", p.resolved}};
}

// A correlation time: its value, uncertainty (Tc sd(ln Tc)) and the 68 % interval that follows from
// it (ci_low, ci_high: tc_interval()); null where not determined.
nlohmann::json tc_json(double tc_s, double sd_s) {
  const auto [low, high] = tc_interval(tc_s, sd_s);
  return {{"value", tc_s},
          {"uncertainty", positive_or_null(sd_s)},
          {"ci_low", positive_or_null(low)},
          {"ci_high", positive_or_null(high)},
          {"unit", "s"}};
}

// The terms beyond the five, the model selection and the residuals of a fit.
void add_model_json(nlohmann::json& one, const Ieee952Fit& fit, const ReportUnits& u) {
  using nlohmann::json;
  const FitUnit& rate = fit_units(u)[2];
  json markov = json::array();
  for (std::size_t j = 0; j < fit.n_markov; ++j)
    markov.push_back({{"sigma", parameter_json(fit.markov[j].sigma, rate.si, rate.name)},
                      {"tc", tc_json(fit.markov[j].tc_s, fit.markov[j].tc_uncertainty_s)}});
  json sinusoids = json::array();
  for (std::size_t j = 0; j < fit.n_sinusoids; ++j)
    sinusoids.push_back(
        {{"amplitude", parameter_json(fit.sinusoids[j].amplitude, rate.si, rate.name)},
         {"frequency", {{"value", fit.sinusoids[j].frequency_hz}, {"uncertainty", nullptr}, {"unit", "Hz"}}}});
  one["markov"] = std::move(markov);
  one["sinusoids"] = std::move(sinusoids);
  one["bandwidth"] = fit.bandwidth_tc_s > 0 ? json{{"tc", tc_json(fit.bandwidth_tc_s, fit.bandwidth_tc_uncertainty_s)},
                                                   {"corner_hz", 1 / (2 * std::numbers::pi * fit.bandwidth_tc_s)}}
                                            : json(nullptr);
  one["bandwidth_excluded_below_tau"] = fit.bandwidth_excluded_below_tau_s > 0 ? json(fit.bandwidth_excluded_below_tau_s)
                                                                               : json(nullptr);
  one["model"] = summary_json(fit.chosen);
  one["runner_up"] = summary_json(fit.runner_up);
  const double k = u.factor() / u.phase_unit_si;  // SI deviation -> output unit
  json residuals = json::array();
  for (std::size_t i = 0; i < fit.n_residuals; ++i) {
    const FitResidual& r = fit.residuals[i];
    residuals.push_back({{"stat", name(r.stat == Stat::avar ? DevStat::oadev : DevStat::mdev)},
                         {"m", r.m},
                         {"dev", std::sqrt(r.variance) * k},
                         {"model", std::sqrt(std::fmax(r.model, 0.0)) * k},
                         {"residual_sigma", r.normalized}});
  }
  one["residuals"] = std::move(residuals);
}

}  // namespace

nlohmann::json to_json(const Report& r) {
  using nlohmann::json;
  const ReportUnits& u = r.units;
  json j;
  j["tau0"] = r.tau0_s;
  j["n_samples"] = r.analysis.n_values;
  j["type"] = name(r.type);
  j["units"] = units_json(u);
  j["stride_factor"] = r.analysis.stride_factor;
  j["confidence"] = r.confidence;
  json rows = json::array();
  for (const AnalysisRow& row : r.analysis.rows) rows.push_back(row_json(row, u));
  j["results"] = std::move(rows);
  if (!r.fits.empty()) {
    json fits = json::array();
    for (const CurveFit& f : r.fits) {
      const Ieee952Fit& fit = f.fit;
      json one = {{"curve", name(f.curve)},
                  {"long_tau", name(static_cast<LongTau>(f.long_tau))},
                  {"recommended", f.curve == FitCurve::both},
                  {"status", name(fit.status)},
                  {"ok", fit.ok()},
                  {"points", fit.points},
                  {"chi2", fit.chi2},
                  {"dof", fit.dof},
                  {"chi2_per_dof", fit.chi2_per_dof()},
                  {"uncertainty_scale", fit.birge},
                  {"quantization_white", fit.quantization_white},
                  {"excluded_below_tau",
                   {{"avar", fit.excluded_below_tau_s[0] > 0 ? json(fit.excluded_below_tau_s[0]) : json(nullptr)},
                    {"mvar", fit.excluded_below_tau_s[1] > 0 ? json(fit.excluded_below_tau_s[1]) : json(nullptr)}}}};
      for (std::size_t i = 0; i < 5; ++i) {
        const FitUnit& fu = fit_units(u)[i];
        const Ieee952Parameter& p = fit.p[i];
        one[fu.letter] = {{"value", p.value / fu.si}, {"uncertainty", p.uncertainty / fu.si},
                          {"fitted", p.fitted},       {"resolved", p.resolved},
                          {"doubted", p.doubted},     {"unit", fu.name}};
        if (p.markov_in_place_tc_s > 0)  // doubted: a Markov term of this Tc in its place does as well
          one[fu.letter]["markov_in_place"] = {{"tc", p.markov_in_place_tc_s}, {"unit", "s"}};
        if (p.held_for_markov) one[fu.letter]["held_for_markov"] = true;  // a Markov term in its place
        if (p.unconstrained_uncertainty > 0)  // what a verdict judges (docs/metrology.md, "Acceptance limits")
          one[fu.letter]["unconstrained"] = {{"value", p.unconstrained / fu.si},
                                             {"uncertainty", p.unconstrained_uncertainty / fu.si}};
      }
      add_model_json(one, fit, u);
      fits.push_back(std::move(one));
    }
    j["fit"] = std::move(fits);
  }
  if (r.truth) {
    json truth = {{"quantization_white", r.truth->quantization_white}};
    for (std::size_t i = 0; i < 5; ++i) {
      const FitUnit& fu = fit_units(u)[i];
      truth[fu.letter] = {{"value", truth_values(*r.truth)[i] / fu.si}, {"unit", fu.name}};
    }
    j["simulated"] = std::move(truth);
  }
  if (r.readoff) j["readoff"] = readoff_json(r);
  if (r.spectrum) {
    j["psd"] = spectrum_json(*r.spectrum);
    if (j.contains("fit")) add_frequency_uncertainties(j["fit"], *r.spectrum);
  }
  return j;
}

std::string kalibr_left_out(const Ieee952Fit& fit) {
  std::string s;
  const auto add = [&](const std::string& t) { s += (s.empty() ? "" : ", ") + t; };
  if (fit.bandwidth_tc_s > 0) add("sensor filter");
  if (fit.n_markov) add(fmt::format("{} Markov term{}", fit.n_markov, fit.n_markov > 1 ? "s" : ""));
  if (fit.n_sinusoids) add(fmt::format("{} sinusoid{}", fit.n_sinusoids, fit.n_sinusoids > 1 ? "s" : ""));
  if (fit.p[2].fitted) add("B");
  if (fit.p[4].fitted) add("R");
  return s;
}

std::optional<std::string> kalibr_yaml(const Report& r, std::string& why) {
  if (!r.units.gyro) {
    why = "needs gyro data: counts, or --unit with an angle or a rate";
    return std::nullopt;
  }
  const Ieee952Fit* both = recommended_fit(r);
  if (both == nullptr) {
    why = "needs the IEEE-952 fit (--fit ieee952)";
    return std::nullopt;
  }
  if (!both->ok()) {
    why = fmt::format("the IEEE-952 fit of both curves is {}: no noise parameters to give", name(both->status));
    return std::nullopt;
  }
  const auto term = [&](std::size_t k) {
    const Ieee952Parameter& p = both->p[k];
    return KalibrTerm{p.value, p.value > 0 ? p.uncertainty / p.value : 0.0, p.fitted, p.resolved};
  };
  const std::string beyond = kalibr_left_out(*both);
  return kalibr_imu_yaml(term(1), term(3), 1.0 / r.tau0_s,
                         fmt::format("{} ({}){}", r.source, r.units.input,
                                     beyond.empty() ? "" : "; N and K alone, without the model's " + beyond),
                         why, true);
}

}  // namespace gyrochar
