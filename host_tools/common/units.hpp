#pragma once
// Units for gyro people, written once for every host tool: angles, rates and the IEEE Std 952
// parameters, each as the size of the named unit in SI (rad, s). Lookups by name are O(1) and
// allocate nothing.
#include <array>
#include <numbers>
#include <optional>
#include <string_view>

namespace gyrochar {

namespace units {
inline constexpr double pi = std::numbers::pi;
inline constexpr double deg = pi / 180.0;                         // rad
inline constexpr double arcsec = deg / 3600.0;                    // rad
inline constexpr double deg_per_h = deg / 3600.0;                 // rad/s
inline constexpr double deg_per_sqrt_h = deg / 60.0;              // rad/s^0.5 (sqrt(3600 s) = 60 s^0.5)
inline constexpr double deg_per_h_sqrt_h = deg / 3600.0 / 60.0;   // rad/s^1.5
inline constexpr double deg_per_h_per_h = deg / 3600.0 / 3600.0;  // rad/s^2

/// An IEEE-952 parameter in the unit gyro people use: its letter, the unit's name and size in SI.
struct Ieee952Unit {
  const char* letter;
  const char* name;
  double si;
};
/// Q, N, B, K, R (the order of protocol::Ieee952Term): Q in arcsec (rad), N in deg/sqrt(h)
/// (rad/s^0.5), B in deg/h (rad/s), K in deg/h/sqrt(h) (rad/s^1.5), R in deg/h/h (rad/s^2).
inline constexpr std::array<Ieee952Unit, 5> ieee952{{{"Q", "arcsec", arcsec},
                                                     {"N", "deg/sqrt(h)", deg_per_sqrt_h},
                                                     {"B", "deg/h", deg_per_h},
                                                     {"K", "deg/h/sqrt(h)", deg_per_h_sqrt_h},
                                                     {"R", "deg/h/h", deg_per_h_per_h}}};
}  // namespace units

/// Size in rad of an angle unit: rad, mrad, urad, deg, arcsec; empty for anything else.
std::optional<double> angle_unit_rad(std::string_view unit);

struct RateUnit {
  const char* name = "rad/s";
  double rad_per_s = 1.0;     // size of the unit
  const char* angle = "rad";  // the unit times 1 s, for TDEV
};
/// A rate unit: deg/h, deg/s, rad/s; empty for anything else.
std::optional<RateUnit> rate_unit(std::string_view unit);

}  // namespace gyrochar
