// The names of the protocol's enumerations (what the decoder and the tools print), and where each
// fit parameter sits among the IEEE-952 parameter pages (docs/protocol.md).
#include "gyrochar/wire/protocol.hpp"

namespace gyrochar::protocol {

const char* name(ProtocolError e) {
  switch (e) {
    case ProtocolError::none: return "none";
    case ProtocolError::error_frame: return "error_frame";
    case ProtocolError::not_extended: return "not_extended";
    case ProtocolError::fd_frame: return "fd_frame";
    case ProtocolError::unknown_id: return "unknown_id";
    case ProtocolError::bad_address: return "bad_address";
    case ProtocolError::wrong_length: return "wrong_length";
    case ProtocolError::unknown_page: return "unknown_page";
    case ProtocolError::reserved_bits: return "reserved_bits";
    case ProtocolError::out_of_range: return "out_of_range";
  }
  return "invalid";
}

const char* name(NoiseType t) {
  switch (t) {
    case NoiseType::not_identified: return "not_identified";
    case NoiseType::white_pm: return "white_pm";
    case NoiseType::flicker_pm: return "flicker_pm";
    case NoiseType::white_fm: return "white_fm";
    case NoiseType::flicker_fm: return "flicker_fm";
    case NoiseType::random_walk_fm: return "random_walk_fm";
    case NoiseType::flicker_walk_fm: return "flicker_walk_fm";
    case NoiseType::random_run_fm: return "random_run_fm";
  }
  return "invalid";
}

const char* name(NodeState s) {
  switch (s) {
    case NodeState::starting: return "starting";
    case NodeState::running: return "running";
    case NodeState::input_lost: return "input_lost";
  }
  return "invalid";
}

const char* name(AngleUnit u) {
  switch (u) {
    case AngleUnit::pulse: return "pulse";
    case AngleUnit::rad: return "rad";
    case AngleUnit::urad: return "urad";
    case AngleUnit::deg: return "deg";
    case AngleUnit::arcsec: return "arcsec";
  }
  return "invalid";
}

const char* name(InputSource s) {
  switch (s) {
    case InputSource::unknown: return "unknown";
    case InputSource::gpio_quadrature: return "gpio_quadrature";
    case InputSource::strobe_counter: return "strobe_counter";
    case InputSource::can_counter: return "can_counter";
    case InputSource::simulated: return "simulated";
  }
  return "invalid";
}

const char* name(Ieee952Status s) {
  switch (s) {
    case Ieee952Status::ok: return "ok";
    case Ieee952Status::too_few_points: return "too_few_points";
    case Ieee952Status::rejected: return "rejected";
    case Ieee952Status::singular: return "singular";
  }
  return "invalid";
}

const char* name(FitParameter p) {
  switch (p) {
    case FitParameter::markov_sigma: return "markov_sigma";
    case FitParameter::markov_tc: return "markov_tc";
    case FitParameter::filter_tf: return "filter_tf";
    case FitParameter::sinusoid_amplitude: return "sinusoid_amplitude";
    case FitParameter::sinusoid_frequency: return "sinusoid_frequency";
  }
  return "invalid";
}

FitParameterSlot fit_parameter_slot(std::size_t k) {
  if (k < 2 * wire_markov_terms)
    return {k % 2 == 0 ? FitParameter::markov_sigma : FitParameter::markov_tc, static_cast<std::uint8_t>(k / 2)};
  if (k == 2 * wire_markov_terms) return {FitParameter::filter_tf, 0};
  k -= 2 * wire_markov_terms + 1;
  return {k % 2 == 0 ? FitParameter::sinusoid_amplitude : FitParameter::sinusoid_frequency,
          static_cast<std::uint8_t>(k / 2)};
}

std::size_t fit_parameter_position(FitParameter parameter, std::uint8_t index) {
  for (std::size_t k = 0; k < fit_parameter_pages; ++k) {
    const FitParameterSlot s = fit_parameter_slot(k);
    if (s.parameter == parameter && s.index == index) return k;
  }
  return fit_parameter_pages;
}

const char* name(Ieee952Term t) {
  switch (t) {
    case Ieee952Term::quantization: return "Q_quantization";
    case Ieee952Term::angle_random_walk: return "N_angle_random_walk";
    case Ieee952Term::bias_instability: return "B_bias_instability";
    case Ieee952Term::rate_random_walk: return "K_rate_random_walk";
    case Ieee952Term::rate_ramp: return "R_rate_ramp";
  }
  return "invalid";
}

}  // namespace gyrochar::protocol
