#pragma once
// The gyroscope's part of a Kalibr imu.yaml (the IMU noise file of ETH Zurich's Kalibr, read by
// ROS camera-IMU and IMU calibration tools), from an IEEE-952 fit. The conversion is an identity
// of units, no factor:
//   gyroscope_noise_density = N, the angle random walk: white rate noise whose AVAR is N^2 / tau;
//     Kalibr's continuous-time density sigma_g [rad/s/sqrt(Hz)] gives a sample of period dt the
//     standard deviation sigma_g / sqrt(dt), and such samples have AVAR sigma_g^2 / tau: sigma_g = N,
//     and rad/s/sqrt(Hz) = rad/s * s^0.5 = rad/s^0.5, N's SI unit.
//   gyroscope_random_walk = K, the rate random walk: a Brownian rate whose increments over dt have
//     the variance K^2 dt has AVAR K^2 tau / 3 (IEEE Std 952); Kalibr's bias random walk sigma_bg
//     [rad/s^2/sqrt(Hz)] is that diffusion: sigma_bg = K, rad/s^2/sqrt(Hz) = rad/s^1.5.
//   update_rate = 1 / tau0 [Hz].
// So N = 0.003 deg/sqrt(h) is 0.003 (pi/180) / 60 = 8.7266e-7 rad/s/sqrt(Hz), and
// K = 0.01 deg/h/sqrt(h) is 0.01 (pi/180) / 3600 / 60 = 8.0802e-10 rad/s^2/sqrt(Hz).
// gyrochar measures no accelerometer: the file says so, and its accelerometer keys are left for
// the user to fill from the accelerometer's own characterization (Kalibr needs them).
#include <optional>
#include <string>
#include <string_view>

namespace gyrochar {

/// One fitted IEEE-952 term in SI (N: rad/s^0.5, K: rad/s^1.5).
struct KalibrTerm {
  double value_si = 0.0;
  double rel_uncertainty = 0.0;  // standard uncertainty / value
  bool fitted = false;           // in the fitted model
  bool resolved = false;         // significant (else the fit's value is an upper-bound reading)
};

/// The imu.yaml text for N and K at `update_rate_hz`, with `origin` (what was fitted) in its first
/// comment line. Nothing, and `why`, when N or K is not in the fitted model or not a positive
/// finite number (Kalibr needs both > 0), or the rate is not. With `partial`, one term not in the
/// fitted model is written as the accelerometer keys are, commented out with '?' for the user to
/// fill in (Kalibr refuses the file until then), and `why` says which: a note, the text is
/// returned. O(1); allocates the text.
std::optional<std::string> kalibr_imu_yaml(const KalibrTerm& n, const KalibrTerm& k, double update_rate_hz,
                                           std::string_view origin, std::string& why, bool partial = false);

}  // namespace gyrochar
