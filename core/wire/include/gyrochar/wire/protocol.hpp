#pragma once
// The gyrochar CAN protocol, version 5: one value type per frame kind, encode() and decode()
// between those values and CanFrame, and the report schedule. The codec decodes the frames of
// versions 1 to 4 too (each version only adds: version 2 the IEEE-952 fit summary page and the
// Fitted flag of the term frames, version 3 the Window message of the dynamic Allan deviation,
// version 4 the Ieee952 model and parameter pages of the fit's selected model, version 5 the
// Ieee952Unconstrained message: each term's unconstrained estimate, what verdicts judge),
// and the schedule of every version is available. docs/protocol.md is the specification,
// docs/gyrochar.dbc describes the same frames for CAN tools (tests/dbc checks it against this codec).
// The board firmware and the host decoder both use this codec; there is no other.
//
// Wire conventions: classic CAN, 29-bit identifiers (J1939 proprietary-B PGNs 0xFF40..0xFF50, the
// sending node's address in the low byte), little-endian fields, IEEE-754 binary32 floats. Angles are
// in the node's angle unit (MetaScaleMsg::angle_unit), times in seconds unless a name says otherwise.
//
// Every function is O(1) unless stated, allocates nothing, throws nothing and reads no clock.
#include <cstddef>
#include <array>
#include <cstdint>
#include <variant>

#include "gyrochar/wire/can_frame.hpp"

namespace gyrochar::protocol {

inline constexpr std::uint8_t version = 5;              // what this codec's nodes send
inline constexpr std::uint8_t oldest_version = 1;       // the oldest version decoders accept
inline constexpr std::size_t max_taus = 64;             // tau index is 6 bits
inline constexpr std::uint8_t max_node_address = 0xFD;  // J1939: 0xFE null, 0xFF global

// Identifier bases; the node address goes in the low byte (frame_id()).
inline constexpr std::uint32_t status_id = 0x14FF4000;         // priority 5, every report
inline constexpr std::uint32_t tau_stats_id = 0x18FF4100;      // priority 6, every report
inline constexpr std::uint32_t metadata_id = 0x18FF4200;       // priority 6, slow cycle
inline constexpr std::uint32_t ieee952_id = 0x18FF4300;        // priority 6, slow cycle
inline constexpr std::uint32_t window_id = 0x18FF4400;         // priority 6, slow cycle (version 3)
inline constexpr std::uint32_t unconstrained_id = 0x18FF4500;  // priority 6, slow cycle (version 5)
inline constexpr std::uint32_t counter_input_id = 0x0CFF5000;  // priority 3, gyro electronics -> board

constexpr std::uint32_t frame_id(std::uint32_t base, std::uint8_t node) { return base | node; }

// ---------------------------------------------------------------------------------------------
// Enumerations (VAL_ tables in the DBC carry the same names, see name())

/// Power-law noise identified at a tau; the code is what goes on the wire.
enum class NoiseType : std::uint8_t {
  not_identified = 0,
  white_pm = 1,         // alpha = +2: quantization noise (white angle noise)
  flicker_pm = 2,       // alpha = +1
  white_fm = 3,         // alpha =  0: angle random walk
  flicker_fm = 4,       // alpha = -1: bias instability
  random_walk_fm = 5,   // alpha = -2: rate random walk
  flicker_walk_fm = 6,  // alpha = -3
  random_run_fm = 7,    // alpha = -4: rate ramp
};
/// alpha (the exponent of f in the frequency-noise spectrum) of an identified noise type, +2..-4.
/// Precondition: t != NoiseType::not_identified.
constexpr int alpha(NoiseType t) { return 3 - static_cast<int>(t); }
/// The noise type of alpha in -4..+2; NoiseType::not_identified for any other value.
constexpr NoiseType noise_type(int alpha) {
  return alpha < -4 || alpha > 2 ? NoiseType::not_identified : static_cast<NoiseType>(3 - alpha);
}

enum class NodeState : std::uint8_t {
  starting = 0,    // configured, no samples yet
  running = 1,     // samples arriving
  input_lost = 2,  // no samples during the last report period
};

/// Unit of every angle on the wire: rates are angle unit per second, Q is in the angle unit.
enum class AngleUnit : std::uint8_t { pulse = 0, rad = 1, urad = 2, deg = 3, arcsec = 4 };

enum class InputSource : std::uint8_t {
  unknown = 0,
  gpio_quadrature = 1,
  strobe_counter = 2,
  can_counter = 3,
  simulated = 4,
};

/// The two deviations a node sends: a subset of the statistics (DevStat, core's stat.hpp). On the
/// wire `adev` is the OVERLAPPING Allan deviation (DevStat::oadev, which the analyzer calls
/// "oadev"), a name kept for compatibility: docs/architecture.md, "Names of statistics".
enum class DevKind : std::uint8_t { adev = 0, mdev = 1 };  // overlapping Allan, modified Allan

/// IEEE Std 952 gyro error-model terms and their units (A = angle unit, time in s).
enum class Ieee952Term : std::uint8_t {
  quantization = 0,       // Q, A
  angle_random_walk = 1,  // N, A/s^0.5
  bias_instability = 2,   // B, A/s
  rate_random_walk = 3,   // K, A/s^1.5
  rate_ramp = 4,          // R, A/s^2
};
/// The Ieee952 frame's multiplexor value (its "Term" field) of the fit summary page (version 2).
inline constexpr std::uint8_t ieee952_summary_page = 5;
/// Version 4: the page of one parameter of the selected model beyond the five terms, and the page
/// of the model itself (which terms it holds, and its runner-up).
inline constexpr std::uint8_t ieee952_parameter_page = 6;
inline constexpr std::uint8_t ieee952_model_page = 7;
/// Markov terms and sinusoids the protocol carries (version 4; the fit's max_markov, max_sinusoids).
inline constexpr std::size_t wire_markov_terms = 2;
inline constexpr std::size_t wire_sinusoids = 2;

/// What an Ieee952 parameter page (version 4) carries; the code is what goes on the wire.
enum class FitParameter : std::uint8_t {
  markov_sigma = 0,        // a Markov term's stationary standard deviation sigma, A/s (Resolved)
  markov_tc = 1,           // its correlation time Tc, s
  filter_tf = 2,           // the time constant Tf of the sensor's own filter on N's white noise, s
  sinusoid_amplitude = 3,  // a sinusoid's rate amplitude, A/s (Resolved)
  sinusoid_frequency = 4,  // its frequency, Hz
};
/// Whether a parameter page of this kind carries a Resolved flag (the amplitudes do).
constexpr bool has_resolved(FitParameter p) {
  return p == FitParameter::markov_sigma || p == FitParameter::sinusoid_amplitude;
}
/// The parameter pages of a version-4 slow cycle, in sending order: sigma and Tc of Markov term 0,
/// of term 1, the filter's Tf, amplitude and frequency of sinusoid 0, of sinusoid 1.
inline constexpr std::size_t fit_parameter_pages = 2 * wire_markov_terms + 1 + 2 * wire_sinusoids;
struct FitParameterSlot {
  FitParameter parameter = FitParameter::markov_sigma;
  std::uint8_t index = 0;  // the Markov term or sinusoid (0 for the filter)
};
/// Parameter page k (< fit_parameter_pages) of that order, and back (fit_parameter_pages for a
/// kind and index with no page).
FitParameterSlot fit_parameter_slot(std::size_t k);
std::size_t fit_parameter_position(FitParameter parameter, std::uint8_t index);

/// Outcome of the node's IEEE-952 fit (the values of gyrochar::FitStatus, core/ieee952.hpp).
enum class Ieee952Status : std::uint8_t {
  ok = 0,
  too_few_points = 1,  // fewer points than terms to fit: no fit
  rejected = 2,        // the model does not describe the curve (chi2/dof > 2 and p < 1e-4)
  singular = 3,        // the covariance of the points or the normal equations could not be solved
};

// ---------------------------------------------------------------------------------------------
// Messages: one struct per frame kind. seq is the 8-bit report sequence number (wraps); a frame
// belongs to the report whose status frame has the same seq. Counts are unsigned and saturate at
// the field's maximum when encoded (see docs/protocol.md for each field's width).

/// Status page 0, the heartbeat: first frame of every report.
struct StatusMsg {
  std::uint8_t seq = 0;
  NodeState state = NodeState::starting;
  std::uint8_t tau_count = 0;      // taus in this report, 0..max_taus
  std::uint64_t sample_count = 0;  // tau0 samples since start; 40 bits, saturates
  bool operator==(const StatusMsg&) const = default;
};

/// Status page 1: fault counters since start, every report. Each saturates at its maximum.
struct StatusFaultsMsg {
  std::uint8_t seq = 0;
  std::uint32_t lost_edges = 0;         // 16 bits: illegal quadrature transitions, counter errors
  std::uint32_t sample_gaps = 0;        // 16 bits: gaps in the sample stream (segments started)
  std::uint32_t tx_dropped_frames = 0;  // 16 bits: report frames the node could not queue
  std::uint32_t bus_off_events = 0;     // 6 bits
  bool operator==(const StatusFaultsMsg&) const = default;
};

/// Tau statistics pages 0 (ADEV) and 1 (MDEV), every report, for every tau.
struct TauDevMsg {
  std::uint8_t seq = 0;
  std::uint8_t tau_index = 0;  // 0..max_taus-1
  DevKind kind = DevKind::adev;
  float dev_angle_per_s = 0.0f;  // the deviation, >= 0, finite
  double edf = 0.0;              // equivalent degrees of freedom; 0 = not available. On the wire as
                                 // log2(edf) in 1/64 steps, clamped to [2^-3.98, 2^59.98]
  NoiseType noise = NoiseType::not_identified;
  bool valid = false;  // false: no estimate yet, or terms were lost (do not plot)
  bool operator==(const TauDevMsg&) const = default;
};

/// Tau statistics page 2: number of overlapping Allan terms n, in the slow cycle.
struct TauTermsMsg {
  std::uint8_t seq = 0;
  std::uint8_t tau_index = 0;
  std::uint64_t n = 0;  // 48 bits, saturates
  bool operator==(const TauTermsMsg&) const = default;
};

/// Tau statistics page 3: what tau index i means, in the slow cycle.
struct TauInfoMsg {
  std::uint8_t seq = 0;
  std::uint8_t tau_index = 0;
  std::uint64_t m = 1;           // tau = m * tau0; 1 <= m < 2^40
  std::uint8_t stride_log2 = 0;  // terms are formed every 2^stride_log2 samples; 2^stride_log2 divides m
  bool operator==(const TauInfoMsg&) const = default;
};

/// Metadata page 0.
struct MetaSamplingMsg {
  std::uint8_t seq = 0;
  float tau0_s = 0.0f;              // sample interval, > 0, finite
  std::uint16_t stride_factor = 1;  // S, a power of two
  bool operator==(const MetaSamplingMsg&) const = default;
};

/// Metadata page 1.
struct MetaClockMsg {
  std::uint8_t seq = 0;
  std::uint64_t uptime_ms = 0;              // 40 bits, saturates
  std::uint8_t protocol_version = version;  // >= 1
  bool operator==(const MetaClockMsg&) const = default;
};

/// Metadata page 2.
struct MetaScaleMsg {
  std::uint8_t seq = 0;
  float angle_per_pulse = 1.0f;  // pulse weight in angle_unit, > 0, finite
  AngleUnit angle_unit = AngleUnit::pulse;
  InputSource input_source = InputSource::unknown;
  bool operator==(const MetaScaleMsg&) const = default;
};

/// Metadata page 3.
struct MetaConfigMsg {
  std::uint8_t seq = 0;
  std::uint32_t config_hash = 0;          // changes whenever the configuration does
  std::uint16_t report_period_ms = 1000;  // 100..2000
  bool operator==(const MetaConfigMsg&) const = default;
};

/// One IEEE-952 parameter of the latest fit, in the slow cycle (Ieee952 pages 0-4).
struct Ieee952Msg {
  std::uint8_t seq = 0;
  Ieee952Term term = Ieee952Term::quantization;
  bool resolved = false;         // the fit resolved this term: significant, and the largest term at
                                 // one of the taus fitted at least
  float value = 0.0f;            // >= 0, finite, in the term's unit (see Ieee952Term)
  double rel_uncertainty = 0.0;  // standard uncertainty / value, >= 0; on the wire in 0.01 % steps,
                                 // saturating at 655.35 %
  bool fitted = false;           // version 2: the term is in the fitted model, so value and
                                 // uncertainty are the fit's even when not resolved (an upper-bound
                                 // reading). Version-1 nodes send 0 (their Resolved implies fitted);
                                 // a version-2 node sets it whenever it sets resolved.
  bool operator==(const Ieee952Msg&) const = default;
};

/// The IEEE-952 fit's summary (Ieee952 page 5, version 2), in the slow cycle beside the terms.
struct Ieee952SummaryMsg {
  std::uint8_t seq = 0;
  Ieee952Status status = Ieee952Status::too_few_points;
  float chi2_per_dof = 0.0f;       // generalized chi-squared per degree of freedom; finite, >= 0
                                   // (0 when no fit was made or no degree of freedom was left)
  std::uint32_t points = 0;        // points (AVAR and MVAR estimates) the fit used; 8 bits, saturates
  bool quantization_white = true;  // false: the quantization of the counts is not white, the
                                   // short taus it reaches were left out and Q was held at
                                   // pulse weight / sqrt(12) rather than fitted
  /// AVAR [0] and MVAR [1] points with averaging factor m < 2^c were left out of the fit because of
  /// that quantization; 0: none. 0..31 (5 bits); both 0 when quantization_white.
  std::array<std::uint8_t, 2> excluded_below_log2_m{};
  bool operator==(const Ieee952SummaryMsg&) const = default;
};

/// One parameter of the selected model beyond the five terms (Ieee952 page 6, version 4), in the
/// slow cycle. Every page of the cycle is sent; those of terms the model (Ieee952ModelMsg) does not
/// hold carry zeros.
struct Ieee952ParameterMsg {
  std::uint8_t seq = 0;
  FitParameter parameter = FitParameter::markov_sigma;
  std::uint8_t index = 0;        // the Markov term or sinusoid, 0..1; 0 for filter_tf
  bool resolved = false;         // markov_sigma, sinusoid_amplitude only: the term is resolved in an
                                 // accepted fit (as Ieee952Msg::resolved); false for the others
  float value = 0.0f;            // >= 0, finite, in the parameter's unit (see FitParameter)
  double rel_uncertainty = 0.0;  // standard uncertainty / value, >= 0; as Ieee952Msg's on the wire
                                 // (a sinusoid's frequency is given to the fit, not fitted: 0)
  bool operator==(const Ieee952ParameterMsg&) const = default;
};

/// The selected model of the fit (Ieee952 page 7, version 4), in the slow cycle: the first page
/// of the cycle's model list. Every Ieee952 frame of one slow cycle describes the same fit.
struct Ieee952ModelMsg {
  std::uint8_t seq = 0;
  std::uint8_t markov = 0;     // Markov terms in the model, 0..wire_markov_terms
  std::uint8_t sinusoids = 0;  // sinusoids in the model, 0..wire_sinusoids
  bool bandwidth = false;      // the sensor's own filter is in the model (its Tf on a parameter page)
  /// Points with averaging factor m < 2^c were left out because the sensor's filter shapes them in
  /// a way the model does not describe; 0: none. 0..31 (5 bits).
  std::uint8_t bandwidth_excluded_below_log2_m = 0;
  bool runner_up = false;  // a runner-up candidate was fitted; false: its fields are all 0
  std::uint8_t runner_up_markov = 0, runner_up_sinusoids = 0;  // 0..2 each
  bool runner_up_bandwidth = false;
  float criterion_margin = 0.0f;  // the runner-up's information criterion minus the chosen
                                  // model's; finite (0 without runner-up)
  bool operator==(const Ieee952ModelMsg&) const = default;
};

/// The unconstrained estimate of one IEEE-952 term (message Ieee952Unconstrained, version 5), in the
/// slow cycle, from the fit every Ieee952 frame of its cycle describes: the term in the model with
/// every free term, its square not held non-negative (gyrochar::Ieee952Parameter::unconstrained).
/// The term pages carry the non-negative fit's value, which leans low where another term is clipped
/// at zero; acceptance verdicts judge this estimate.
struct Ieee952UnconstrainedMsg {
  std::uint8_t seq = 0;
  Ieee952Term term = Ieee952Term::quantization;
  /// The signed root of the unconstrained estimate s of the term's square, sign(s) sqrt(|s|), in the
  /// term's unit: negative where s is (the estimate for a verdict is then 0); finite. 0 without an
  /// estimate.
  float value = 0.0f;
  /// Its standard uncertainty (Ieee952Parameter::unconstrained_uncertainty), in the term's unit,
  /// >= 0 and finite; 0: no estimate (the term was not free in the fit, or no fit), and then value
  /// is 0. On the wire as log2 in 1/256 steps (relative rounding error at most 0.14 %), clamped to
  /// [2^(1/256 - 128), 2^(128 - 1/256)].
  double uncertainty = 0.0;
  bool operator==(const Ieee952UnconstrainedMsg&) const = default;
};

/// Window page 0 (version 3): which window of the node's dynamic Allan deviation the Window frames
/// of this slow cycle describe. The node restarts a second characterizer every `length` samples
/// (WindowLengthMsg); window k covers the samples k length .. (k+1) length - 1 of the SampleCount.
struct WindowMsg {
  std::uint8_t seq = 0;
  std::uint8_t tau_count = 1;  // window taus: window tau i has the node's tau i's m; 1..63
  bool complete = false;       // false: no window completed yet (then window = 0, gaps = 0, and
                               // every WindowDevMsg says "no estimate")
  std::uint32_t window = 0;    // k, the number of the window described
  std::uint32_t gaps = 0;      // sample gaps inside that window; 8 bits, saturates
  bool operator==(const WindowMsg&) const = default;
};

/// Window page 1 (version 3): samples per window.
struct WindowLengthMsg {
  std::uint8_t seq = 0;
  std::uint64_t length = 4;  // tau0 samples per window, 4 <= length < 2^40
  bool operator==(const WindowLengthMsg&) const = default;
};

/// A deviation of exactly 0 (a perfectly constant rate) goes into a WindowDevMsg as this, since 0
/// there means "no estimate": like every deviation below 2^-128 it is sent as the smallest code,
/// 2^(2^-14 - 128).
inline constexpr double window_dev_floor = 0x1p-128;

/// Window page 2 (version 3): ADEV and MDEV of one window tau in the window WindowMsg names.
struct WindowDevMsg {
  std::uint8_t seq = 0;
  std::uint8_t tau_index = 0;     // 0..max_taus-1; tau = the node's tau tau_index
  std::uint8_t window = 0;        // the window's number modulo 16 (4 bits), as a check
  double adev_angle_per_s = 0.0;  // overlapping Allan deviation in the window; 0: no estimate
  double mdev_angle_per_s = 0.0;  // modified Allan deviation in the window; 0: no estimate
  // Each deviation is >= 0 and finite; on the wire as log2 in 2^-14 steps (relative error at most
  // 2.2e-5), clamped to [2^(2^-14 - 128), 2^(128 - 2^-14)] (see window_dev_floor).
  bool operator==(const WindowDevMsg&) const = default;
};

/// Counter input: sent by the gyro's readout electronics to the board once per sample interval.
struct CounterInputMsg {
  std::uint32_t count = 0;        // accumulated pulses, wraps modulo 2^32 (differences are signed)
  std::uint8_t seq = 0;           // +1 per frame, wraps
  bool count_error = false;       // the electronics lost counts during this interval
  bool sensor_not_ready = false;  // e.g. dither or laser not locked
  bool operator==(const CounterInputMsg&) const = default;
};

using Message = std::variant<StatusMsg, StatusFaultsMsg, TauDevMsg, TauTermsMsg, TauInfoMsg, MetaSamplingMsg, MetaClockMsg,
                             MetaScaleMsg, MetaConfigMsg, Ieee952Msg, CounterInputMsg, Ieee952SummaryMsg, WindowMsg,
                             WindowLengthMsg, WindowDevMsg, Ieee952ParameterMsg, Ieee952ModelMsg, Ieee952UnconstrainedMsg>;

// ---------------------------------------------------------------------------------------------
// Codec

enum class ProtocolError : std::uint8_t {
  none = 0,
  error_frame,    // the controller reported an error frame
  not_extended,   // 11-bit identifier
  fd_frame,       // CAN FD frame: protocol versions 1 to 5 are classic CAN only
  unknown_id,     // not one of the identifiers above (PGN or priority differ)
  bad_address,    // node address 0xFE or 0xFF
  wrong_length,   // data length differs from the frame kind's (8, counter input 6)
  unknown_page,   // multiplexor value with no layout
  reserved_bits,  // a reserved bit is set
  out_of_range,   // a field holds a value outside its range (NaN, negative, zero m, ...)
};

/// Static name of a value, as in the DBC's VAL_ tables (errors: as spelled above); "invalid" for a
/// value outside the enumeration. Never null, no allocation.
const char* name(ProtocolError e);
const char* name(NoiseType t);
const char* name(NodeState s);
const char* name(AngleUnit u);
const char* name(InputSource s);
const char* name(Ieee952Term t);
const char* name(Ieee952Status s);
const char* name(FitParameter p);

/// Encodes one message sent by node `node` (0..max_node_address) into `frame`: a classic frame with
/// an extended identifier, 8 data bytes (counter input: 6), unused data bytes zero.
/// Returns ProtocolError::none, or bad_address / out_of_range when a field cannot be represented,
/// in which case `frame` is left untouched. Counts saturate instead of failing.
ProtocolError encode(const StatusMsg& msg, std::uint8_t node, CanFrame& frame);
ProtocolError encode(const StatusFaultsMsg& msg, std::uint8_t node, CanFrame& frame);
ProtocolError encode(const TauDevMsg& msg, std::uint8_t node, CanFrame& frame);
ProtocolError encode(const TauTermsMsg& msg, std::uint8_t node, CanFrame& frame);
ProtocolError encode(const TauInfoMsg& msg, std::uint8_t node, CanFrame& frame);
ProtocolError encode(const MetaSamplingMsg& msg, std::uint8_t node, CanFrame& frame);
ProtocolError encode(const MetaClockMsg& msg, std::uint8_t node, CanFrame& frame);
ProtocolError encode(const MetaScaleMsg& msg, std::uint8_t node, CanFrame& frame);
ProtocolError encode(const MetaConfigMsg& msg, std::uint8_t node, CanFrame& frame);
ProtocolError encode(const Ieee952Msg& msg, std::uint8_t node, CanFrame& frame);
ProtocolError encode(const Ieee952SummaryMsg& msg, std::uint8_t node, CanFrame& frame);
ProtocolError encode(const WindowMsg& msg, std::uint8_t node, CanFrame& frame);
ProtocolError encode(const WindowLengthMsg& msg, std::uint8_t node, CanFrame& frame);
ProtocolError encode(const WindowDevMsg& msg, std::uint8_t node, CanFrame& frame);
ProtocolError encode(const Ieee952ParameterMsg& msg, std::uint8_t node, CanFrame& frame);
ProtocolError encode(const Ieee952ModelMsg& msg, std::uint8_t node, CanFrame& frame);
ProtocolError encode(const Ieee952UnconstrainedMsg& msg, std::uint8_t node, CanFrame& frame);
ProtocolError encode(const CounterInputMsg& msg, std::uint8_t node, CanFrame& frame);
ProtocolError encode(const Message& msg, std::uint8_t node, CanFrame& frame);

struct Decoded {
  ProtocolError error = ProtocolError::none;  // none: node and message are valid
  std::uint8_t node = 0;                      // sender's address (low byte of the identifier)
  Message message{};
};

/// Decodes any frame. Never fails hard: a frame that is not exactly a valid protocol frame gives the
/// first reason found (in the order of ProtocolError, but fd_frame after bad_address: a refused
/// frame with a protocol identifier names its sender in `node`). A frame decode() accepts is canonical:
/// encode(decoded.message, decoded.node, f) reproduces it bit for bit.
Decoded decode(const CanFrame& frame);

// ---------------------------------------------------------------------------------------------
// Report schedule (docs/protocol.md, "Report schedule"). Every report carries the fast frames
// (status, faults, ADEV and MDEV of every tau); the slow list (metadata, tau info, terms, IEEE-952
// terms and, from version 2, the fit summary) is cut into slow_cycle_reports equal parts, one part
// per report, chosen by seq; from version 3, a node with window taus appends a part of its window
// list (window page, window length, one WindowDevMsg per window tau), cut the same way. Both the
// node (what to send) and the decoder (what to expect) derive a report's frames from seq, tau
// count, window tau count and the node's protocol version. From version 4 every report appends a
// part of the model list (the Ieee952 model page, then the fit_parameter_pages parameter pages),
// cut the same way, after its window part.
//
// The version-2 slow list is version 1's with the summary appended; its length 10 + 2T is even
// where version 1's 9 + 2T is odd, so both cut into parts of the same length ceil(L/4): every frame
// keeps its position, and one report of the cycle has one frame more. Version 3 keeps every
// version-2 position too: the window part follows them; version 4 keeps every version-3 position:
// the model part follows the window part. From version 5 every report appends a part of the
// unconstrained list (the Ieee952Unconstrained frames of Q N B K R), cut the same way, after its
// model part; every version-4 position stays.

inline constexpr std::size_t slow_cycle_reports = 4;

enum class Slot : std::uint8_t {
  status,
  faults,
  adev,
  mdev,
  terms,
  tau_info,
  sampling,
  clock,
  scale,
  config,
  ieee952,
  window,
  window_length,
  window_dev,  // version 3
  fit_model,
  fit_parameter,  // version 4
  unconstrained   // version 5
};
inline constexpr std::size_t slot_kinds = 17;
struct ReportSlot {
  Slot slot = Slot::status;
  std::uint8_t index = 0;  // tau index (adev, mdev, terms, tau_info, window_dev); for ieee952 the
                           // page: an Ieee952Term (0-4) or ieee952_summary_page (5); for
                           // fit_parameter the position in fit_parameter_slot()'s order; for
                           // unconstrained the Ieee952Term
};

/// Number of frames in report `seq` for `tau_count` taus (<= max_taus) and `window_taus` window
/// taus (<= tau_count; 0: no window, and for versions 1 and 2) of a node speaking
/// `protocol_version` (1, 2, 3, 4, or 5 and above: the current schedule).
std::size_t report_frame_count(std::uint8_t seq, std::size_t tau_count, std::uint8_t protocol_version = version,
                               std::size_t window_taus = 0);
/// Frame `position` (< report_frame_count()) of report `seq`, in sending order: status, faults,
/// ADEV and MDEV of tau 0, 1, ..., then this report's part of the slow list, then (version 3) its
/// part of the window list, then (version 4) its part of the model list, then (version 5) its part
/// of the unconstrained list.
ReportSlot report_slot(std::uint8_t seq, std::size_t tau_count, std::size_t position,
                       std::uint8_t protocol_version = version, std::size_t window_taus = 0);

/// Data bytes of every report frame (the counter-input frame has 6).
inline constexpr std::uint8_t report_frame_len = 8;

/// Worst-case bits on the wire of a classic data frame with a 29-bit identifier and `data_bytes`
/// (<= 8) data bytes, with the maximum number of stuff bits and the 3-bit interframe space:
/// 67 + 8 data_bytes + floor((53 + 8 data_bytes) / 4); 160 for 8 bytes.
constexpr std::uint32_t worst_case_frame_bits(std::uint32_t data_bytes) {
  const std::uint32_t stuffed = 54 + 8 * data_bytes;  // SOF through CRC: the bits stuffing applies to
  return stuffed + 13 + (stuffed - 1) / 4;            // + CRC delimiter, ACK, EOF, interframe space
}

/// Worst-case share of a bus of `bitrate_bps` taken by one node reporting `tau_count` taus and
/// `window_taus` window taus every `report_period_s` seconds (the longest report of the slow cycle,
/// current version). O(slow_cycle_reports).
double worst_case_bus_load(std::size_t tau_count, double report_period_s, double bitrate_bps, std::size_t window_taus = 0);

}  // namespace gyrochar::protocol
