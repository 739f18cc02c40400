#pragma once
// A simulated ring laser gyro with known IEEE Std 952 parameters, streaming in constant memory:
// pulse counts per tau0 interval. Sample k (k = 1, 2, ...) ends at t_k = k tau0; over the interval
// (t_{k-1}, t_k] the simulator adds, exactly as written (docs/metrology.md, "The simulator and its
// conventions", derives each term's Allan deviation and the measured agreement):
//   input rate + rate ramp:   (rate + R t_mid) tau0, t_mid = (k - 1/2) tau0 (exact integral of R t)
//   angle random walk N:      N sqrt(tau0) z                        (white rate noise of density N)
//   rate random walk K:       the exact integral of a Brownian rate of diffusion K over the
//                             interval: the rate held at the start times tau0, plus
//                             K tau0^1.5 (z1 / 2 + z2 / sqrt(12)); the rate then steps by
//                             K sqrt(tau0) z1 (the same z1)
//   bias instability B:       sum_i s_i tau0, each s_i a first-order Gauss-Markov (AR(1)) rate
//                             updated at the start of the interval and held over it
//   Gauss-Markov rate terms:  y tau0 for each term (sigma, Tc): the AR(1) rate
//                             y_k = phi y_{k-1} + sigma sqrt(1 - phi^2) e_k, phi = exp(-tau0 / Tc),
//                             y_0 ~ N(0, sigma^2) (stationary from the start), updated at the
//                             start of the interval and held over it: sigma is the stationary
//                             standard deviation of the interval's mean rate
//   sinusoidal rate terms:    the exact integral of A sin(2 pi f t + phi0) over the interval,
//                             (A sin(pi f tau0) / (pi f)) sin(2 pi f t_mid + phi0), phi0 uniform
//                             in [0, 2 pi)
// and observes, at t_k, angle + white angle noise q z + dither A sin(2 pi f t_k). The count is
// floor(observed / pulse weight) minus the same at t_{k-1} (0 at t_0 = 0): the fractional pulse
// is carried over, so no angle is ever lost. The quantization error (the fractional pulse) is a
// white angle noise of Q = pulse_weight / sqrt(12) only when the fraction at the sample instants
// is randomized (random angle increments of about a pulse or more per sample); a steady rate below
// a pulse per sample gives a periodic pattern instead (docs/metrology.md).
// Bias instability is flicker rate noise, one-sided S(f) = B^2 / (pi f) (AVAR floor
// (2 ln 2 / pi) B^2, ADEV 0.664 B), made as a sum of AR(1) rates with corner frequencies an octave
// apart, from f_top = flicker_top_corner / tau0 down to the first corner at or below
// 1 / (2 pi bias_time_s), each of variance B^2 ln 2 / pi and coefficient exp(-2 pi f_i tau0).
// Inside the band the octave sum of Lorentzians equals B^2 / (pi f) to a few parts per million.
// Anchoring the top corner at a fixed fraction of the sample rate makes the short-tau edge the
// same for every bias_time: the ADEV floor holds within 0.3 % from 4 tau0 up to 0.017 bias_time_s
// and within 1 % up to 0.059 bias_time_s (+10.5 % at tau0, +2.6 % at 2 tau0); docs/metrology.md
// has the figures.
// z, z1, z2 and the flicker processes' innovations are independent standard normal draws from one
// std::mt19937_64 seeded with `seed`: a run is reproducible. The Gauss-Markov and sinusoidal terms
// draw from a second std::mt19937_64 (seeded with `seed` and a tag through std::seed_seq) with its
// own normal distribution (a distribution caches its second value, so sharing one would shift the
// first stream): adding them leaves every other term's draws, and the counts of a run without
// them, exactly as they were. docs/metrology.md and tests/oracle/sim_closed_forms.hpp give their AVAR and MVAR.
#include <cstdint>
#include <random>
#include <vector>

#include "units.hpp"  // units:: conversions for the parameters

namespace gyrochar {

/// The largest pulse total (the observed angle in pulses, at any sample) the simulator counts:
/// 2^53, up to which a double holds every whole pulse, so no count is rounded (and far inside the
/// int64 range of the counts). check_parameters (sim_truth.hpp) refuses runs that could pass it;
/// next_count throws rather than emit a count beyond it.
inline constexpr double max_pulse_total = 0x1p53;

/// Top corner of the flicker band times tau0 (0.34 / tau0, below the Nyquist frequency 0.5 / tau0):
/// the value that keeps the ADEV floor flattest from 4 tau0 on (docs/metrology.md).
inline constexpr double flicker_top_corner = 0.34;

/// A first-order Gauss-Markov (exponentially correlated) rate: stationary standard deviation
/// sigma (rad/s) and correlation time tc (s); the simulator's convention is in the header comment.
struct MarkovRate {
  double sigma_rad_s = 0;
  double tc_s = 0;
  bool operator==(const MarkovRate&) const = default;
};

/// A sinusoidal rate of amplitude (rad/s) and frequency (Hz); its phase is drawn from the seed.
struct SinusoidRate {
  double amplitude_rad_s = 0;
  double frequency_hz = 0;
  bool operator==(const SinusoidRate&) const = default;
};

struct GyroParameters {
  double tau0_s = 0.01;
  double pulse_weight_rad = 4.8481368110953599e-6;  // 1 arcsec
  double rate_rad_s = 7.2921159e-5;                 // earth rate
  double q_rad = 0.0;                               // white angle noise beyond quantization
  double n_rad_sqrt_s = 0.0;                        // angle random walk
  double k_rad_s_sqrt_s = 0.0;                      // rate random walk
  double r_rad_s2 = 0.0;                            // rate ramp
  double b_rad_s = 0.0;                             // bias instability
  double bias_time_s = 1e5;                         // the flicker band reaches down to 1/(2 pi bias_time_s)
  double dither_amplitude_rad = 0.0;
  double dither_frequency_hz = 0.0;
  std::uint64_t seed = 1;
  std::vector<MarkovRate> markov;       // Gauss-Markov rates: tc_s > 0, sigma_rad_s >= 0
  std::vector<SinusoidRate> sinusoids;  // sinusoidal rates: 0 < frequency_hz < 1 / (2 tau0)
};

class GyroSimulator {
 public:
  /// Allocates the flicker processes (one per octave of the band, a few dozen at most) and one
  /// state per Gauss-Markov and sinusoidal term; nothing afterwards. Expects tau0_s > 0, pulse_weight_rad > 0 and bias_time_s > tau0_s when b_rad_s > 0
  /// (gyrochar-sim checks its options; see check_parameters in sim_truth.hpp).
  explicit GyroSimulator(const GyroParameters& p);
  /// Pulses in the next tau0 interval. O(flicker processes + terms), no allocation. Throws
  /// std::overflow_error, saying at which sample, when the observed angle is not finite or beyond
  /// max_pulse_total pulses: never a wrapped or rounded count.
  std::int64_t next_count();
  /// From the next interval on: the input rate, white angle noise, angle random walk and rate random
  /// walk of `p` (its other parameters are ignored). The angle, the rate random walk's rate, the
  /// flicker states and the Gauss-Markov and sinusoidal terms carry over: the change is a step of
  /// the levels, nothing restarts. O(1).
  void retune(const GyroParameters& p);
  /// True angle (rad) at the end of the last interval, without the white angle noise and dither.
  double angle_rad() const { return angle_; }
  /// Corner frequencies of the flicker band's processes (Hz), lowest first; empty when B is 0. Allocates.
  std::vector<double> flicker_corners_hz() const;

 private:
  GyroParameters p_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};
  std::uint64_t k_ = 0;
  double angle_ = 0.0;           // integrated rate (rad)
  double rrw_rate_ = 0.0;        // rate random walk state (rad/s)
  double arw_step_rad_ = 0.0;    // N sqrt(tau0)
  double rrw_step_rad_s_ = 0.0;  // K sqrt(tau0)
  // A stationary AR(1) rate: state = decay state + drive z, started at sigma z.
  struct Markov {
    double decay = 0, drive = 0, state = 0, corner_hz = 0;
    static Markov stationary(double sigma, double decay, double one_minus_decay2, double z, double corner_hz);
    double step(double z) { return state = decay * state + drive * z; }
  };
  // A sinusoidal rate's mean over an interval: mean_amplitude sin(2 pi cycles + phase), cycles =
  // (interval index + 1/2) cycles_per_sample, reduced modulo 1 in long double.
  struct Sinusoid {
    double mean_amplitude_rad_s = 0;    // A sin(pi f tau0) / (pi f tau0)
    long double cycles_per_sample = 0;  // f tau0
    double phase_rad = 0;
  };
  std::vector<Markov> flicker_;  // bias instability processes
  std::mt19937_64 terms_rng_;    // the Gauss-Markov and sinusoidal terms' own stream
  std::normal_distribution<double> terms_normal_{0.0, 1.0};
  std::vector<Markov> markov_;       // Gauss-Markov rate terms
  std::vector<Sinusoid> sinusoids_;  // sinusoidal rate terms
  std::int64_t pulses_ = 0;          // pulses emitted so far
};

}  // namespace gyrochar
