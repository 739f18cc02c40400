#include "gyro_sim.hpp"

#include <cmath>

namespace gyrochar {

GyroSimulator::GyroSimulator(const GyroParameters& p) : p_(p), rng_(p.seed) {
  if (p.b_rad_s > 0) {
    const double sigma = p.b_rad_s * std::sqrt(std::log(2.0) / units::pi);
    for (double f = 1.0 / (2.0 * units::pi * p.bias_time_s); f < 0.5 / p.tau0_s; f *= 2.0) {
      const double decay = std::exp(-2.0 * units::pi * f * p.tau0_s);
      flicker_.push_back({decay, sigma * std::sqrt(1.0 - decay * decay), sigma * normal_(rng_)});
    }
  }
}

std::int64_t GyroSimulator::next_count() {
  const double dt = p_.tau0_s;
  const double t_mid = (static_cast<double>(k_) + 0.5) * dt;
  ++k_;
  // Rate over this interval: input + ramp + random walk; angle random walk adds white rate noise
  // of density N (angle increment N sqrt(dt)).
  double bias = 0.0;
  for (Markov& m : flicker_) {
    m.state = m.decay * m.state + m.drive * normal_(rng_);
    bias += m.state;
  }
  const double rate = p_.rate_rad_s + p_.r_rad_s2 * t_mid + rrw_rate_ + bias;
  angle_ += rate * dt + p_.n_rad_sqrt_s * std::sqrt(dt) * normal_(rng_);
  rrw_rate_ += p_.k_rad_s_sqrt_s * std::sqrt(dt) * normal_(rng_);
  double observed = angle_ + p_.q_rad * normal_(rng_);
  if (p_.dither_amplitude_rad != 0)
    observed += p_.dither_amplitude_rad * std::sin(2.0 * units::pi * p_.dither_frequency_hz * static_cast<double>(k_) * dt);
  const auto total = static_cast<std::int64_t>(std::floor(observed / p_.pulse_weight_rad));
  const std::int64_t count = total - pulses_;
  pulses_ = total;
  return count;
}

}  // namespace gyrochar
