// The gyrochar CAN codec (docs/protocol.md). Each frame kind has one range check, check(), shared by
// encode (before packing) and decode (after unpacking), so both accept exactly the same values.
#include "gyrochar/wire/protocol.hpp"

#include <algorithm>
#include <bit>
#include <cmath>

namespace gyrochar::protocol {
namespace {

constexpr std::uint8_t report_len = report_frame_len;
constexpr std::uint8_t counter_input_len = 6;
constexpr std::uint32_t id_mask = 0x1FFFFFFF;
constexpr std::uint64_t max_m = std::uint64_t{1} << 40;  // m < 2^40
constexpr unsigned edf_code_bits = 12;
constexpr double edf_codes_per_octave = 64.0;  // log2(edf) = code / 64 - 4; code 0: not available
constexpr double edf_log2_offset = -4.0;
constexpr double rel_uncertainty_step = 1e-4;  // 0.01 %
constexpr std::uint16_t min_report_period_ms = 100;
constexpr std::uint16_t max_report_period_ms = 2000;
constexpr unsigned excluded_code_bits = 5;  // Ieee952 summary: log2 m below which points were left out
constexpr unsigned ieee952_resolved_bit = 8u, ieee952_fitted_bit = 16u;  // Ieee952 term pages, byte 0
constexpr std::uint64_t min_window_length = 4;                           // the shortest window holds an MDEV term at m = 1
constexpr unsigned window_dev_code_bits = 22;
constexpr double window_dev_codes_per_octave = 16384.0;  // log2(dev) = code / 2^14 - 128; code 0: none
constexpr double window_dev_log2_offset = -128.0;
constexpr double uncertainty_codes_per_octave = 256.0;  // Ieee952Unconstrained: log2(u) = code / 256 - 128; 0: none
constexpr double uncertainty_log2_offset = -128.0;

// --- little-endian fields --------------------------------------------------------------------

void put(CanFrame& f, std::size_t offset, std::size_t bytes, std::uint64_t value) {
  for (std::size_t i = 0; i < bytes; ++i) f.data[offset + i] = static_cast<std::uint8_t>(value >> (8 * i));
}
std::uint64_t get(const CanFrame& f, std::size_t offset, std::size_t bytes) {
  std::uint64_t value = 0;
  for (std::size_t i = 0; i < bytes; ++i) value |= std::uint64_t{f.data[offset + i]} << (8 * i);
  return value;
}
void put_float(CanFrame& f, std::size_t offset, float value) { put(f, offset, 4, std::bit_cast<std::uint32_t>(value)); }
float get_float(const CanFrame& f, std::size_t offset) {
  return std::bit_cast<float>(static_cast<std::uint32_t>(get(f, offset, 4)));
}
std::uint64_t saturate(std::uint64_t value, unsigned bits) {
  const std::uint64_t max = (std::uint64_t{1} << bits) - 1;
  return value < max ? value : max;
}
std::uint8_t u8(unsigned value) { return static_cast<std::uint8_t>(value); }
template <class E>
unsigned code(E e) {
  return static_cast<unsigned>(e);
}

CanFrame blank(std::uint32_t base, std::uint8_t node, std::uint8_t len) {
  CanFrame f;
  f.id = frame_id(base, node);
  f.extended = true;
  f.len = len;
  return f;
}

// --- quantized fields ------------------------------------------------------------------------

std::uint16_t edf_code(double edf) {
  if (edf == 0.0) return 0;
  const double c = std::round(edf_codes_per_octave * (std::log2(edf) - edf_log2_offset));
  const double max = double((1u << edf_code_bits) - 1);
  return static_cast<std::uint16_t>(c < 1.0 ? 1.0 : c > max ? max : c);
}
double edf_from_code(unsigned c) { return c == 0 ? 0.0 : std::exp2(c / edf_codes_per_octave + edf_log2_offset); }
std::uint32_t window_dev_code(double dev) {
  if (dev == 0.0) return 0;
  const double c = std::round(window_dev_codes_per_octave * (std::log2(dev) - window_dev_log2_offset));
  const double max = double((1u << window_dev_code_bits) - 1);
  return static_cast<std::uint32_t>(c < 1.0 ? 1.0 : c > max ? max : c);
}
double window_dev_from_code(std::uint32_t c) {
  return c == 0 ? 0.0 : std::exp2(c / window_dev_codes_per_octave + window_dev_log2_offset);
}
std::uint16_t uncertainty_code(double u) {
  if (u == 0.0) return 0;
  const double c = std::round(uncertainty_codes_per_octave * (std::log2(u) - uncertainty_log2_offset));
  return static_cast<std::uint16_t>(c < 1.0 ? 1.0 : c > 65535.0 ? 65535.0 : c);
}
double uncertainty_from_code(unsigned c) {
  return c == 0 ? 0.0 : std::exp2(c / uncertainty_codes_per_octave + uncertainty_log2_offset);
}
std::uint16_t rel_uncertainty_code(double rel) {
  const double c = std::round(rel / rel_uncertainty_step);
  return static_cast<std::uint16_t>(c > 65535.0 ? 65535.0 : c);
}

// --- ranges, shared by encode and decode -----------------------------------------------------

bool nonnegative(double v) { return std::isfinite(v) && v >= 0.0; }
bool positive(double v) { return std::isfinite(v) && v > 0.0; }
constexpr ProtocolError ok_if(bool in_range) { return in_range ? ProtocolError::none : ProtocolError::out_of_range; }

ProtocolError check(const StatusMsg& m) { return ok_if(m.state <= NodeState::input_lost && m.tau_count <= max_taus); }
ProtocolError check(const StatusFaultsMsg&) { return ProtocolError::none; }
ProtocolError check(const TauDevMsg& m) {
  return ok_if(m.tau_index < max_taus && m.kind <= DevKind::mdev && nonnegative(m.dev_angle_per_s) && nonnegative(m.edf) &&
               m.noise <= NoiseType::random_run_fm);
}
ProtocolError check(const TauTermsMsg& m) { return ok_if(m.tau_index < max_taus); }
ProtocolError check(const TauInfoMsg& m) {
  return ok_if(m.tau_index < max_taus && m.m >= 1 && m.m < max_m && m.stride_log2 < 40 &&
               (m.m & ((std::uint64_t{1} << m.stride_log2) - 1)) == 0);
}
ProtocolError check(const MetaSamplingMsg& m) { return ok_if(positive(m.tau0_s) && std::has_single_bit(m.stride_factor)); }
ProtocolError check(const MetaClockMsg& m) { return ok_if(m.protocol_version >= 1); }
ProtocolError check(const MetaScaleMsg& m) {
  return ok_if(positive(m.angle_per_pulse) && m.angle_unit <= AngleUnit::arcsec && m.input_source <= InputSource::simulated);
}
ProtocolError check(const MetaConfigMsg& m) {
  return ok_if(m.report_period_ms >= min_report_period_ms && m.report_period_ms <= max_report_period_ms);
}
ProtocolError check(const Ieee952Msg& m) {
  return ok_if(m.term <= Ieee952Term::rate_ramp && nonnegative(m.value) && !std::isnan(m.rel_uncertainty) &&
               m.rel_uncertainty >= 0.0);
}
ProtocolError check(const Ieee952SummaryMsg& m) {
  const auto [avar, mvar] = m.excluded_below_log2_m;
  constexpr unsigned max_code = (1u << excluded_code_bits) - 1;
  return ok_if(m.status <= Ieee952Status::singular && nonnegative(m.chi2_per_dof) && avar <= max_code && mvar <= max_code &&
               (!m.quantization_white || (avar == 0 && mvar == 0)));
}
ProtocolError check(const WindowMsg& m) {
  return ok_if(m.tau_count >= 1 && m.tau_count < max_taus && (m.complete || (m.window == 0 && m.gaps == 0)));
}
ProtocolError check(const WindowLengthMsg& m) { return ok_if(m.length >= min_window_length && m.length < max_m); }
ProtocolError check(const WindowDevMsg& m) {
  return ok_if(m.tau_index < max_taus && m.window < 16 && nonnegative(m.adev_angle_per_s) &&
               nonnegative(m.mdev_angle_per_s));
}
ProtocolError check(const Ieee952ParameterMsg& m) {
  const std::size_t terms = m.parameter == FitParameter::filter_tf   ? 1
                            : m.parameter <= FitParameter::markov_tc ? wire_markov_terms
                                                                     : wire_sinusoids;
  return ok_if(m.parameter <= FitParameter::sinusoid_frequency && m.index < terms &&
               (!m.resolved || has_resolved(m.parameter)) && nonnegative(m.value) && !std::isnan(m.rel_uncertainty) &&
               m.rel_uncertainty >= 0.0);
}
ProtocolError check(const Ieee952ModelMsg& m) {
  const bool runner_up_blank = m.runner_up_markov == 0 && m.runner_up_sinusoids == 0 && !m.runner_up_bandwidth &&
                               m.criterion_margin == 0.0f;
  return ok_if(m.markov <= wire_markov_terms && m.sinusoids <= wire_sinusoids &&
               m.bandwidth_excluded_below_log2_m < (1u << excluded_code_bits) && m.runner_up_markov <= wire_markov_terms &&
               m.runner_up_sinusoids <= wire_sinusoids && std::isfinite(m.criterion_margin) &&
               (m.runner_up || runner_up_blank));
}
ProtocolError check(const Ieee952UnconstrainedMsg& m) {
  return ok_if(m.term <= Ieee952Term::rate_ramp && std::isfinite(m.value) && nonnegative(m.uncertainty) &&
               (m.uncertainty > 0.0 || m.value == 0.0f));
}
ProtocolError check(const CounterInputMsg&) { return ProtocolError::none; }

// --- encoding --------------------------------------------------------------------------------

/// Checks node and ranges, then packs with `pack` into a fresh frame that replaces `frame`.
template <class Msg, class Pack>
ProtocolError encode_with(const Msg& msg, std::uint8_t node, std::uint32_t base, std::uint8_t len, CanFrame& frame,
                          Pack pack) {
  if (node > max_node_address) return ProtocolError::bad_address;
  if (const ProtocolError e = check(msg); e != ProtocolError::none) return e;
  CanFrame f = blank(base, node, len);
  pack(f);
  frame = f;
  return ProtocolError::none;
}

// Report frames: byte 0 bits 0-1 are the page (multiplexor), byte 1 is seq.
void header(CanFrame& f, unsigned page, unsigned upper_bits, std::uint8_t seq) {
  f.data[0] = u8(page | upper_bits << 2);
  f.data[1] = seq;
}

// --- decoding --------------------------------------------------------------------------------

template <class Msg>
ProtocolError accept(const Msg& msg, Message& out) {
  const ProtocolError e = check(msg);
  if (e == ProtocolError::none) out = msg;
  return e;
}

ProtocolError decode_status(const CanFrame& f, Message& out) {
  const unsigned page = f.data[0] & 3u;
  if (page == 0) {
    if (f.data[0] & 0xF0u) return ProtocolError::reserved_bits;
    StatusMsg m;
    m.seq = f.data[1];
    m.state = static_cast<NodeState>(f.data[0] >> 2 & 3u);
    m.tau_count = f.data[2];
    m.sample_count = get(f, 3, 5);
    return accept(m, out);
  }
  if (page == 1) {
    StatusFaultsMsg m;
    m.seq = f.data[1];
    m.bus_off_events = f.data[0] >> 2u;
    m.lost_edges = static_cast<std::uint32_t>(get(f, 2, 2));
    m.sample_gaps = static_cast<std::uint32_t>(get(f, 4, 2));
    m.tx_dropped_frames = static_cast<std::uint32_t>(get(f, 6, 2));
    return accept(m, out);
  }
  return ProtocolError::unknown_page;
}

ProtocolError decode_tau_stats(const CanFrame& f, Message& out) {
  const unsigned page = f.data[0] & 3u;
  const auto tau_index = u8(f.data[0] >> 2u);
  if (page <= 1) {
    const auto tail = static_cast<unsigned>(get(f, 6, 2));
    TauDevMsg m;
    m.seq = f.data[1];
    m.tau_index = tau_index;
    m.kind = static_cast<DevKind>(page);
    m.dev_angle_per_s = get_float(f, 2);
    m.edf = edf_from_code(tail & 0xFFFu);
    m.noise = static_cast<NoiseType>(tail >> 12 & 7u);
    m.valid = (tail >> 15) != 0;
    return accept(m, out);
  }
  if (page == 2) {
    TauTermsMsg m;
    m.seq = f.data[1];
    m.tau_index = tau_index;
    m.n = get(f, 2, 6);
    return accept(m, out);
  }
  TauInfoMsg m;
  m.seq = f.data[1];
  m.tau_index = tau_index;
  m.m = get(f, 2, 5);
  m.stride_log2 = f.data[7];
  return accept(m, out);
}

ProtocolError decode_metadata(const CanFrame& f, Message& out) {
  if (f.data[0] & 0xFCu) return ProtocolError::reserved_bits;
  switch (f.data[0] & 3u) {
    case 0: {
      MetaSamplingMsg m;
      m.seq = f.data[1];
      m.tau0_s = get_float(f, 2);
      m.stride_factor = static_cast<std::uint16_t>(get(f, 6, 2));
      return accept(m, out);
    }
    case 1: {
      MetaClockMsg m;
      m.seq = f.data[1];
      m.uptime_ms = get(f, 2, 5);
      m.protocol_version = f.data[7];
      return accept(m, out);
    }
    case 2: {
      MetaScaleMsg m;
      m.seq = f.data[1];
      m.angle_per_pulse = get_float(f, 2);
      m.angle_unit = static_cast<AngleUnit>(f.data[6]);
      m.input_source = static_cast<InputSource>(f.data[7]);
      return accept(m, out);
    }
    default: {
      MetaConfigMsg m;
      m.seq = f.data[1];
      m.config_hash = static_cast<std::uint32_t>(get(f, 2, 4));
      m.report_period_ms = static_cast<std::uint16_t>(get(f, 6, 2));
      return accept(m, out);
    }
  }
}

ProtocolError decode_ieee952_model(const CanFrame& f, Message& out) {
  if (f.data[3] & 0xF8u) return ProtocolError::reserved_bits;
  Ieee952ModelMsg m;
  m.seq = f.data[1];
  m.markov = u8(f.data[0] >> 3 & 3u);
  m.sinusoids = u8(f.data[0] >> 5 & 3u);
  m.bandwidth = (f.data[0] & 0x80u) != 0;
  m.bandwidth_excluded_below_log2_m = u8(f.data[2] & 0x1Fu);
  m.runner_up = (f.data[2] & 0x20u) != 0;
  m.runner_up_markov = u8(f.data[2] >> 6);
  m.runner_up_sinusoids = u8(f.data[3] & 3u);
  m.runner_up_bandwidth = (f.data[3] & 4u) != 0;
  m.criterion_margin = get_float(f, 4);
  return accept(m, out);
}

ProtocolError decode_ieee952_parameter(const CanFrame& f, Message& out) {
  Ieee952ParameterMsg m;
  m.seq = f.data[1];
  m.parameter = static_cast<FitParameter>(f.data[0] >> 3 & 7u);
  m.index = u8(f.data[0] >> 6 & 1u);
  m.resolved = (f.data[0] & 0x80u) != 0;
  m.value = get_float(f, 2);
  m.rel_uncertainty = static_cast<double>(get(f, 6, 2)) * rel_uncertainty_step;
  return accept(m, out);
}

ProtocolError decode_ieee952(const CanFrame& f, Message& out) {
  const unsigned page = f.data[0] & 7u;
  if (page == ieee952_model_page) return decode_ieee952_model(f, out);
  if (page == ieee952_parameter_page) return decode_ieee952_parameter(f, out);
  if (page == ieee952_summary_page) {
    Ieee952SummaryMsg m;
    m.seq = f.data[1];
    m.excluded_below_log2_m[0] = u8(f.data[0] >> 3u);
    m.chi2_per_dof = get_float(f, 2);
    m.points = f.data[6];
    m.excluded_below_log2_m[1] = u8(f.data[7] & 0x1Fu);
    m.quantization_white = (f.data[7] & 0x20u) != 0;
    m.status = static_cast<Ieee952Status>(f.data[7] >> 6u);
    return accept(m, out);
  }
  if (page > code(Ieee952Term::rate_ramp)) return ProtocolError::unknown_page;
  if (f.data[0] & 0xE0u) return ProtocolError::reserved_bits;
  Ieee952Msg m;
  m.seq = f.data[1];
  m.term = static_cast<Ieee952Term>(page);
  m.resolved = (f.data[0] & ieee952_resolved_bit) != 0;
  m.fitted = (f.data[0] & ieee952_fitted_bit) != 0;
  m.value = get_float(f, 2);
  m.rel_uncertainty = static_cast<double>(get(f, 6, 2)) * rel_uncertainty_step;
  return accept(m, out);
}

ProtocolError decode_unconstrained(const CanFrame& f, Message& out) {
  const unsigned page = f.data[0] & 7u;
  if (page > code(Ieee952Term::rate_ramp)) return ProtocolError::unknown_page;
  if (f.data[0] & 0xF8u) return ProtocolError::reserved_bits;
  Ieee952UnconstrainedMsg m;
  m.seq = f.data[1];
  m.term = static_cast<Ieee952Term>(page);
  m.value = get_float(f, 2);
  m.uncertainty = uncertainty_from_code(static_cast<unsigned>(get(f, 6, 2)));
  return accept(m, out);
}

ProtocolError decode_window(const CanFrame& f, Message& out) {
  const unsigned page = f.data[0] & 3u;
  if (page == 0) {
    if (f.data[7] & 0x7Fu) return ProtocolError::reserved_bits;
    WindowMsg m;
    m.seq = f.data[1];
    m.tau_count = u8(f.data[0] >> 2u);
    m.window = static_cast<std::uint32_t>(get(f, 2, 4));
    m.gaps = f.data[6];
    m.complete = (f.data[7] & 0x80u) != 0;
    return accept(m, out);
  }
  if (page == 1) {
    if ((f.data[0] & 0xFCu) || f.data[7]) return ProtocolError::reserved_bits;
    WindowLengthMsg m;
    m.seq = f.data[1];
    m.length = get(f, 2, 5);
    return accept(m, out);
  }
  if (page == 2) {
    const std::uint64_t fields = get(f, 2, 6);  // bits 16-63
    WindowDevMsg m;
    m.seq = f.data[1];
    m.tau_index = u8(f.data[0] >> 2u);
    m.window = u8(static_cast<unsigned>(fields & 0xFu));
    m.adev_angle_per_s = window_dev_from_code(static_cast<std::uint32_t>(fields >> 4 & 0x3FFFFFu));
    m.mdev_angle_per_s = window_dev_from_code(static_cast<std::uint32_t>(fields >> 26));
    return accept(m, out);
  }
  return ProtocolError::unknown_page;
}

ProtocolError decode_counter_input(const CanFrame& f, Message& out) {
  if (f.data[5] & 0xFCu) return ProtocolError::reserved_bits;
  CounterInputMsg m;
  m.count = static_cast<std::uint32_t>(get(f, 0, 4));
  m.seq = f.data[4];
  m.count_error = (f.data[5] & 1u) != 0;
  m.sensor_not_ready = (f.data[5] & 2u) != 0;
  return accept(m, out);
}

}  // namespace

// --- encode ----------------------------------------------------------------------------------

ProtocolError encode(const StatusMsg& msg, std::uint8_t node, CanFrame& frame) {
  return encode_with(msg, node, status_id, report_len, frame, [&](CanFrame& f) {
    header(f, 0, code(msg.state), msg.seq);
    f.data[2] = msg.tau_count;
    put(f, 3, 5, saturate(msg.sample_count, 40));
  });
}

ProtocolError encode(const StatusFaultsMsg& msg, std::uint8_t node, CanFrame& frame) {
  return encode_with(msg, node, status_id, report_len, frame, [&](CanFrame& f) {
    header(f, 1, static_cast<unsigned>(saturate(msg.bus_off_events, 6)), msg.seq);
    put(f, 2, 2, saturate(msg.lost_edges, 16));
    put(f, 4, 2, saturate(msg.sample_gaps, 16));
    put(f, 6, 2, saturate(msg.tx_dropped_frames, 16));
  });
}

ProtocolError encode(const TauDevMsg& msg, std::uint8_t node, CanFrame& frame) {
  return encode_with(msg, node, tau_stats_id, report_len, frame, [&](CanFrame& f) {
    header(f, code(msg.kind), msg.tau_index, msg.seq);
    put_float(f, 2, msg.dev_angle_per_s);
    put(f, 6, 2, edf_code(msg.edf) | code(msg.noise) << 12 | (msg.valid ? 1u : 0u) << 15);
  });
}

ProtocolError encode(const TauTermsMsg& msg, std::uint8_t node, CanFrame& frame) {
  return encode_with(msg, node, tau_stats_id, report_len, frame, [&](CanFrame& f) {
    header(f, 2, msg.tau_index, msg.seq);
    put(f, 2, 6, saturate(msg.n, 48));
  });
}

ProtocolError encode(const TauInfoMsg& msg, std::uint8_t node, CanFrame& frame) {
  return encode_with(msg, node, tau_stats_id, report_len, frame, [&](CanFrame& f) {
    header(f, 3, msg.tau_index, msg.seq);
    put(f, 2, 5, msg.m);
    f.data[7] = msg.stride_log2;
  });
}

ProtocolError encode(const MetaSamplingMsg& msg, std::uint8_t node, CanFrame& frame) {
  return encode_with(msg, node, metadata_id, report_len, frame, [&](CanFrame& f) {
    header(f, 0, 0, msg.seq);
    put_float(f, 2, msg.tau0_s);
    put(f, 6, 2, msg.stride_factor);
  });
}

ProtocolError encode(const MetaClockMsg& msg, std::uint8_t node, CanFrame& frame) {
  return encode_with(msg, node, metadata_id, report_len, frame, [&](CanFrame& f) {
    header(f, 1, 0, msg.seq);
    put(f, 2, 5, saturate(msg.uptime_ms, 40));
    f.data[7] = msg.protocol_version;
  });
}

ProtocolError encode(const MetaScaleMsg& msg, std::uint8_t node, CanFrame& frame) {
  return encode_with(msg, node, metadata_id, report_len, frame, [&](CanFrame& f) {
    header(f, 2, 0, msg.seq);
    put_float(f, 2, msg.angle_per_pulse);
    f.data[6] = u8(code(msg.angle_unit));
    f.data[7] = u8(code(msg.input_source));
  });
}

ProtocolError encode(const MetaConfigMsg& msg, std::uint8_t node, CanFrame& frame) {
  return encode_with(msg, node, metadata_id, report_len, frame, [&](CanFrame& f) {
    header(f, 3, 0, msg.seq);
    put(f, 2, 4, msg.config_hash);
    put(f, 6, 2, msg.report_period_ms);
  });
}

ProtocolError encode(const Ieee952Msg& msg, std::uint8_t node, CanFrame& frame) {
  return encode_with(msg, node, ieee952_id, report_len, frame, [&](CanFrame& f) {
    f.data[0] = u8(code(msg.term) | (msg.resolved ? ieee952_resolved_bit : 0u) | (msg.fitted ? ieee952_fitted_bit : 0u));
    f.data[1] = msg.seq;
    put_float(f, 2, msg.value);
    put(f, 6, 2, rel_uncertainty_code(msg.rel_uncertainty));
  });
}

ProtocolError encode(const Ieee952SummaryMsg& msg, std::uint8_t node, CanFrame& frame) {
  return encode_with(msg, node, ieee952_id, report_len, frame, [&](CanFrame& f) {
    f.data[0] = u8(ieee952_summary_page | unsigned{msg.excluded_below_log2_m[0]} << 3);
    f.data[1] = msg.seq;
    put_float(f, 2, msg.chi2_per_dof);
    f.data[6] = u8(static_cast<unsigned>(saturate(msg.points, 8)));
    f.data[7] = u8(unsigned{msg.excluded_below_log2_m[1]} | (msg.quantization_white ? 0x20u : 0u) | code(msg.status) << 6);
  });
}

ProtocolError encode(const WindowMsg& msg, std::uint8_t node, CanFrame& frame) {
  return encode_with(msg, node, window_id, report_len, frame, [&](CanFrame& f) {
    header(f, 0, msg.tau_count, msg.seq);
    put(f, 2, 4, msg.window);
    f.data[6] = u8(static_cast<unsigned>(saturate(msg.gaps, 8)));
    f.data[7] = u8(msg.complete ? 0x80u : 0u);
  });
}

ProtocolError encode(const WindowLengthMsg& msg, std::uint8_t node, CanFrame& frame) {
  return encode_with(msg, node, window_id, report_len, frame, [&](CanFrame& f) {
    header(f, 1, 0, msg.seq);
    put(f, 2, 5, msg.length);
  });
}

ProtocolError encode(const WindowDevMsg& msg, std::uint8_t node, CanFrame& frame) {
  return encode_with(msg, node, window_id, report_len, frame, [&](CanFrame& f) {
    header(f, 2, msg.tau_index, msg.seq);
    put(f, 2, 6,
        std::uint64_t{msg.window} | std::uint64_t{window_dev_code(msg.adev_angle_per_s)} << 4 |
            std::uint64_t{window_dev_code(msg.mdev_angle_per_s)} << 26);
  });
}

ProtocolError encode(const Ieee952ParameterMsg& msg, std::uint8_t node, CanFrame& frame) {
  return encode_with(msg, node, ieee952_id, report_len, frame, [&](CanFrame& f) {
    f.data[0] = u8(ieee952_parameter_page | code(msg.parameter) << 3 | unsigned{msg.index} << 6 |
                   (msg.resolved ? 0x80u : 0u));
    f.data[1] = msg.seq;
    put_float(f, 2, msg.value);
    put(f, 6, 2, rel_uncertainty_code(msg.rel_uncertainty));
  });
}

ProtocolError encode(const Ieee952ModelMsg& msg, std::uint8_t node, CanFrame& frame) {
  return encode_with(msg, node, ieee952_id, report_len, frame, [&](CanFrame& f) {
    f.data[0] = u8(ieee952_model_page | unsigned{msg.markov} << 3 | unsigned{msg.sinusoids} << 5 |
                   (msg.bandwidth ? 0x80u : 0u));
    f.data[1] = msg.seq;
    f.data[2] = u8(unsigned{msg.bandwidth_excluded_below_log2_m} | (msg.runner_up ? 0x20u : 0u) |
                   unsigned{msg.runner_up_markov} << 6);
    f.data[3] = u8(unsigned{msg.runner_up_sinusoids} | (msg.runner_up_bandwidth ? 4u : 0u));
    put_float(f, 4, msg.criterion_margin);
  });
}

ProtocolError encode(const Ieee952UnconstrainedMsg& msg, std::uint8_t node, CanFrame& frame) {
  return encode_with(msg, node, unconstrained_id, report_len, frame, [&](CanFrame& f) {
    f.data[0] = u8(code(msg.term));
    f.data[1] = msg.seq;
    put_float(f, 2, msg.value);
    put(f, 6, 2, uncertainty_code(msg.uncertainty));
  });
}

ProtocolError encode(const CounterInputMsg& msg, std::uint8_t node, CanFrame& frame) {
  return encode_with(msg, node, counter_input_id, counter_input_len, frame, [&](CanFrame& f) {
    put(f, 0, 4, msg.count);
    f.data[4] = msg.seq;
    f.data[5] = u8((msg.count_error ? 1u : 0u) | (msg.sensor_not_ready ? 2u : 0u));
  });
}

ProtocolError encode(const Message& msg, std::uint8_t node, CanFrame& frame) {
  return std::visit([&](const auto& m) { return encode(m, node, frame); }, msg);
}

// --- decode ----------------------------------------------------------------------------------

Decoded decode(const CanFrame& frame) {
  Decoded out;
  const auto fail = [&](ProtocolError e) {
    out.error = e;
    return out;
  };
  if (frame.error) return fail(ProtocolError::error_frame);
  if (!frame.extended) return fail(ProtocolError::not_extended);
  const std::uint32_t base = frame.id & ~std::uint32_t{0xFF};
  const bool known = frame.id <= id_mask &&
                     (base == status_id || base == tau_stats_id || base == metadata_id || base == ieee952_id ||
                      base == window_id || base == unconstrained_id || base == counter_input_id);
  if (!known) return fail(ProtocolError::unknown_id);
  out.node = u8(frame.id & 0xFFu);  // set before any later refusal: the frame is counted against its node
  if (out.node > max_node_address) return fail(ProtocolError::bad_address);
  if (frame.fd) return fail(ProtocolError::fd_frame);
  const std::uint8_t len = base == counter_input_id ? counter_input_len : report_len;
  if (frame.len != len) return fail(ProtocolError::wrong_length);
  switch (base) {
    case status_id: out.error = decode_status(frame, out.message); break;
    case tau_stats_id: out.error = decode_tau_stats(frame, out.message); break;
    case metadata_id: out.error = decode_metadata(frame, out.message); break;
    case ieee952_id: out.error = decode_ieee952(frame, out.message); break;
    case window_id: out.error = decode_window(frame, out.message); break;
    case unconstrained_id: out.error = decode_unconstrained(frame, out.message); break;
    default: out.error = decode_counter_input(frame, out.message); break;
  }
  return out;
}

}  // namespace gyrochar::protocol
