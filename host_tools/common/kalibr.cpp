#include "kalibr.hpp"

#include <fmt/format.h>

#include <cmath>

#include "units.hpp"

namespace gyrochar {

namespace {

// "N = 0.003 deg/sqrt(h) +- 2.1 %", with the fit's word on a term it did not resolve.
std::string term_comment(const KalibrTerm& t, std::size_t k) {
  const units::Ieee952Unit& u = units::ieee952[k];
  std::string s = fmt::format("{} = {:.4g} {} +- {:.2g} %", u.letter, t.value_si / u.si, u.name, 100.0 * t.rel_uncertainty);
  if (!t.resolved) s += " (not resolved: the fit's value, an upper-bound reading)";
  return s;
}

// The key of one gyroscope term: its value with the comment in gyro units or, not in the fitted
// model (partial), the placeholder of the accelerometer keys.
std::string term_line(const char* key, const char* unit, const KalibrTerm& t, std::size_t k) {
  if (!t.fitted)
    return fmt::format(
        "#{}: ?   # {}; {} is not in the fitted model: fill it in (from a longer record, or the "
        "data sheet)\n",
        key, unit, units::ieee952[k].letter);
  return fmt::format("{}: {}   # {}; {}\n", key, t.value_si, unit, term_comment(t, k));
}

}  // namespace

std::optional<std::string> kalibr_imu_yaml(const KalibrTerm& n, const KalibrTerm& k, double update_rate_hz,
                                           std::string_view origin, std::string& why, bool partial) {
  why.clear();
  if (!n.fitted && !k.fitted) partial = false;  // nothing to give
  for (const auto& [term, letter] : {std::pair{&n, "N (angle random walk)"}, std::pair{&k, "K (rate random walk)"}}) {
    if (!term->fitted && partial) {
      why = fmt::format(
          "{} is not in the fitted model: its key is written commented out with '?' for you to fill "
          "in (Kalibr needs it > 0)",
          letter);
      continue;
    }
    if (!term->fitted) {
      why = fmt::format("{} is not in the fitted model: Kalibr needs it > 0", letter);
      return std::nullopt;
    }
    if (!(term->value_si > 0) || !std::isfinite(term->value_si)) {
      why = fmt::format("{} = {} is not a positive number: Kalibr needs it > 0", letter, term->value_si);
      return std::nullopt;
    }
  }
  if (!(update_rate_hz > 0) || !std::isfinite(update_rate_hz)) {
    why = "the sample rate (1 / tau0) is not known";
    return std::nullopt;
  }
  return fmt::format(
      "# Kalibr IMU noise parameters of the gyroscope, from gyrochar's IEEE-952 fit of {}.\n"
      "# gyroscope_noise_density = N, gyroscope_random_walk = K, in SI: 1 rad/s/sqrt(Hz) = 1 rad/s^0.5,\n"
      "# 1 rad/s^2/sqrt(Hz) = 1 rad/s^1.5 (continuous-time densities); update_rate = 1 / tau0.\n"
      "# gyrochar measures no accelerometer: fill in the two accelerometer keys from the\n"
      "# accelerometer's own characterization before giving this file to Kalibr.\n"
      "#accelerometer_noise_density: ?   # m/s^2/sqrt(Hz)\n"
      "#accelerometer_random_walk: ?     # m/s^3/sqrt(Hz)\n"
      "{}{}"
      "update_rate: {}   # Hz\n"
      "rostopic: /imu0   # the IMU's ROS topic: change to yours\n",
      origin, term_line("gyroscope_noise_density", "rad/s/sqrt(Hz)", n, 1),
      term_line("gyroscope_random_walk", "rad/s^2/sqrt(Hz)", k, 3), update_rate_hz);
}

}  // namespace gyrochar
