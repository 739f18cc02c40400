#include "confidence.hpp"

#include <fmt/format.h>

#include <boost/math/distributions/chi_squared.hpp>
#include <cmath>

#include "gyrochar/ieee952.hpp"

namespace gyrochar {

Interval confidence_interval(double dev, double edf, double confidence, double skew_dof) {
  Interval out;
  if (!(edf > 0) || !std::isfinite(edf) || !(confidence > 0 && confidence < 1) || !(dev >= 0)) return out;
  try {
    const double p = (1.0 - confidence) / 2.0;
    if (skew_dof > 0 && skew_dof < edf) {
      const boost::math::chi_squared chi2(skew_dof);
      const double b = 1 / std::sqrt(edf * skew_dof), a = 1 - b * skew_dof;
      out.low = dev / std::sqrt(a + b * boost::math::quantile(chi2, 1.0 - p));
      out.high = dev / std::sqrt(a + b * boost::math::quantile(chi2, p));
    } else {
      const boost::math::chi_squared chi2(edf);
      out.low = dev * std::sqrt(edf / boost::math::quantile(chi2, 1.0 - p));
      out.high = dev * std::sqrt(edf / boost::math::quantile(chi2, p));
    }
    out.valid = std::isfinite(out.low) && std::isfinite(out.high);
  } catch (const std::exception&) {
    out = Interval{};
  }
  return out;
}

Interval ConfidenceIntervals::operator()(double dev, double edf) {
  if (!(edf > 0) || !std::isfinite(edf)) return {};
  auto it = unit_intervals_.find(edf);
  if (it == unit_intervals_.end()) it = unit_intervals_.emplace(edf, confidence_interval(1.0, edf, confidence_)).first;
  const Interval& unit = it->second;
  return unit.valid ? Interval{dev * unit.low, dev * unit.high, true} : Interval{};
}

std::string correlation_time_interval(double tc_s, double uncertainty_s) {
  const auto [low, high] = tc_interval(tc_s, uncertainty_s);
  return high > 0 ? fmt::format("68 %: {:.3g} .. {:.3g} s", low, high) : std::string();
}

}  // namespace gyrochar
