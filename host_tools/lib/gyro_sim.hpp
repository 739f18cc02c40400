#pragma once
// A simulated ring laser gyro with known IEEE Std 952 parameters, streaming in constant memory:
// pulse counts per tau0 interval from the true angle of
//   earth/input rate + angle random walk N + rate random walk K + rate ramp R
//   + bias instability B + white angle noise Q_extra, quantized by the pulse weight (which adds
//   quantization noise with Q = pulse_weight / sqrt(12)) and an optional sinusoidal dither.
// The fractional pulse is carried over, so no angle is ever lost: the sum of the counts equals
// floor(total angle / pulse weight).
// Bias instability is flicker rate noise, S(f) = B^2 / (pi f) one-sided (AVAR floor (2 ln 2 / pi)
// B^2), made in constant memory as a sum of first-order Markov processes with corner frequencies
// an octave apart from 1/(2 pi bias_time_s) up to the Nyquist frequency, each of variance
// B^2 ln 2 / pi: their spectra add up to B^2 / (pi f) within a few percent inside that band.
#include <cstdint>
#include <random>
#include <vector>

namespace gyrochar {

struct GyroParameters {
  double tau0_s = 0.01;
  double pulse_weight_rad = 4.8481368110953599e-6;  // 1 arcsec
  double rate_rad_s = 7.2921159e-5;                 // earth rate
  double q_rad = 0.0;                               // white angle noise beyond quantization
  double n_rad_sqrt_s = 0.0;                        // angle random walk
  double k_rad_s_sqrt_s = 0.0;                      // rate random walk
  double r_rad_s2 = 0.0;                            // rate ramp
  double b_rad_s = 0.0;                             // bias instability
  double bias_time_s = 1e5;                         // longest correlation time of the flicker band
  double dither_amplitude_rad = 0.0;
  double dither_frequency_hz = 0.0;
  std::uint64_t seed = 1;
};

/// Unit conversions for gyro people (value in the named unit -> SI).
namespace units {
inline constexpr double pi = 3.14159265358979323846;
inline constexpr double arcsec = pi / (180.0 * 3600.0);        // rad
inline constexpr double deg_per_h = pi / 180.0 / 3600.0;       // rad/s
inline constexpr double deg_per_sqrt_h = pi / 180.0 / 60.0;    // rad/s^0.5
inline constexpr double deg_per_h_sqrt_h = pi / 180.0 / 3600.0 / 60.0;  // rad/s^1.5
inline constexpr double deg_per_h_per_h = pi / 180.0 / 3600.0 / 3600.0;  // rad/s^2
}  // namespace units

class GyroSimulator {
 public:
  explicit GyroSimulator(const GyroParameters& p);
  /// Pulses in the next tau0 interval. O(1), no allocation.
  std::int64_t next_count();
  /// True angle (rad) at the end of the last interval, without the white angle noise and dither.
  double angle_rad() const { return angle_; }

 private:
  GyroParameters p_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};
  std::uint64_t k_ = 0;
  double angle_ = 0.0;         // integrated rate (rad)
  double rrw_rate_ = 0.0;      // rate random walk state (rad/s)
  struct Markov {
    double decay = 0, drive = 0, state = 0;
  };
  std::vector<Markov> flicker_;  // bias instability processes
  std::int64_t pulses_ = 0;    // pulses emitted so far
};

}  // namespace gyrochar
