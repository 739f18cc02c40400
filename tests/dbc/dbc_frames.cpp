// Frames from the gyrochar codec for the DBC check (tests/dbc/test_dbc.py).
//
//   gyrochar_dbc_frames              candump log of the frames on stdout (canplayer replays it)
//   gyrochar_dbc_frames --expected   the same frames as JSON: for each, the candump line, the value
//                                    of every DBC signal as the codec decodes the frame, and the
//                                    VAL_ name of every enumeration
//   gyrochar_dbc_frames --log FILE [--expected]
//                                    the same for the frames of a candump log captured from a run
//                                    (gyrochar-demo --candump): lines that are not gyrochar frames
//                                    are an error
//
// The frames are four paced reports of a 3-tau node with 2 window taus (every slot of the
// current version's schedule, sequence wrapping 254 -> 1) and a set of messages at their range limits, covering every enumeration value.
#include <cerrno>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>
#include <tuple>
#include <vector>

#include <nlohmann/json.hpp>

#include "candump.hpp"
#include "gyrochar/wire/protocol.hpp"

namespace {

using namespace gyrochar::protocol;
using gyrochar::CanFrame;
using nlohmann::json;

struct Entry {
  std::uint64_t t_us = 0;  // candump timestamp
  std::uint8_t node = 0;
  Message message;
};

// --- what the DBC must say about a decoded message ------------------------------------------

struct Expected {
  json signals = json::object();
  json names = json::object();
};

double physical(float v) { return static_cast<double>(v); }

// The signals of each message as a table, one message a line or two (kept as written):
// clang-format off
Expected expected(const StatusMsg& m) {
  return {{{"Page", 0}, {"State", static_cast<int>(m.state)}, {"Seq", m.seq}, {"TauCount", m.tau_count},
           {"SampleCount", m.sample_count}},
          {{"State", name(m.state)}}};
}
Expected expected(const StatusFaultsMsg& m) {
  return {{{"Page", 1}, {"BusOffEvents", m.bus_off_events}, {"Seq", m.seq}, {"LostEdges", m.lost_edges},
           {"SampleGaps", m.sample_gaps}, {"TxDroppedFrames", m.tx_dropped_frames}}};
}
Expected expected(const TauDevMsg& m) {
  const std::string p = m.kind == DevKind::adev ? "ADEV" : "MDEV";
  // Log2Edf: raw 0 (EDF not available) is the signal's offset, -4.
  return {{{"Page", static_cast<int>(m.kind)}, {"TauIndex", m.tau_index}, {"Seq", m.seq},
           {p, physical(m.dev_angle_per_s)}, {p + "_Log2Edf", m.edf == 0.0 ? -4.0 : std::log2(m.edf)},
           {p + "_Noise", static_cast<int>(m.noise)}, {p + "_Valid", m.valid ? 1 : 0}},
          {{p + "_Noise", name(m.noise)}}};
}
Expected expected(const TauTermsMsg& m) {
  return {{{"Page", 2}, {"TauIndex", m.tau_index}, {"Seq", m.seq}, {"Terms", m.n}}};
}
Expected expected(const TauInfoMsg& m) {
  return {{{"Page", 3}, {"TauIndex", m.tau_index}, {"Seq", m.seq}, {"TauM", m.m}, {"StrideLog2", m.stride_log2}}};
}
Expected expected(const MetaSamplingMsg& m) {
  return {{{"Page", 0}, {"Seq", m.seq}, {"Tau0", physical(m.tau0_s)}, {"StrideFactor", m.stride_factor}}};
}
Expected expected(const MetaClockMsg& m) {
  return {{{"Page", 1}, {"Seq", m.seq}, {"Uptime", static_cast<double>(m.uptime_ms) / 1000.0},
           {"ProtocolVersion", m.protocol_version}}};
}
Expected expected(const MetaScaleMsg& m) {
  return {{{"Page", 2}, {"Seq", m.seq}, {"PulseWeight", physical(m.angle_per_pulse)},
           {"AngleUnit", static_cast<int>(m.angle_unit)}, {"InputSource", static_cast<int>(m.input_source)}},
          {{"AngleUnit", name(m.angle_unit)}, {"InputSource", name(m.input_source)}}};
}
Expected expected(const MetaConfigMsg& m) {
  return {{{"Page", 3}, {"Seq", m.seq}, {"ConfigHash", m.config_hash},
           {"ReportPeriod", static_cast<double>(m.report_period_ms) / 1000.0}}};
}
Expected expected(const Ieee952Msg& m) {
  static const char* const value_signal[] = {"Q", "N", "B", "K", "R"};
  const std::string p = value_signal[static_cast<int>(m.term)];
  return {{{"Term", static_cast<int>(m.term)}, {p + "_Resolved", m.resolved ? 1 : 0}, {p + "_Fitted", m.fitted ? 1 : 0},
           {"Seq", m.seq}, {p, physical(m.value)}, {p + "_RelUncertainty", m.rel_uncertainty * 100.0}},
          {{"Term", name(m.term)}}};
}
Expected expected(const Ieee952SummaryMsg& m) {
  // The codec has no name for the summary page's multiplexor value: the DBC calls it fit_summary.
  return {{{"Term", ieee952_summary_page}, {"Seq", m.seq}, {"AvarExcludedLog2M", m.excluded_below_log2_m[0]},
           {"Chi2PerDof", physical(m.chi2_per_dof)}, {"FitPoints", m.points},
           {"MvarExcludedLog2M", m.excluded_below_log2_m[1]}, {"QuantizationWhite", m.quantization_white ? 1 : 0},
           {"FitStatus", static_cast<int>(m.status)}},
          {{"Term", "fit_summary"}, {"FitStatus", name(m.status)}}};
}
Expected expected(const Ieee952ParameterMsg& m) {
  return {{{"Term", ieee952_parameter_page}, {"Parameter", static_cast<int>(m.parameter)}, {"ParameterIndex", m.index},
           {"ParameterResolved", m.resolved ? 1 : 0}, {"Seq", m.seq}, {"ParameterValue", physical(m.value)},
           {"ParameterRelUncertainty", m.rel_uncertainty * 100.0}},
          {{"Term", "fit_parameter"}, {"Parameter", name(m.parameter)}}};
}
Expected expected(const Ieee952ModelMsg& m) {
  return {{{"Term", ieee952_model_page}, {"MarkovTerms", m.markov}, {"Sinusoids", m.sinusoids},
           {"Bandwidth", m.bandwidth ? 1 : 0}, {"Seq", m.seq}, {"BandwidthExcludedLog2M", m.bandwidth_excluded_below_log2_m},
           {"RunnerUp", m.runner_up ? 1 : 0}, {"RunnerUpMarkovTerms", m.runner_up_markov},
           {"RunnerUpSinusoids", m.runner_up_sinusoids}, {"RunnerUpBandwidth", m.runner_up_bandwidth ? 1 : 0},
           {"CriterionMargin", physical(m.criterion_margin)}},
          {{"Term", "fit_model"}}};
}
Expected expected(const Ieee952UnconstrainedMsg& m) {
  static const char* const value_signal[] = {"Q", "N", "B", "K", "R"};
  const std::string p = value_signal[static_cast<int>(m.term)];
  // Log2Uncertainty on the wire's grid (1/256 steps); raw 0 (no estimate) is the offset, -128.
  const double log2_u = m.uncertainty == 0.0 ? -128.0 : std::round(std::log2(m.uncertainty) * 256.0) / 256.0;
  return {{{"Term", static_cast<int>(m.term)}, {"Seq", m.seq}, {p + "_Unconstrained", physical(m.value)},
           {p + "_Log2Uncertainty", log2_u}},
          {{"Term", name(m.term)}}};
}
// A window deviation's log2 on the wire's grid (2^-14 steps); raw 0 (no estimate) is the offset, -128.
double window_log2(double dev) {
  return dev == 0.0 ? -128.0 : std::round(std::log2(dev) * 16384.0) / 16384.0;
}
Expected expected(const WindowMsg& m) {
  return {{{"Page", 0}, {"TauCount", m.tau_count}, {"Seq", m.seq}, {"Window", m.window}, {"WindowGaps", m.gaps},
           {"Complete", m.complete ? 1 : 0}}};
}
Expected expected(const WindowLengthMsg& m) { return {{{"Page", 1}, {"Seq", m.seq}, {"WindowLength", m.length}}}; }
Expected expected(const WindowDevMsg& m) {
  return {{{"Page", 2}, {"TauIndex", m.tau_index}, {"Seq", m.seq}, {"WindowMod16", m.window},
           {"ADEV_Log2", window_log2(m.adev_angle_per_s)}, {"MDEV_Log2", window_log2(m.mdev_angle_per_s)}}};
}
Expected expected(const CounterInputMsg& m) {
  return {{{"Count", m.count}, {"Seq", m.seq}, {"CountError", m.count_error ? 1 : 0},
           {"SensorNotReady", m.sensor_not_ready ? 1 : 0}}};
}
// clang-format on

// --- the frames ------------------------------------------------------------------------------

// The slots as a table, one a line (kept as written):
// clang-format off
/// A message of a plausible node for one slot of the schedule.
Message for_slot(ReportSlot slot, std::uint8_t seq, std::uint64_t report) {
  const std::uint8_t i = slot.index;
  const float tau_s = 0.001f * static_cast<float>(1u << (4 * (i % 8)));  // m = 1, 16, 256 at tau0 = 1 ms (i % 8: the model pages index past 7)
  switch (slot.slot) {
    case Slot::status: return StatusMsg{seq, NodeState::running, 3, 1000 * (report + 1)};
    case Slot::faults: return StatusFaultsMsg{seq, 2, 1, 0, 0};
    case Slot::adev: return TauDevMsg{seq, i, DevKind::adev, 0.02f / std::sqrt(tau_s), 1000.0 / (1 + i), NoiseType::white_fm, true};
    case Slot::mdev: return TauDevMsg{seq, i, DevKind::mdev, 0.015f / std::sqrt(tau_s), 800.0 / (1 + i), NoiseType::white_fm, true};
    case Slot::terms: return TauTermsMsg{seq, i, 1000 * (report + 1) - 2 * (std::uint64_t{1} << (4 * i))};
    case Slot::tau_info: return TauInfoMsg{seq, i, std::uint64_t{1} << (4 * i), static_cast<std::uint8_t>(i == 0 ? 0 : 4 * i - 3)};  // S = 8
    case Slot::sampling: return MetaSamplingMsg{seq, 0.001f, 8};
    case Slot::clock: return MetaClockMsg{seq, 1000 * (report + 1) + 250, version};
    case Slot::scale: return MetaScaleMsg{seq, 1.5f, AngleUnit::arcsec, InputSource::strobe_counter};
    case Slot::config: return MetaConfigMsg{seq, 0xC0FFEE01u, 1000};
    case Slot::ieee952:
      if (i == ieee952_summary_page) return Ieee952SummaryMsg{seq, Ieee952Status::ok, 0.875f, 6, true, {0, 0}};
      return Ieee952Msg{seq, static_cast<Ieee952Term>(i), i < 3, i < 4 ? 0.001f * static_cast<float>(i + 1) : 0.0f,
                        i < 4 ? 0.05 * (i + 1) : 0.0, i < 4};  // K fitted, not resolved; R not fitted
    case Slot::window: return WindowMsg{seq, 2, true, 41, 1};  // 2 window taus, windows of 60 s
    case Slot::window_length: return WindowLengthMsg{seq, 60000};
    case Slot::window_dev:
      return WindowDevMsg{seq, i, 41 % 16, 0.021 / std::sqrt(tau_s), i == 0 ? 0.016 / std::sqrt(tau_s) : 0.0};
    case Slot::fit_model: return Ieee952ModelMsg{seq, 2, 1, true, 3, true, 1, 0, false, 7.25f};
    case Slot::fit_parameter: {  // two Markov terms (the first resolved), the filter, one sinusoid
      const FitParameterSlot p = fit_parameter_slot(i);
      const bool held = p.parameter != FitParameter::sinusoid_amplitude && p.parameter != FitParameter::sinusoid_frequency;
      const bool in_model = held || p.index == 0;
      return Ieee952ParameterMsg{seq, p.parameter, p.index, in_model && has_resolved(p.parameter) && p.index == 0,
                                 in_model ? 0.002f * static_cast<float>(i + 1) : 0.0f,
                                 in_model && p.parameter != FitParameter::sinusoid_frequency ? 0.1 * (i + 1) : 0.0};
    }
    case Slot::unconstrained:  // N's unconstrained square negative, R not free
      return Ieee952UnconstrainedMsg{seq, static_cast<Ieee952Term>(i), i == 1 ? -2.5e-4f : i < 4 ? 0.0011f * static_cast<float>(i + 1) : 0.0f,
                                     i < 4 ? 0.0004 * (i + 1) : 0.0};
  }
  return StatusMsg{};
}
// clang-format on

std::vector<Entry> frames() {
  std::vector<Entry> out;
  constexpr std::uint64_t t0_us = 1'700'000'000'000'000;
  constexpr std::size_t taus = 3, window_taus = 2;
  for (std::uint64_t report = 0; report < slow_cycle_reports; ++report) {
    const auto seq = static_cast<std::uint8_t>(254 + report);
    const std::size_t count = report_frame_count(seq, taus, version, window_taus);
    for (std::size_t p = 0; p < count; ++p) {
      const std::uint64_t t_us = t0_us + report * 1'000'000 + p * 1'000'000 / count;
      out.push_back({t_us, 0x2A, for_slot(report_slot(seq, taus, p, version, window_taus), seq, report)});
    }
  }

  std::vector<Message> limits{
      StatusMsg{0, NodeState::starting, 0, 0},
      StatusMsg{255, NodeState::input_lost, max_taus, (std::uint64_t{1} << 40) - 1},
      StatusFaultsMsg{255, 65535, 65535, 65535, 63},
      TauDevMsg{0, 0, DevKind::adev, 0.0f, 0.0, NoiseType::not_identified, false},
      TauDevMsg{255, 63, DevKind::mdev, FLT_MAX, std::exp2(59.984375), NoiseType::random_run_fm, true},
      TauDevMsg{1, 62, DevKind::adev, FLT_TRUE_MIN, std::exp2(-4.0 + 1.0 / 64), NoiseType::flicker_walk_fm, true},
      TauTermsMsg{255, 63, (std::uint64_t{1} << 48) - 1},
      TauTermsMsg{0, 0, 0},
      TauInfoMsg{255, 63, (std::uint64_t{1} << 40) - 1, 0},
      TauInfoMsg{0, 0, std::uint64_t{1} << 39, 39},
      MetaSamplingMsg{255, FLT_MAX, 32768},
      MetaSamplingMsg{0, FLT_TRUE_MIN, 1},
      MetaClockMsg{255, (std::uint64_t{1} << 40) - 1, 255},
      MetaScaleMsg{0, 1.0f, AngleUnit::pulse, InputSource::unknown},
      MetaScaleMsg{1, 0.5f, AngleUnit::rad, InputSource::gpio_quadrature},
      MetaScaleMsg{2, 2.0e-6f, AngleUnit::urad, InputSource::can_counter},
      MetaScaleMsg{3, 4.2e-4f, AngleUnit::deg, InputSource::simulated},
      MetaConfigMsg{255, 0xFFFFFFFFu, 2000},
      MetaConfigMsg{0, 0, 100},
      Ieee952Msg{255, Ieee952Term::rate_ramp, true, FLT_MAX, 6.5535, true},
      Ieee952Msg{0, Ieee952Term::quantization, false, 0.0f, 0.0, false},
      Ieee952Msg{7, Ieee952Term::angle_random_walk, true, 1.0e-4f, 0.02, false},  // as a version-1 node sends it
      Ieee952SummaryMsg{255, Ieee952Status::rejected, FLT_MAX, 255, false, {31, 31}},
      Ieee952SummaryMsg{0, Ieee952Status::too_few_points, 0.0f, 0, true, {0, 0}},
      Ieee952SummaryMsg{1, Ieee952Status::singular, 0.0f, 3, false, {4, 0}},
      Ieee952SummaryMsg{2, Ieee952Status::ok, 1.25f, 48, false, {0, 5}},
      Ieee952ParameterMsg{255, FitParameter::sinusoid_amplitude, 1, true, FLT_MAX, 6.5535},
      Ieee952ParameterMsg{0, FitParameter::markov_tc, 0, false, 0.0f, 0.0},
      Ieee952ModelMsg{255, 2, 2, true, 31, true, 2, 2, true, -FLT_MAX},
      Ieee952ModelMsg{0, 0, 0, false, 0, false, 0, 0, false, 0.0f},
      Ieee952UnconstrainedMsg{255, Ieee952Term::rate_ramp, -FLT_MAX, 1e300},   // uncertainty code 65535 (saturated)
      Ieee952UnconstrainedMsg{0, Ieee952Term::quantization, FLT_MAX, 1e-300},  // code 1 (clamped)
      Ieee952UnconstrainedMsg{1, Ieee952Term::bias_instability, 0.0f, 0.0},    // no estimate
      CounterInputMsg{0xFFFFFFFFu, 255, true, true},
      CounterInputMsg{0, 0, false, false},
      CounterInputMsg{123456789, 17, false, true},
      WindowMsg{0, 1, false, 0, 0},
      WindowMsg{255, 63, true, 0xFFFFFFFFu, 255},
      WindowLengthMsg{0, 4},
      WindowLengthMsg{255, (std::uint64_t{1} << 40) - 1},
      WindowDevMsg{0, 0, 0, 0.0, 0.0},
      WindowDevMsg{255, 63, 15, window_dev_floor, std::exp2(128.0 - 1.0 / 16384)},  // codes 1, 2^22 - 1
  };
  for (int k = 0; k < 16; ++k)  // every noise type on both pages
    limits.push_back(TauDevMsg{static_cast<std::uint8_t>(k), static_cast<std::uint8_t>(k), static_cast<DevKind>(k / 8),
                               1.0f / static_cast<float>(k + 1), 10.0 * (k + 1), static_cast<NoiseType>(k % 8), k % 3 != 0});
  std::uint64_t t_us = t0_us + 10'000'000;
  const std::uint8_t nodes[] = {0x00, 0x01, max_node_address};
  for (std::size_t k = 0; k < limits.size(); ++k) out.push_back({t_us += 1000, nodes[k % 3], limits[k]});
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  const std::vector<std::string> args(argv + 1, argv + argc);
  bool want_json = false;
  std::string log_path;
  bool usage = false;
  for (std::size_t k = 0; k < args.size(); ++k) {
    if (args[k] == "--expected") want_json = true;
    else if (args[k] == "--log" && k + 1 < args.size()) log_path = args[++k];
    else usage = true;
  }
  if (usage) {
    std::fprintf(stderr,
                 "usage: gyrochar_dbc_frames [--log FILE] [--expected]\n"
                 "  prints codec frames (or those of a candump log) as a candump log, or with\n"
                 "  --expected as JSON with the value of every DBC signal\n");
    return 2;
  }
  std::vector<std::tuple<double, std::string, CanFrame>> frames_out;  // time, interface, frame
  if (log_path.empty()) {
    for (const Entry& e : frames()) {
      CanFrame f;
      if (const ProtocolError err = encode(e.message, e.node, f); err != ProtocolError::none) {
        std::fprintf(stderr, "gyrochar_dbc_frames: encode: %s\n", name(err));
        return 1;
      }
      frames_out.emplace_back(static_cast<double>(e.t_us) * 1e-6, "can0", f);
    }
  } else {
    std::FILE* in = std::fopen(log_path.c_str(), "r");
    if (in == nullptr) {
      std::fprintf(stderr, "gyrochar_dbc_frames: %s: %s\n", log_path.c_str(), std::strerror(errno));
      return 1;
    }
    char buffer[256];
    gyrochar::CandumpLine parsed;
    std::string why;
    while (std::fgets(buffer, sizeof buffer, in) != nullptr) {
      std::string_view line(buffer);
      while (!line.empty() && (line.back() == '\n' || line.back() == '\r')) line.remove_suffix(1);
      if (!gyrochar::parse_candump_line(line, parsed, why)) {
        std::fprintf(stderr, "gyrochar_dbc_frames: %s: %s\n", log_path.c_str(), why.c_str());
        return 1;
      }
      frames_out.emplace_back(parsed.time_s, parsed.interface, parsed.frame);
    }
    std::fclose(in);
  }
  json all = json::array();
  for (const auto& [t_s, interface, f] : frames_out) {
    // Expected values come from what the codec decodes, so they carry the wire's quantization.
    const Decoded d = decode(f);
    if (d.error != ProtocolError::none) {
      std::fprintf(stderr, "gyrochar_dbc_frames: decode: %s\n", name(d.error));
      return 1;
    }
    const std::string line = gyrochar::format_candump_line(t_s, interface, f);
    if (!want_json) {
      std::puts(line.c_str());
      continue;
    }
    const Expected x = std::visit([](const auto& m) { return expected(m); }, d.message);
    all.push_back({{"candump", line}, {"signals", x.signals}, {"names", x.names}});
  }
  if (want_json) std::puts(all.dump(1).c_str());
  return 0;
}
