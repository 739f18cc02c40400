#include "display_units.hpp"

namespace gyrochar::decoding {

using namespace protocol;

std::optional<double> wire_per_si(const NodeView& node) {
  if (!node.scale) return std::nullopt;
  const std::optional<double> rad = angle_unit_rad(name(node.scale->angle_unit));  // none for pulses
  if (!rad) return std::nullopt;
  return 1.0 / *rad;
}

Units units_for(const NodeView& node, const DisplayRate& choice) {
  Units u;
  if (!node.scale) {
    u.rate_name = "unknown";
    u.ieee_name.fill("unknown");
    return u;
  }
  u.known = true;
  const AngleUnit angle = node.scale->angle_unit;
  const std::optional<double> si_per_wire = angle_unit_rad(name(angle));
  u.pulses = !si_per_wire;
  if (u.pulses || !choice) {
    const std::string a = name(angle);
    u.rate_name = a + "/s";
    u.ieee_name = {a, a + "/sqrt(s)", a + "/s", a + "/s/sqrt(s)", a + "/s/s"};
    return u;
  }
  u.rate_name = choice->name;
  u.rate = *si_per_wire / choice->rad_per_s;
  for (std::size_t k = 0; k < 5; ++k) {
    u.ieee_name[k] = units::ieee952[k].name;
    u.ieee[k] = *si_per_wire / units::ieee952[k].si;
  }
  return u;
}

}  // namespace gyrochar::decoding
