#include "gyro_sim.hpp"

#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace gyrochar {

namespace {

// The Gauss-Markov and sinusoidal terms' stream: the seed's two halves and a tag, through
// std::seed_seq, so that it shares no state with the first stream (seeded with the seed itself).
std::mt19937_64 terms_stream(std::uint64_t seed) {
  constexpr std::uint32_t tag = 0x6d61726b;  // "mark"
  std::seed_seq seq{static_cast<std::uint32_t>(seed), static_cast<std::uint32_t>(seed >> 32), tag};
  return std::mt19937_64(seq);
}

}  // namespace

GyroSimulator::Markov GyroSimulator::Markov::stationary(double sigma, double decay, double one_minus_decay2, double z,
                                                        double corner_hz) {
  return {decay, sigma * std::sqrt(one_minus_decay2), sigma * z, corner_hz};
}

GyroSimulator::GyroSimulator(const GyroParameters& p)
    : p_(p),
      rng_(p.seed),
      arw_step_rad_(p.n_rad_sqrt_s * std::sqrt(p.tau0_s)),
      rrw_step_rad_s_(p.k_rad_s_sqrt_s * std::sqrt(p.tau0_s)),
      terms_rng_(terms_stream(p.seed)) {
  if (p.b_rad_s > 0) {
    // Each process: variance sigma^2 = B^2 ln 2 / pi, AR(1) coefficient exp(-2 pi f tau0), the
    // exact sampling of an Ornstein-Uhlenbeck rate with corner f; started in its stationary state.
    // Octave spacing: sum_i (2 sigma^2 / (pi f_i)) / (1 + (f / f_i)^2) = sigma^2 / (f ln 2) in
    // the band (Poisson summation: the first ripple term is 2 sech(pi^2 / ln 2) = 3e-6).
    const double sigma = p.b_rad_s * std::sqrt(std::log(2.0) / units::pi);
    const double lowest_hz = 1.0 / (2.0 * units::pi * p.bias_time_s);
    for (double f = flicker_top_corner / p.tau0_s;; f *= 0.5) {
      const double decay = std::exp(-2.0 * units::pi * f * p.tau0_s);
      const double z = normal_(rng_);
      flicker_.push_back(Markov::stationary(sigma, decay, 1.0 - decay * decay, z, f));
      if (f <= lowest_hz) break;
    }
  }
  // From the terms' own stream, in this order: each Gauss-Markov term's starting rate, then each
  // sinusoid's phase.
  for (const MarkovRate& m : p.markov) {  // 1 - phi^2 from expm1: accurate also when Tc spans many samples
    const double a = p.tau0_s / m.tc_s, z = terms_normal_(terms_rng_);
    markov_.push_back(
        Markov::stationary(m.sigma_rad_s, std::exp(-a), -std::expm1(-2.0 * a), z, 1.0 / (2.0 * units::pi * m.tc_s)));
  }
  std::uniform_real_distribution<double> phase(0.0, 2.0 * units::pi);
  for (const SinusoidRate& s : p.sinusoids) {
    const double half_cycle = units::pi * s.frequency_hz * p.tau0_s;  // pi f tau0
    sinusoids_.push_back({s.amplitude_rad_s * std::sin(half_cycle) / half_cycle,
                          static_cast<long double>(s.frequency_hz) * p.tau0_s, phase(terms_rng_)});
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
  const std::uint64_t interval = k_++;  // this interval is (interval tau0, (interval + 1) tau0]
  const double t_mid = (static_cast<double>(interval) + 0.5) * dt;
  // Bias instability, then the Gauss-Markov terms (their own stream), then the sinusoids' mean
  // rate over this interval, (A sin(pi f tau0) / (pi f tau0)) sin(2 pi f t_mid + phi0): the exact
  // integral of the sinusoid divided by tau0. With no such terms nothing is added.
  double correlated = 0.0;
  for (Markov& m : flicker_) correlated += m.step(normal_(rng_));
  for (Markov& m : markov_) correlated += m.step(terms_normal_(terms_rng_));
  for (const Sinusoid& s : sinusoids_) {
    const long double cycles = (static_cast<long double>(interval) + 0.5L) * s.cycles_per_sample;
    const double fraction = static_cast<double>(cycles - std::floor(cycles));  // the phase modulo a cycle
    correlated += s.mean_amplitude_rad_s * std::sin(2.0 * units::pi * fraction + s.phase_rad);
  }
  // Rate held over this interval: input + ramp (R t_mid dt is the exact integral of R t) + rate
  // random walk + bias instability + Gauss-Markov + sinusoids; angle random walk adds white rate
  // noise of density N.
  const double rate = p_.rate_rad_s + p_.r_rad_s2 * t_mid + rrw_rate_ + correlated;
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
  const double pulses = std::floor(observed / p_.pulse_weight_rad);
  if (!(std::fabs(pulses) <= max_pulse_total)) {
    char why[160];
    std::snprintf(why, sizeof why,
                  "sample %llu: the angle reached %.4g pulses, beyond the simulator's 2^53 (counts "
                  "exact in a double)",
                  static_cast<unsigned long long>(k_), pulses);
    throw std::overflow_error(why);
  }
  const auto total = static_cast<std::int64_t>(pulses);
  const std::int64_t count = total - pulses_;
  pulses_ = total;
  return count;
}

}  // namespace gyrochar
