#include "acceptance.hpp"

#include <fmt/format.h>

#include <cmath>

namespace gyrochar {
namespace {

LimitEstimate term_estimate(const Report& r, std::size_t k, double run_s) {
  const char* letter = units::ieee952[k].letter;
  if (r.fits.empty()) return no_estimate("no fit");
  const Ieee952Fit& fit = r.fits.front().fit;  // the recommended fit of both curves
  if (!fit.ok()) return no_estimate(fmt::format("fit {}", name(fit.status)));
  const Ieee952Parameter& p = fit.p[k];
  if (!p.fitted) return no_estimate(fmt::format("{} not in the fitted model", letter));
  if (!p.resolved) return no_estimate(fmt::format("{} not resolved", letter));
  return fitted_term_estimate(p, run_s);
}

LimitEstimate deviation_row_estimate(const Limit& l, const Report& r, const std::vector<AnalysisRow>& rows, double run_s) {
  const DevStat stat = l.kind == Limit::Kind::adev ? DevStat::oadev : DevStat::mdev;
  double below = 0, above = 0;
  for (const AnalysisRow& row : rows) {
    if (row.stat != stat) continue;
    if (std::abs(row.tau_s - l.tau_s) <= 1e-9 * l.tau_s) {
      // Engine units (phase unit per second) to rad/s.
      const double si = r.units.phase_unit_si;
      return deviation_estimate(row.dev * si, row.edf, row.skew_dof, run_s);
    }
    if (row.tau_s < l.tau_s) below = row.tau_s;
    else if (above == 0) above = row.tau_s;
  }
  return no_estimate(fmt::format("no {} at tau = {:g} s{}", name(stat), l.tau_s,
                                 below > 0 || above > 0 ? fmt::format(" (nearest: {:g} s, {:g} s)", below, above) : ""));
}

}  // namespace

// The non-negative fit's value leans low where it clips another term at zero (docs/metrology.md,
// "Acceptance limits"): judged by it, a gyro at the limit would pass more often than the risk.
LimitEstimate fitted_term_estimate(const Ieee952Parameter& p, double run_s) {
  if (p.unconstrained_uncertainty > 0) return normal_estimate(p.unconstrained, p.unconstrained_uncertainty, run_s);
  return normal_estimate(p.value, p.uncertainty, run_s);
}

int exit_code_of(Verdict v) {
  return v == Verdict::fail ? exit_limits_failed : v == Verdict::undecided ? exit_limits_undecided : 0;
}

std::uint64_t limit_m(const Limit& limit, double tau0_s) {
  if (limit.kind == Limit::Kind::term) return 0;
  const double m = std::round(limit.tau_s / tau0_s);
  if (!(m >= 1) || m > 9e15 || std::abs(m * tau0_s - limit.tau_s) > 1e-9 * limit.tau_s) return 0;
  return static_cast<std::uint64_t>(m);
}

std::vector<Decision> decide_limits(const std::vector<Limit>& limits, const Report& r, const std::vector<AnalysisRow>& rows,
                                    double run_s) {
  std::vector<Decision> out;
  for (const Limit& l : limits)
    out.push_back(decide(l, l.kind == Limit::Kind::term ? term_estimate(r, l.term, run_s)
                                                        : deviation_row_estimate(l, r, rows, run_s)));
  return out;
}

}  // namespace gyrochar
