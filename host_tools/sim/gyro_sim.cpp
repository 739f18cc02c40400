#include "gyro_sim.hpp"

#include <cmath>

namespace gyrochar {

GyroSimulator::GyroSimulator(const GyroParameters& p)
    : p_(p),
      rng_(p.seed),
      arw_step_rad_(p.n_rad_sqrt_s * std::sqrt(p.tau0_s)),
      rrw_step_rad_s_(p.k_rad_s_sqrt_s * std::sqrt(p.tau0_s)) {
  if (p.b_rad_s > 0) {
    // Each process: variance sigma^2 = B^2 ln 2 / pi, AR(1) coefficient exp(-2 pi f tau0), the
    // exact sampling of an Ornstein-Uhlenbeck rate with corner f; started in its stationary state.
    // Octave spacing: sum_i (2 sigma^2 / (pi f_i)) / (1 + (f / f_i)^2) = sigma^2 / (f ln 2) in
    // the band (Poisson summation: the first ripple term is 2 sech(pi^2 / ln 2) = 3e-6).
    const double sigma = p.b_rad_s * std::sqrt(std::log(2.0) / units::pi);
    const double lowest_hz = 1.0 / (2.0 * units::pi * p.bias_time_s);
    for (double f = flicker_top_corner / p.tau0_s;; f *= 0.5) {
      const double decay = std::exp(-2.0 * units::pi * f * p.tau0_s);
      flicker_.push_back({decay, sigma * std::sqrt(1.0 - decay * decay), sigma * normal_(rng_), f});
      if (f <= lowest_hz) break;
    }
  }
}

std::vector<double> GyroSimulator::flicker_corners_hz() const {
  std::vector<double> f;
  for (auto it = flicker_.rbegin(); it != flicker_.rend(); ++it) f.push_back(it->corner_hz);
  return f;
}

void GyroSimulator::retune(const GyroParameters& p) {
  p_.rate_rad_s = p.rate_rad_s;
  p_.q_rad = p.q_rad;
  p_.n_rad_sqrt_s = p.n_rad_sqrt_s;
  p_.k_rad_s_sqrt_s = p.k_rad_s_sqrt_s;
  arw_step_rad_ = p.n_rad_sqrt_s * std::sqrt(p_.tau0_s);
  rrw_step_rad_s_ = p.k_rad_s_sqrt_s * std::sqrt(p_.tau0_s);
}

std::int64_t GyroSimulator::next_count() {
  const double dt = p_.tau0_s;
  const double t_mid = (static_cast<double>(k_) + 0.5) * dt;
  ++k_;
  double bias = 0.0;
  for (Markov& m : flicker_) {
    m.state = m.decay * m.state + m.drive * normal_(rng_);
    bias += m.state;
  }
  // Rate held over this interval: input + ramp (R t_mid dt is the exact integral of R t) + rate
  // random walk + bias instability; angle random walk adds white rate noise of density N.
  const double rate = p_.rate_rad_s + p_.r_rad_s2 * t_mid + rrw_rate_ + bias;
  angle_ += rate * dt + arw_step_rad_ * normal_(rng_);
  // Rate random walk, integrated exactly: with W a Brownian motion over the interval,
  // W(dt) = sqrt(dt) z1 and integral_0^dt W = dt^1.5 (z1 / 2 + z2 / sqrt(12)) (variances dt and
  // dt^3 / 3, covariance dt^2 / 2). Sampled at t_k the angle is then the continuous-time process,
  // whose AVAR is K^2 tau / 3 at every tau (a rate held over the interval would give
  // K^2 tau / 3 (1 + 1 / (2 m^2))). z2 is drawn only when K > 0, so runs without rate random walk
  // keep the random stream they always had.
  const double z1 = normal_(rng_);
  if (rrw_step_rad_s_ != 0) {
    const double z2 = normal_(rng_);
    angle_ += rrw_step_rad_s_ * dt * (0.5 * z1 + z2 / std::sqrt(12.0));
  }
  rrw_rate_ += rrw_step_rad_s_ * z1;
  double observed = angle_ + p_.q_rad * normal_(rng_);
  if (p_.dither_amplitude_rad != 0)
    observed += p_.dither_amplitude_rad * std::sin(2.0 * units::pi * p_.dither_frequency_hz * static_cast<double>(k_) * dt);
  const auto total = static_cast<std::int64_t>(std::floor(observed / p_.pulse_weight_rad));
  const std::int64_t count = total - pulses_;
  pulses_ = total;
  return count;
}

}  // namespace gyrochar
