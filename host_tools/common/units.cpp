#include "units.hpp"

namespace gyrochar {

std::optional<double> angle_unit_rad(std::string_view unit) {
  if (unit == "rad") return 1.0;
  if (unit == "mrad") return 1e-3;
  if (unit == "urad") return 1e-6;
  if (unit == "deg") return units::deg;
  if (unit == "arcsec") return units::arcsec;
  return std::nullopt;
}

std::optional<RateUnit> rate_unit(std::string_view unit) {
  if (unit == "deg/h") return RateUnit{"deg/h", units::deg_per_h, "arcsec"};
  if (unit == "deg/s") return RateUnit{"deg/s", units::deg, "deg"};
  if (unit == "rad/s") return RateUnit{"rad/s", 1.0, "rad"};
  return std::nullopt;
}

}  // namespace gyrochar
