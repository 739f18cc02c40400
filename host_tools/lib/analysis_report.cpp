#include "analysis_report.hpp"

#include <fmt/format.h>

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

const char* curve_name(Ieee952Curve c) { return c == Ieee952Curve::avar ? "avar" : "mvar"; }

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

std::vector<CurveFit> fit_curves(const Analysis& a, const ReportUnits& units, double tau0_s) {
  std::vector<CurveFit> fits;
  for (const auto& [stat, curve] : {std::pair{DevStat::oadev, Ieee952Curve::avar}, std::pair{DevStat::mdev, Ieee952Curve::mvar}}) {
    std::vector<VariancePoint> points;
    for (const AnalysisRow& r : a.rows) {
      if (r.stat != stat) continue;
      const double dev_si = r.dev * units.phase_unit_si;
      points.push_back({r.tau_s, dev_si * dev_si, r.edf});
    }
    if (!points.empty()) fits.push_back({curve, fit_ieee952(points, curve, tau0_s)});
  }
  return fits;
}

std::string format_table(const Report& r) {
  const Analysis& a = r.analysis;
  const ReportUnits& u = r.units;
  std::string out;
  auto to = std::back_inserter(out);
  fmt::format_to(to, "# {} data: {}; {} values, tau0 = {} s; stride factor {}; {:.1f} % confidence intervals\n",
                 name(r.type), u.input, a.n_values, r.tau0_s, a.stride_factor, 100.0 * r.confidence);
  fmt::format_to(to, "# deviations in {}{}\n", u.gyro ? u.rate.name : "fractional frequency",
                 u.gyro ? fmt::format(", TDEV in {}", u.rate.angle) : std::string(", TDEV in s"));
  fmt::format_to(to, "{:<6} {:>12} {:>12} {:>12} {:>13} {:>13} {:>13} {:>6} {:>9}  {}\n", "stat", "m", "tau [s]", "n",
                 "ci low", "dev", "ci high", "alpha", "edf", "unit");
  const double k = u.factor();
  for (const AnalysisRow& row : a.rows) {
    fmt::format_to(to, "{:<6} {:>12} {:>12.6g} {:>12} {:>13} {:>13.5e} {:>13} {:>6} {:>9}  {}\n", name(row.stat), row.m,
                   row.tau_s, row.n, row.ci.valid ? fmt::format("{:.5e}", row.ci.low * k) : "-", row.dev * k,
                   row.ci.valid ? fmt::format("{:.5e}", row.ci.high * k) : "-",
                   row.alpha ? fmt::format("{}", *row.alpha) : "-", row.edf > 0 ? fmt::format("{:.4g}", row.edf) : "-",
                   u.unit(row.stat));
  }
  for (const CurveFit& f : r.fits) {
    fmt::format_to(to, "# IEEE-952 fit on the {} curve: {} points, chi2/dof {:.3g}{}\n", curve_name(f.curve),
                   f.fit.points, f.fit.chi2_per_dof, f.fit.ok ? "" : " (failed: too few points)");
    for (std::size_t i = 0; i < 5; ++i) {
      const FitUnit& fu = fit_units(u)[i];
      const Ieee952Parameter& p = f.fit.p[i];
      fmt::format_to(to, "#   {} = {:.4g} +- {:.2g} {}{}\n", fu.name, p.value / fu.si, p.uncertainty / fu.si, fu.unit,
                     p.resolved ? "" : "  (not resolved)");
    }
  }
  return out;
}

std::string format_csv(const Report& r) {
  std::string out = "stat,m,tau,n,dev,unit,alpha,edf,ci_low,ci_high,stride\n";
  auto to = std::back_inserter(out);
  const double k = r.units.factor();
  for (const AnalysisRow& row : r.analysis.rows) {
    fmt::format_to(to, "{},{},{},{},{},{},{},{},{},{},{}\n", name(row.stat), row.m, row.tau_s, row.n, row.dev * k,
                   r.units.unit(row.stat), row.alpha ? fmt::format("{}", *row.alpha) : "",
                   row.edf > 0 ? fmt::format("{}", row.edf) : "", row.ci.valid ? fmt::format("{}", row.ci.low * k) : "",
                   row.ci.valid ? fmt::format("{}", row.ci.high * k) : "", row.stride);
  }
  return out;
}

nlohmann::json to_json(const Report& r) {
  using nlohmann::json;
  const ReportUnits& u = r.units;
  const double k = u.factor();
  json j;
  j["tau0"] = r.tau0_s;
  j["n_samples"] = r.analysis.n_values;
  j["type"] = name(r.type);
  j["units"] = {{"input", u.input},
                {"dev", u.gyro ? u.rate.name : "1"},
                {"tdev", u.gyro ? u.rate.angle : "s"}};
  j["stride_factor"] = r.analysis.stride_factor;
  j["confidence"] = r.confidence;
  json rows = json::array();
  for (const AnalysisRow& row : r.analysis.rows) {
    rows.push_back({{"stat", name(row.stat)},
                    {"m", row.m},
                    {"tau", row.tau_s},
                    {"n", row.n},
                    {"dev", row.dev * k},
                    {"unit", u.unit(row.stat)},
                    {"alpha", row.alpha ? json(*row.alpha) : json(nullptr)},
                    {"edf", row.edf > 0 ? json(row.edf) : json(nullptr)},
                    {"ci_low", row.ci.valid ? json(row.ci.low * k) : json(nullptr)},
                    {"ci_high", row.ci.valid ? json(row.ci.high * k) : json(nullptr)},
                    {"stride", row.stride}});
  }
  j["results"] = std::move(rows);
  if (!r.fits.empty()) {
    json fits = json::array();
    for (const CurveFit& f : r.fits) {
      json fit = {{"curve", curve_name(f.curve)}, {"points", f.fit.points}, {"chi2_per_dof", f.fit.chi2_per_dof}, {"ok", f.fit.ok}};
      for (std::size_t i = 0; i < 5; ++i) {
        const FitUnit& fu = fit_units(u)[i];
        const Ieee952Parameter& p = f.fit.p[i];
        fit[fu.name] = {{"value", p.value / fu.si}, {"uncertainty", p.uncertainty / fu.si}, {"resolved", p.resolved}, {"unit", fu.unit}};
      }
      fits.push_back(std::move(fit));
    }
    j["fit"] = std::move(fits);
  }
  return j;
}

}  // namespace gyrochar
