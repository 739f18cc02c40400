#include "analysis_report.hpp"

#include <fmt/format.h>

#include <array>
#include <bit>
#include <cmath>
#include <iterator>
#include <numbers>

namespace gyrochar {

namespace {

constexpr double deg_rad = std::numbers::pi / 180.0;

// IEEE-952 parameters Q, N, B, K, R: name, unit and size of the unit in SI.
struct FitUnit {
  const char* name;
  const char* unit;
  double si;
};
constexpr FitUnit gyro_fit_units[5] = {{"Q", "arcsec", deg_rad / 3600.0},
                                       {"N", "deg/sqrt(h)", deg_rad / 60.0},
                                       {"B", "deg/h", deg_rad / 3600.0},
                                       {"K", "deg/h/sqrt(h)", deg_rad / (3600.0 * 60.0)},
                                       {"R", "deg/h/h", deg_rad / (3600.0 * 3600.0)}};
constexpr FitUnit clock_fit_units[5] = {{"Q", "s", 1}, {"N", "s^0.5", 1}, {"B", "1", 1}, {"K", "s^-0.5", 1}, {"R", "1/s", 1}};

const FitUnit* fit_units(const ReportUnits& u) { return u.gyro ? gyro_fit_units : clock_fit_units; }

const char* curve_title(FitCurve c) {
  switch (c) {
    case FitCurve::both: return "both curves (recommended)";
    case FitCurve::avar: return "the Allan curve alone";
    case FitCurve::mvar: return "the modified Allan curve alone";
  }
  return "?";
}

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
  std::string s = fmt::format("IEEE-952 fit of {}: {} points", curve_title(f.curve), fit.points);
  if (fit.status == FitStatus::too_few_points || fit.status == FitStatus::singular)
    return s + fmt::format(": not identified ({})", name(fit.status));
  s += fmt::format(", chi2/dof {:.3g} on {} dof", fit.chi2_per_dof(), fit.dof);
  if (fit.birge > 1) s += fmt::format(", uncertainties scaled by {:.3g}", fit.birge);
  if (fit.status == FitStatus::rejected) s += ": MODEL REJECTED, the IEEE-952 terms do not describe this curve";
  return s;
}

}  // namespace

std::optional<double> angle_unit_rad(std::string_view unit) {
  if (unit == "rad") return 1.0;
  if (unit == "mrad") return 1e-3;
  if (unit == "urad") return 1e-6;
  if (unit == "deg") return deg_rad;
  if (unit == "arcsec") return deg_rad / 3600.0;
  return std::nullopt;
}

std::optional<RateUnit> rate_unit(std::string_view unit) {
  if (unit == "deg/h") return RateUnit{"deg/h", deg_rad / 3600.0, "arcsec"};
  if (unit == "deg/s") return RateUnit{"deg/s", deg_rad, "deg"};
  if (unit == "rad/s") return RateUnit{"rad/s", 1.0, "rad"};
  return std::nullopt;
}

std::string ReportUnits::unit(DevStat s) const {
  if (gyro) return s == DevStat::tdev ? rate.angle : rate.name;
  return s == DevStat::tdev ? "s" : "1";
}

std::vector<CurveFit> fit_curves(const Analysis& a, const ReportUnits& units, double tau0_s,
                                 double white_quantization_si) {
  std::vector<FitPoint> points;
  for (const AnalysisRow& r : a.rows) {
    if ((r.stat != DevStat::oadev && r.stat != DevStat::mdev) || !std::has_single_bit(r.m)) continue;
    const double dev_si = r.dev * units.phase_unit_si;
    points.push_back({r.stat == DevStat::oadev ? Stat::avar : Stat::mvar, r.m, r.stride, r.n, dev_si * dev_si, r.edf});
  }
  std::vector<CurveFit> fits;
  if (points.empty()) return fits;
  std::vector<double> workspace(ieee952_workspace_doubles(points.size()));
  // The three fits share the covariance sums of their points: computed once, in a cache with room
  // for every pair.
  std::vector<PairSumCache::Entry> entries(points.size() * points.size() + 16);
  PairSumCache cache(entries);
  const FitSetup setup{tau0_s, a.n_phase, white_quantization_si};
  for (const FitCurve curve : {FitCurve::both, FitCurve::avar, FitCurve::mvar})
    fits.push_back({curve, fit_ieee952(points, setup, curve, workspace, &cache)});
  return fits;
}

std::optional<Ieee952Truth> truth_of(const std::vector<std::string>& header, DataType type, double tau0_s,
                                     double pulse_weight_rad) {
  if (type != DataType::counts) return std::nullopt;
  for (const std::string& line : header) {
    const auto t = parse_sim_truth_line(line);
    if (!t) continue;
    const auto same = [](double a, double b) { return std::fabs(a - b) <= 1e-9 * std::fabs(b); };
    if (!same(t->options.tau0_s, tau0_s) || !same(t->options.pulse_arcsec * deg_rad / 3600.0, pulse_weight_rad))
      return std::nullopt;
    if (!t->options.segments.empty()) return std::nullopt;  // the gyro changed: no one truth for the run
    return t->truth;
  }
  return std::nullopt;
}

namespace {

std::array<double, 5> truth_values(const Ieee952Truth& t) {
  return {t.q_rad, t.n_rad_sqrt_s, t.b_rad_s, t.k_rad_s_sqrt_s, t.r_rad_s2};
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
  fmt::format_to(to, "{:<6} {:>12} {:>12} {:>12} {:>13} {:>13} {:>13} {:>6} {:>12} {:>9}  {}\n", "stat", "m", "tau [s]",
                 "n", "ci low", "dev", "ci high", "alpha", "noise id", "edf", "unit");
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
      fmt::format_to(to, "#   quantization is not white (the short taus do not follow white quantization: a steady rate "
                         "makes a periodic pattern without dither): points it reaches left out ({}), Q held at "
                         "pulse weight / sqrt(12)\n",
                     excluded_text(f.fit));
    if (f.fit.status == FitStatus::too_few_points || f.fit.status == FitStatus::singular) continue;
    for (std::size_t i = 0; i < 5; ++i) {
      const FitUnit& fu = fit_units(u)[i];
      const Ieee952Parameter& p = f.fit.p[i];
      if (!p.fitted && !(i == 0 && !f.fit.quantization_white)) {
        fmt::format_to(to, "#   {} not in the model (the fit is better without it){}\n", fu.name,
                       r.truth ? fmt::format("   simulated {:.4g} {}", truth_values(*r.truth)[i] / fu.si, fu.unit) : "");
        continue;
      }
      const std::string truth = r.truth ? fmt::format("   simulated {:.4g}", truth_values(*r.truth)[i] / fu.si) : "";
      if (!p.fitted)
        fmt::format_to(to, "#   {} = {:.4g} {}  (held, not fitted){}\n", fu.name, p.value / fu.si, fu.unit, truth);
      else
        fmt::format_to(to, "#   {} = {:.4g} +- {:.2g} {}{}{}\n", fu.name, p.value / fu.si, p.uncertainty / fu.si, fu.unit,
                       p.resolved ? "" : "  (not resolved)", truth);
    }
  }
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
                  {"recommended", f.curve == FitCurve::both},
                  {"status", name(fit.status)},
                  {"ok", fit.ok()},
                  {"points", fit.points},
                  {"chi2", fit.chi2},
                  {"dof", fit.dof},
                  {"chi2_per_dof", fit.chi2_per_dof()},
                  {"uncertainty_scale", fit.birge},
                  {"quantization_white", fit.quantization_white},
                  {"excluded_below_tau", {{"avar", fit.excluded_below_tau_s[0] > 0 ? json(fit.excluded_below_tau_s[0]) : json(nullptr)},
                                          {"mvar", fit.excluded_below_tau_s[1] > 0 ? json(fit.excluded_below_tau_s[1]) : json(nullptr)}}}};
      for (std::size_t i = 0; i < 5; ++i) {
        const FitUnit& fu = fit_units(u)[i];
        const Ieee952Parameter& p = fit.p[i];
        one[fu.name] = {{"value", p.value / fu.si}, {"uncertainty", p.uncertainty / fu.si}, {"fitted", p.fitted},
                        {"resolved", p.resolved}, {"unit", fu.unit}};
      }
      fits.push_back(std::move(one));
    }
    j["fit"] = std::move(fits);
  }
  if (r.truth) {
    json truth = {{"quantization_white", r.truth->quantization_white}};
    for (std::size_t i = 0; i < 5; ++i) {
      const FitUnit& fu = fit_units(u)[i];
      truth[fu.name] = {{"value", truth_values(*r.truth)[i] / fu.si}, {"unit", fu.unit}};
    }
    j["simulated"] = std::move(truth);
  }
  return j;
}

}  // namespace gyrochar
