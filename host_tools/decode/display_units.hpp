#pragma once
// How gyrochar-decode shows a node's values. Deviations arrive in the node's angle unit A per
// second (metadata AngleUnit); they are shown in the chosen rate unit (units.hpp), the IEEE-952
// terms in gyro units (units::ieee952: Q arcsec, N deg/sqrt(h), B deg/h, K deg/h/sqrt(h),
// R deg/h/h). Nothing is converted from pulses: a node reporting pulses is shown in pulse/s and
// pulse units; with the native choice every node is shown in its own unit. Before a node's
// AngleUnit has arrived its values are shown as sent and the unit is "unknown".
#include <array>
#include <optional>
#include <string>

#include "decoder.hpp"
#include "kalibr.hpp"
#include "units.hpp"

namespace gyrochar::decoding {

/// The rate unit deviations are shown in; empty: "native", each node's own angle unit per second.
using DisplayRate = std::optional<RateUnit>;

/// How the values of one node are shown: displayed value = wire value x factor.
struct Units {
  bool known = false;                                   // the node's AngleUnit has arrived
  bool pulses = false;                                  // the node reports pulses: never converted
  std::string rate_name;                                // "deg/h", "pulse/s", "arcsec/s" (native), "unknown"
  double rate = 1.0;                                    // display rate per (A/s)
  std::array<std::string, 5> ieee_name;                 // units of Q, N, B, K, R
  std::array<double, 5> ieee{1.0, 1.0, 1.0, 1.0, 1.0};  // display value per wire value
};

/// The units of `node` for the rate unit `choice`. O(1); allocates the unit names.
Units units_for(const NodeView& node, const DisplayRate& choice);

/// Wire value (the node's angle unit) per SI value (rad): the same factor for every IEEE-952 term,
/// whose other dimensions are seconds on both sides. Nothing for pulses or an unknown unit. O(1).
std::optional<double> wire_per_si(const NodeView& node);

/// The node's N and K as a Kalibr imu.yaml (kalibr.hpp), converted from its angle unit to SI, at
/// the rate 1 / tau0. Nothing, and why, when the node reports pulses or its angle unit or tau0 has
/// not arrived, its fit was not made or was rejected, or N or K is not in the fitted model. O(1).
std::optional<std::string> kalibr_yaml(const NodeView& node, std::string& why);

}  // namespace gyrochar::decoding
