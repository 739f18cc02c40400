#include "display_units.hpp"

#include <fmt/format.h>

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

std::optional<std::string> kalibr_yaml(const NodeView& node, std::string& why) {
  const std::optional<double> to_wire = wire_per_si(node);
  if (!to_wire) {
    why = node.scale ? "the node reports pulses: no angle to give Kalibr" : "the node's angle unit has not arrived";
    return std::nullopt;
  }
  if (!node.sampling) {
    why = "the node's tau0 has not arrived";
    return std::nullopt;
  }
  if (node.ieee952_summary && node.ieee952_summary->status != Ieee952Status::ok) {
    why = fmt::format("the node's IEEE-952 fit is {}: no noise parameters to give", name(node.ieee952_summary->status));
    return std::nullopt;
  }
  const auto term = [&](Ieee952Term t) {
    const Ieee952View& v = node.ieee952[static_cast<std::size_t>(t)];
    return KalibrTerm{static_cast<double>(v.value) / *to_wire, static_cast<double>(v.rel_uncertainty), v.in_model(),
                      v.resolved};
  };
  return kalibr_imu_yaml(term(Ieee952Term::angle_random_walk), term(Ieee952Term::rate_random_walk),
                         static_cast<double>(1.0f / node.sampling->tau0_s),  // the wire carries tau0 as a float32
                         fmt::format("node 0x{:02X} (session {}, {} samples)", node.address, node.session,
                                     node.status.sample_count),
                         why);
}

}  // namespace gyrochar::decoding
