#include "input_units.hpp"

#include <fmt/format.h>

#include <charconv>
#include <cmath>
#include <system_error>

#include "units.hpp"

namespace gyrochar {

namespace {

[[noreturn]] void refuse(const std::string& option, const std::string& why) { throw UnitError(option, why); }

// Counts: one pulse's angle, "1.5arcsec", "1.5 arcsec" or "1.5" (unit from --pulse-unit).
void resolve_pulse_weight(const UnitOptions& o, ReportUnits& u) {
  if (!o.unit.empty()) refuse("--unit", "counts take --pulse-weight instead");
  if (o.pulse_weight.empty()) refuse("--pulse-weight", "counts need the angle of one pulse, e.g. 1.5arcsec");
  const std::string& text = o.pulse_weight;
  double value = 0;
  const char* const end = text.data() + text.size();
  const auto [rest, ec] = std::from_chars(text.data(), end, value);
  if (ec != std::errc() || !(value > 0) || !std::isfinite(value))
    refuse("--pulse-weight", "'" + text + "' is not a positive angle such as 1.5arcsec");
  std::string unit(rest, end);
  unit.erase(0, unit.find_first_not_of(' '));
  if (unit.empty()) {
    unit = o.pulse_unit;
  } else if (o.pulse_unit_given && unit != o.pulse_unit) {
    refuse("--pulse-weight", "unit " + unit + " contradicts --pulse-unit " + o.pulse_unit);
  }
  const auto rad = angle_unit_rad(unit);
  if (!rad) refuse("--pulse-weight", "unknown angle unit '" + unit + "' (rad, mrad, urad, deg, arcsec)");
  if (!std::isnormal(value * *rad))  // 1e-320arcsec: every deviation would be 0 in the output unit
    refuse("--pulse-weight", fmt::format("{} {} is {:g} rad, below the smallest normal double (2.2e-308): the "
                                         "deviations would underflow to 0",
                                         value, unit, value * *rad));
  u.gyro = true;
  u.phase_unit_si = value * *rad;
  u.input = fmt::format("counts of {} {}", value, unit);
}

void resolve_phase(const UnitOptions& o, ReportUnits& u) {
  if (o.unit.empty() || o.unit == "s") {
    u.input = "phase in s";
  } else if (const auto rad = angle_unit_rad(o.unit)) {
    u.gyro = true;
    u.phase_unit_si = *rad;
    u.input = "angle in " + o.unit;
  } else {
    refuse("--unit", "phase is in s or an angle unit (rad, mrad, urad, deg, arcsec), not '" + o.unit + "'");
  }
  if (o.nominal_hz) refuse("--nominal-hz", "only applies to --type freq");
}

void resolve_freq(const UnitOptions& o, ReportUnits& u) {
  if (o.nominal_hz) {
    if (!(*o.nominal_hz > 0) || !std::isfinite(*o.nominal_hz)) refuse("--nominal-hz", "must be a positive frequency in Hz");
    if (!o.unit.empty() && o.unit != "Hz") refuse("--unit", "--nominal-hz means the values are in Hz");
    u.input = fmt::format("frequency in Hz, nominal {} Hz", *o.nominal_hz);
  } else if (o.unit.empty() || o.unit == "1") {
    u.input = "fractional frequency";
  } else if (const auto rate = rate_unit(o.unit)) {
    u.gyro = true;
    u.phase_unit_si = rate->rad_per_s;
    u.input = "rate in " + o.unit;
  } else if (o.unit == "Hz") {
    refuse("--unit", "frequency in Hz needs --nominal-hz");
  } else {
    refuse("--unit", "freq is in 1 (fractional), Hz or a rate unit (deg/h, deg/s, rad/s), not '" + o.unit + "'");
  }
}

}  // namespace

ReportUnits resolve_units(const UnitOptions& o) {
  ReportUnits u;
  if (o.type == DataType::counts) {
    resolve_pulse_weight(o, u);
  } else {
    if (!o.pulse_weight.empty() || o.pulse_unit_given) refuse("--pulse-weight", "only applies to --type counts");
    if (o.type == DataType::phase) resolve_phase(o, u);
    else resolve_freq(o, u);
  }
  if (u.gyro) {
    const auto rate = rate_unit(o.rate_unit);
    if (!rate) refuse("--rate-unit", "unknown unit '" + o.rate_unit + "' (deg/h, deg/s, rad/s)");
    u.rate = *rate;
  } else if (o.rate_unit_given) {
    refuse("--rate-unit", "only applies to gyro data (counts, or --unit with an angle or a rate)");
  }
  return u;
}

}  // namespace gyrochar
