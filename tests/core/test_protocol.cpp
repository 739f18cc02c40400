// The CAN codec (core/wire/include/gyrochar/wire/protocol.hpp, docs/protocol.md): round trips of every frame
// kind, every field at its range limits, saturation and quantization, rejection of malformed frames
// with the right reason, a fuzz run, the report schedule (versions 1 to 4) and the bus load.
//
// Oracles: the byte layouts of docs/protocol.md (written out by hand below), closed forms for
// saturation (min(v, 2^bits - 1)) and quantization (half a step), the worst-case CAN frame length of
// Davis, Burns, Bril and Lukkien, "Controller Area Network (CAN) schedulability analysis: refuted,
// revisited and revised", Real-Time Systems 35 (2007), section 3 (29-bit identifiers:
// 8 s + 67 + floor((54 + 8 s - 1) / 4) bits), and brute-force counts over the schedule.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "gyrochar/wire/protocol.hpp"

namespace gyrochar::protocol {
namespace {

constexpr float nan_f = std::numeric_limits<float>::quiet_NaN();
constexpr float inf_f = std::numeric_limits<float>::infinity();
constexpr std::uint64_t max40 = (std::uint64_t{1} << 40) - 1;
constexpr std::uint64_t max48 = (std::uint64_t{1} << 48) - 1;

CanFrame encoded(const Message& m, std::uint8_t node) {
  CanFrame f;
  const ProtocolError e = encode(m, node, f);
  EXPECT_EQ(e, ProtocolError::none) << name(e);
  return f;
}

/// Encodes, checks the frame envelope, decodes and returns the decoded message.
Message round_trip(const Message& m, std::uint8_t node = 0x2A) {
  const CanFrame f = encoded(m, node);
  EXPECT_TRUE(f.extended);
  EXPECT_FALSE(f.fd);
  EXPECT_FALSE(f.error);
  const Decoded d = decode(f);
  EXPECT_EQ(d.error, ProtocolError::none) << name(d.error);
  EXPECT_EQ(d.node, node);
  return d.message;
}

std::array<std::uint8_t, 8> bytes(const CanFrame& f) {
  std::array<std::uint8_t, 8> b{};
  for (std::size_t i = 0; i < 8; ++i) b[i] = f.data[i];
  return b;
}

// --- layouts -------------------------------------------------------------------------------

TEST(ProtocolLayout, FramesMatchTheSpecificationByteForByte) {
  // Hand-written from the tables in docs/protocol.md.
  const CanFrame status = encoded(StatusMsg{0x12, NodeState::running, 32, 0x0102030405}, 0x01);
  EXPECT_EQ(status.id, 0x14FF4001u);
  EXPECT_EQ(status.len, 8);
  EXPECT_EQ(bytes(status), (std::array<std::uint8_t, 8>{0x04, 0x12, 0x20, 0x05, 0x04, 0x03, 0x02, 0x01}));

  const CanFrame faults = encoded(StatusFaultsMsg{0x12, 0x0102, 0x0304, 0x0506, 5}, 0x01);
  EXPECT_EQ(bytes(faults), (std::array<std::uint8_t, 8>{0x15, 0x12, 0x02, 0x01, 0x04, 0x03, 0x06, 0x05}));

  // 1.0f = 0x3F800000; edf 2^37 -> code 64 * (37 + 4) = 2624 = 0xA40; white PM (1); valid.
  const CanFrame mdev = encoded(TauDevMsg{7, 1, DevKind::mdev, 1.0f, std::exp2(37.0), NoiseType::white_pm, true}, 0x2A);
  EXPECT_EQ(mdev.id, 0x18FF412Au);
  EXPECT_EQ(bytes(mdev), (std::array<std::uint8_t, 8>{0x05, 0x07, 0x00, 0x00, 0x80, 0x3F, 0x40, 0x9A}));

  const CanFrame terms = encoded(TauTermsMsg{9, 63, 0x010203040506}, 0x2A);
  EXPECT_EQ(bytes(terms), (std::array<std::uint8_t, 8>{0xFE, 0x09, 0x06, 0x05, 0x04, 0x03, 0x02, 0x01}));

  const CanFrame info = encoded(TauInfoMsg{9, 2, 256, 5}, 0x2A);
  EXPECT_EQ(bytes(info), (std::array<std::uint8_t, 8>{0x0B, 0x09, 0x00, 0x01, 0x00, 0x00, 0x00, 0x05}));

  // 0.001f = 0x3A83126F
  const CanFrame sampling = encoded(MetaSamplingMsg{3, 0.001f, 8}, 0x2A);
  EXPECT_EQ(sampling.id, 0x18FF422Au);
  EXPECT_EQ(bytes(sampling), (std::array<std::uint8_t, 8>{0x00, 0x03, 0x6F, 0x12, 0x83, 0x3A, 0x08, 0x00}));

  const CanFrame clock = encoded(MetaClockMsg{3, 0x0102030405, 1}, 0x2A);
  EXPECT_EQ(bytes(clock), (std::array<std::uint8_t, 8>{0x01, 0x03, 0x05, 0x04, 0x03, 0x02, 0x01, 0x01}));

  // 1.5f = 0x3FC00000
  const CanFrame scale = encoded(MetaScaleMsg{3, 1.5f, AngleUnit::arcsec, InputSource::strobe_counter}, 0x2A);
  EXPECT_EQ(bytes(scale), (std::array<std::uint8_t, 8>{0x02, 0x03, 0x00, 0x00, 0xC0, 0x3F, 0x04, 0x02}));

  const CanFrame config = encoded(MetaConfigMsg{3, 0xC0FFEE01, 1000}, 0x2A);
  EXPECT_EQ(bytes(config), (std::array<std::uint8_t, 8>{0x03, 0x03, 0x01, 0xEE, 0xFF, 0xC0, 0xE8, 0x03}));

  // 2.0f = 0x40000000; 12.34 % -> 1234 = 0x04D2
  const CanFrame ieee = encoded(Ieee952Msg{4, Ieee952Term::bias_instability, true, 2.0f, 0.1234}, 0x2A);
  EXPECT_EQ(ieee.id, 0x18FF432Au);
  EXPECT_EQ(bytes(ieee), (std::array<std::uint8_t, 8>{0x0A, 0x04, 0x00, 0x00, 0x00, 0x40, 0xD2, 0x04}));
  // Version 2: Fitted is bit 4; fitted but not resolved: 0x02 | 0x10.
  const CanFrame fitted = encoded(Ieee952Msg{4, Ieee952Term::bias_instability, false, 2.0f, 0.1234, true}, 0x2A);
  EXPECT_EQ(bytes(fitted), (std::array<std::uint8_t, 8>{0x12, 0x04, 0x00, 0x00, 0x00, 0x40, 0xD2, 0x04}));

  // The fit summary, page 5: AVAR code 7 in bits 3-7 (0x05 | 7 << 3 = 0x3D); chi2/dof 1.5f =
  // 0x3FC00000; 40 points; MVAR code 6, QuantizationWhite 0, status rejected (2 << 6): 0x86.
  const CanFrame summary = encoded(Ieee952SummaryMsg{9, Ieee952Status::rejected, 1.5f, 40, false, {7, 6}}, 0x2A);
  EXPECT_EQ(summary.id, 0x18FF432Au);
  EXPECT_EQ(bytes(summary), (std::array<std::uint8_t, 8>{0x3D, 0x09, 0x00, 0x00, 0xC0, 0x3F, 0x28, 0x86}));
  // White quantization (bit 61: 0x20 in byte 7), status ok, nothing left out.
  const CanFrame white = encoded(Ieee952SummaryMsg{9, Ieee952Status::ok, 1.5f, 40, true, {0, 0}}, 0x2A);
  EXPECT_EQ(bytes(white), (std::array<std::uint8_t, 8>{0x05, 0x09, 0x00, 0x00, 0xC0, 0x3F, 0x28, 0x20}));

  // Version 3, the Window message: page 0 with 20 window taus in bits 2-7 (0x50), window
  // 0x01020304, 7 gaps, Complete in bit 63.
  const CanFrame window = encoded(WindowMsg{9, 20, true, 0x01020304, 7}, 0x2A);
  EXPECT_EQ(window.id, 0x18FF442Au);
  EXPECT_EQ(bytes(window), (std::array<std::uint8_t, 8>{0x50, 0x09, 0x04, 0x03, 0x02, 0x01, 0x07, 0x80}));
  const CanFrame length = encoded(WindowLengthMsg{9, 0x0102030405}, 0x2A);
  EXPECT_EQ(bytes(length), (std::array<std::uint8_t, 8>{0x01, 0x09, 0x05, 0x04, 0x03, 0x02, 0x01, 0x00}));
  // Page 2, tau 3 (0x02 | 3 << 2); window 5 in bits 16-19; ADEV 1.0 -> code 128 * 2^14 = 0x200000
  // in bits 20-41; MDEV 0.5 -> code 127 * 2^14 = 0x1FC000 in bits 42-63.
  const CanFrame wdev = encoded(WindowDevMsg{9, 3, 5, 1.0, 0.5}, 0x2A);
  EXPECT_EQ(bytes(wdev), (std::array<std::uint8_t, 8>{0x0E, 0x09, 0x05, 0x00, 0x00, 0x02, 0x00, 0x7F}));

  // Version 4, Ieee952 page 6: Tc (parameter 1) of Markov term 1 (bit 6): 0x06 | 1 << 3 | 1 << 6 =
  // 0x4E; 300 s = 0x43960000; 12.34 % -> 0x04D2. A sigma page, resolved (bit 7): 0x86.
  const CanFrame tc = encoded(Ieee952ParameterMsg{9, FitParameter::markov_tc, 1, false, 300.0f, 0.1234}, 0x2A);
  EXPECT_EQ(tc.id, 0x18FF432Au);
  EXPECT_EQ(bytes(tc), (std::array<std::uint8_t, 8>{0x4E, 0x09, 0x00, 0x00, 0x96, 0x43, 0xD2, 0x04}));
  const CanFrame sigma = encoded(Ieee952ParameterMsg{9, FitParameter::markov_sigma, 0, true, 2.0f, 0.1234}, 0x2A);
  EXPECT_EQ(bytes(sigma), (std::array<std::uint8_t, 8>{0x86, 0x09, 0x00, 0x00, 0x00, 0x40, 0xD2, 0x04}));
  // Page 7, the model: 2 Markov terms (bits 3-4), 1 sinusoid (bits 5-6), the filter (bit 7):
  // 0x07 | 2 << 3 | 1 << 5 | 0x80 = 0xB7; filter cut-off code 3, RunnerUp (bit 21), runner-up with
  // 1 Markov term (bits 22-23): 0x03 | 0x20 | 0x40 = 0x63; no sinusoid, the filter (bit 26): 0x04;
  // margin 1.5f = 0x3FC00000.
  const CanFrame model = encoded(Ieee952ModelMsg{9, 2, 1, true, 3, true, 1, 0, true, 1.5f}, 0x2A);
  EXPECT_EQ(bytes(model), (std::array<std::uint8_t, 8>{0xB7, 0x09, 0x63, 0x04, 0x00, 0x00, 0xC0, 0x3F}));

  const CanFrame counter = encoded(CounterInputMsg{0xA1B2C3D4, 0x55, true, false}, 0x10);
  EXPECT_EQ(counter.id, 0x0CFF5010u);
  EXPECT_EQ(counter.len, 6);
  EXPECT_EQ(bytes(counter), (std::array<std::uint8_t, 8>{0xD4, 0xC3, 0xB2, 0xA1, 0x55, 0x01, 0x00, 0x00}));
}

// --- round trips ---------------------------------------------------------------------------

/// One message of every kind with values on the wire's grid, so the round trip is exact.
std::vector<Message> typical_messages() {
  return {
      StatusMsg{17, NodeState::running, 32, 123456789},
      StatusFaultsMsg{17, 3, 2, 1, 1},
      TauDevMsg{17, 5, DevKind::adev, 1.25e-3f, std::exp2(10.5), NoiseType::white_fm, true},
      TauDevMsg{17, 5, DevKind::mdev, 9.5e-4f, std::exp2(9.25), NoiseType::flicker_fm, false},
      TauTermsMsg{17, 5, 987654321},
      TauInfoMsg{17, 5, 96, 2},
      MetaSamplingMsg{17, 2.5e-3f, 16},
      MetaClockMsg{17, 3600000, version},
      MetaScaleMsg{17, 1.5f, AngleUnit::arcsec, InputSource::gpio_quadrature},
      MetaConfigMsg{17, 0xDEADBEEF, 500},
      Ieee952Msg{17, Ieee952Term::angle_random_walk, true, 3.0e-5f, 0.0125, true},
      CounterInputMsg{4000000000u, 200, false, true},
      Ieee952SummaryMsg{17, Ieee952Status::ok, 0.9375f, 24, false, {5, 4}},
      WindowMsg{17, 12, true, 41, 1},
      WindowLengthMsg{17, 600000},
      WindowDevMsg{17, 5, 41 % 16, std::exp2(-10.0), std::exp2(-10.5)},
      Ieee952ParameterMsg{17, FitParameter::markov_sigma, 1, true, 0.25f, 0.125},
      Ieee952ModelMsg{17, 1, 0, true, 2, true, 2, 0, false, 3.5f},
      Ieee952UnconstrainedMsg{17, Ieee952Term::angle_random_walk, -2.5e-4f, std::exp2(-12.5)},  // on the 1/256 grid
  };
}

TEST(ProtocolRoundTrip, EveryMessageKind) {
  for (const Message& m : typical_messages()) {
    EXPECT_EQ(round_trip(m), m) << "variant index " << m.index();
  }
}

TEST(ProtocolRoundTrip, EveryFieldAtItsLimits) {
  const std::vector<Message> limits{
      StatusMsg{0, NodeState::starting, 0, 0},
      StatusMsg{255, NodeState::input_lost, max_taus, max40},
      StatusFaultsMsg{0, 0, 0, 0, 0},
      StatusFaultsMsg{255, 65535, 65535, 65535, 63},
      TauDevMsg{0, 0, DevKind::adev, 0.0f, 0.0, NoiseType::not_identified, false},
      TauDevMsg{255, 63, DevKind::mdev, FLT_MAX, std::exp2(4095 / 64.0 - 4), NoiseType::random_run_fm, true},
      TauDevMsg{1, 1, DevKind::adev, FLT_TRUE_MIN, std::exp2(1 / 64.0 - 4), NoiseType::white_pm, true},
      TauTermsMsg{0, 0, 0},
      TauTermsMsg{255, 63, max48},
      TauInfoMsg{0, 0, 1, 0},
      TauInfoMsg{255, 63, max40, 0},
      TauInfoMsg{1, 2, std::uint64_t{1} << 39, 39},
      MetaSamplingMsg{0, FLT_TRUE_MIN, 1},
      MetaSamplingMsg{255, FLT_MAX, 32768},
      MetaClockMsg{0, 0, 1},
      MetaClockMsg{255, max40, 255},
      MetaScaleMsg{0, FLT_TRUE_MIN, AngleUnit::pulse, InputSource::unknown},
      MetaScaleMsg{255, FLT_MAX, AngleUnit::arcsec, InputSource::simulated},
      MetaConfigMsg{0, 0, 100},
      MetaConfigMsg{255, 0xFFFFFFFF, 2000},
      Ieee952Msg{0, Ieee952Term::quantization, false, 0.0f, 0.0},
      Ieee952Msg{255, Ieee952Term::rate_ramp, true, FLT_MAX, 6.5535},
      Ieee952Msg{255, Ieee952Term::rate_ramp, false, FLT_MAX, 6.5535, true},
      Ieee952Msg{255, Ieee952Term::rate_ramp, true, FLT_MAX, 6.5535, true},
      Ieee952SummaryMsg{0, Ieee952Status::ok, 0.0f, 0, true, {0, 0}},
      Ieee952SummaryMsg{255, Ieee952Status::singular, FLT_MAX, 255, false, {31, 31}},
      Ieee952SummaryMsg{1, Ieee952Status::too_few_points, FLT_TRUE_MIN, 1, false, {1, 0}},
      CounterInputMsg{0, 0, false, false},
      CounterInputMsg{0xFFFFFFFF, 255, true, true},
      WindowMsg{0, 1, false, 0, 0},
      WindowMsg{255, max_taus - 1, true, 0xFFFFFFFF, 255},
      WindowMsg{1, 1, true, 0, 0},
      WindowLengthMsg{0, 4},
      WindowLengthMsg{255, max40},
      WindowDevMsg{0, 0, 0, 0.0, 0.0},
      WindowDevMsg{255, 63, 15, std::exp2(1.0 / 16384 - 128), std::exp2(128.0 - 1.0 / 16384)},  // codes 1, 2^22 - 1
      Ieee952ParameterMsg{0, FitParameter::markov_sigma, 0, false, 0.0f, 0.0},
      Ieee952ParameterMsg{255, FitParameter::sinusoid_frequency, 1, false, FLT_MAX, 6.5535},
      Ieee952ParameterMsg{1, FitParameter::filter_tf, 0, false, FLT_TRUE_MIN, 1e-4},
      Ieee952ModelMsg{0, 0, 0, false, 0, false, 0, 0, false, 0.0f},
      Ieee952ModelMsg{255, 2, 2, true, 31, true, 2, 2, true, FLT_MAX},
      Ieee952ModelMsg{1, 0, 2, false, 0, true, 0, 0, false, -FLT_MAX},
      Ieee952UnconstrainedMsg{0, Ieee952Term::quantization, 0.0f, 0.0},                                // no estimate
      Ieee952UnconstrainedMsg{255, Ieee952Term::rate_ramp, -FLT_MAX, std::exp2(128.0 - 1.0 / 256)},    // code 65535
      Ieee952UnconstrainedMsg{1, Ieee952Term::bias_instability, FLT_MAX, std::exp2(1.0 / 256 - 128)},  // code 1
      Ieee952UnconstrainedMsg{2, Ieee952Term::rate_random_walk, -FLT_TRUE_MIN, 1.0},
  };
  for (std::uint8_t node : {std::uint8_t{0}, max_node_address}) {
    for (const Message& m : limits) {
      const Message back = round_trip(m, node);
      if (const auto* ieee = std::get_if<Ieee952Msg>(&m)) {  // 0.01 % steps: 65535 * 1e-4 is not exact
        const auto& b = std::get<Ieee952Msg>(back);
        EXPECT_NEAR(b.rel_uncertainty, ieee->rel_uncertainty, 1e-12);
        EXPECT_EQ(b.value, ieee->value);
      } else if (const auto* par = std::get_if<Ieee952ParameterMsg>(&m)) {  // the same steps
        auto b = std::get<Ieee952ParameterMsg>(back);
        EXPECT_NEAR(b.rel_uncertainty, par->rel_uncertainty, 1e-12);
        b.rel_uncertainty = par->rel_uncertainty;
        EXPECT_EQ(b, *par);
      } else {
        EXPECT_EQ(back, m) << "variant index " << m.index();
      }
    }
  }
}

TEST(ProtocolRoundTrip, EveryEnumerationValue) {
  for (int k = 0; k < 8; ++k) {
    const auto noise = static_cast<NoiseType>(k);
    EXPECT_EQ(std::get<TauDevMsg>(round_trip(TauDevMsg{1, 1, DevKind::mdev, 1.0f, 2.0, noise, true})).noise, noise);
  }
  for (int k = 0; k < 3; ++k) {
    const auto state = static_cast<NodeState>(k);
    EXPECT_EQ(std::get<StatusMsg>(round_trip(StatusMsg{1, state, 1, 1})).state, state);
  }
  for (int k = 0; k < 5; ++k) {
    const auto unit = static_cast<AngleUnit>(k);
    const auto source = static_cast<InputSource>(k);
    const auto back = std::get<MetaScaleMsg>(round_trip(MetaScaleMsg{1, 1.0f, unit, source}));
    EXPECT_EQ(back.angle_unit, unit);
    EXPECT_EQ(back.input_source, source);
    const auto term = static_cast<Ieee952Term>(k);
    EXPECT_EQ(std::get<Ieee952Msg>(round_trip(Ieee952Msg{1, term, true, 1.0f, 0.5})).term, term);
  }
  for (int k = 0; k < 5; ++k) {
    const auto parameter = static_cast<FitParameter>(k);
    const Ieee952ParameterMsg m{1, parameter, 0, has_resolved(parameter), 1.0f, 0.5};
    EXPECT_EQ(std::get<Ieee952ParameterMsg>(round_trip(m)), m) << name(parameter);
  }
  for (int k = 0; k < 4; ++k) {
    const auto status = static_cast<Ieee952Status>(k);
    EXPECT_EQ(std::get<Ieee952SummaryMsg>(round_trip(Ieee952SummaryMsg{1, status, 1.0f, 9, true, {}})).status, status);
  }
}

// --- saturation and quantization -----------------------------------------------------------

TEST(ProtocolQuantization, CountsSaturateAtTheirFieldWidth) {
  // Oracle: min(v, 2^bits - 1) for each field's width in docs/protocol.md.
  const auto status = std::get<StatusMsg>(round_trip(StatusMsg{1, NodeState::running, 1, max40 + 5}));
  EXPECT_EQ(status.sample_count, max40);
  const auto faults = std::get<StatusFaultsMsg>(round_trip(StatusFaultsMsg{1, 65536, 1u << 31, 70000, 64}));
  EXPECT_EQ(faults.lost_edges, 65535u);
  EXPECT_EQ(faults.sample_gaps, 65535u);
  EXPECT_EQ(faults.tx_dropped_frames, 65535u);
  EXPECT_EQ(faults.bus_off_events, 63u);
  EXPECT_EQ(std::get<TauTermsMsg>(round_trip(TauTermsMsg{1, 1, ~std::uint64_t{0}})).n, max48);
  EXPECT_EQ(std::get<MetaClockMsg>(round_trip(MetaClockMsg{1, max40 + 1, 1})).uptime_ms, max40);
  EXPECT_EQ(std::get<Ieee952SummaryMsg>(round_trip(Ieee952SummaryMsg{1, Ieee952Status::ok, 1.0f, 256, true, {}})).points,
            255u);
}

TEST(ProtocolQuantization, EdfIsWithinHalfAStepOfLog2) {
  // Step 1/64 in log2(edf): the decoded EDF is within a factor 2^(1/128) of the sent one.
  const double half_step = std::exp2(1.0 / 128) * (1 + 1e-12);
  for (double log2_edf = -3.9; log2_edf < 59.9; log2_edf += 0.0137) {
    const double edf = std::exp2(log2_edf);
    const double back =
        std::get<TauDevMsg>(round_trip(TauDevMsg{1, 1, DevKind::adev, 1.0f, edf, NoiseType::white_fm, true})).edf;
    EXPECT_LE(back / edf, half_step) << edf;
    EXPECT_GE(back / edf, 1 / half_step) << edf;
  }
  // Outside the range the code clamps; 0 means "not available" and stays 0.
  const auto sent = [](double edf) {
    return std::get<TauDevMsg>(round_trip(TauDevMsg{1, 1, DevKind::adev, 1.0f, edf, NoiseType::white_fm, true})).edf;
  };
  EXPECT_EQ(sent(1e-12), std::exp2(1 / 64.0 - 4));
  EXPECT_EQ(sent(1e30), std::exp2(4095 / 64.0 - 4));
  EXPECT_EQ(sent(0.0), 0.0);
}

TEST(ProtocolQuantization, EveryEdfNoiseAndValidCodeIsCanonical) {
  // Exhaustive over the 16-bit tail of the ADEV page: every code decodes and re-encodes unchanged.
  CanFrame f = encoded(TauDevMsg{3, 4, DevKind::adev, 0.5f, 1.0, NoiseType::white_fm, true}, 0x07);
  for (unsigned tail = 0; tail < 65536; ++tail) {
    f.data[6] = static_cast<std::uint8_t>(tail);
    f.data[7] = static_cast<std::uint8_t>(tail >> 8);
    const Decoded d = decode(f);
    ASSERT_EQ(d.error, ProtocolError::none) << tail;
    EXPECT_EQ(bytes(encoded(d.message, d.node)), bytes(f)) << tail;
  }
}

TEST(ProtocolQuantization, EverySummaryCodeIsCanonicalOrOutOfRange) {
  // Exhaustive over the summary page's codes (byte 0 bits 3-7, all of byte 7, points 0, 1, 128,
  // 255): every combination decodes, except QuantizationWhite with a tau left out, and what decodes
  // re-encodes unchanged.
  CanFrame f = encoded(Ieee952SummaryMsg{3, Ieee952Status::ok, 0.5f, 10, true, {}}, 0x07);
  int accepted = 0;
  for (unsigned avar = 0; avar < 32; ++avar) {
    for (unsigned tail = 0; tail < 256; ++tail) {
      for (unsigned points : {0u, 1u, 128u, 255u}) {
        f.data[0] = static_cast<std::uint8_t>(ieee952_summary_page | avar << 3);
        f.data[6] = static_cast<std::uint8_t>(points);
        f.data[7] = static_cast<std::uint8_t>(tail);
        const Decoded d = decode(f);
        const bool white = (tail & 0x20u) != 0, none_left_out = avar == 0 && (tail & 0x1Fu) == 0;
        if (white && !none_left_out) {
          EXPECT_EQ(d.error, ProtocolError::out_of_range) << avar << " " << tail;
          continue;
        }
        ASSERT_EQ(d.error, ProtocolError::none) << avar << " " << tail;
        EXPECT_EQ(bytes(encoded(d.message, d.node)), bytes(f)) << avar << " " << tail;
        ++accepted;
      }
    }
  }
  // Per points value: not white, any AVAR code x any MVAR code x any status; white, only codes 0.
  EXPECT_EQ(accepted, 4 * (32 * 32 * 4 + 4));
}

TEST(ProtocolQuantization, WindowDeviationsWithinHalfAStepOfLog2) {
  // Step 2^-14 in log2(dev): the decoded deviation is within a factor 2^(2^-15) (2.1e-5) of the
  // sent one. Outside [2^-128, 2^128) the code clamps; 0 means "no estimate" and stays 0.
  const double half_step = std::exp2(1.0 / 32768) * (1 + 1e-12);
  const auto sent = [](double adev, double mdev) {
    return std::get<WindowDevMsg>(round_trip(WindowDevMsg{1, 2, 3, adev, mdev}));
  };
  for (double log2_dev = -126.9; log2_dev < 127.9; log2_dev += 0.0713) {
    const double dev = std::exp2(log2_dev);
    const WindowDevMsg back = sent(dev, 0.5 * dev);
    EXPECT_LE(back.adev_angle_per_s / dev, half_step) << dev;
    EXPECT_GE(back.adev_angle_per_s / dev, 1 / half_step) << dev;
    EXPECT_LE(back.mdev_angle_per_s / (0.5 * dev), half_step) << dev;
    EXPECT_GE(back.mdev_angle_per_s / (0.5 * dev), 1 / half_step) << dev;
  }
  EXPECT_EQ(sent(window_dev_floor, 0.0).adev_angle_per_s, std::exp2(1.0 / 16384 - 128));
  EXPECT_EQ(sent(1e-300, 0.0).adev_angle_per_s, std::exp2(1.0 / 16384 - 128));
  EXPECT_EQ(sent(1e-300, 0.0).mdev_angle_per_s, 0.0);
  EXPECT_EQ(sent(1e300, 1.0).adev_angle_per_s, std::exp2(128.0 - 1.0 / 16384));
  EXPECT_EQ(sent(1e300, 1.0).mdev_angle_per_s, 1.0);
}

TEST(ProtocolQuantization, UnconstrainedEstimateSignedAndItsUncertaintyWithinHalfAStepOfLog2) {
  // Oracle: the layout of docs/protocol.md (Ieee952Unconstrained): the value is the float32 itself,
  // of either sign; the uncertainty goes as log2 in 1/256 steps, so the decoded one is within half a
  // step, 2^(1/512) - 1 = 0.136 %, of what was sent, and clamps to codes 1 and 65535 outside
  // [2^(1/256 - 128), 2^(128 - 1/256)] (saturation: a larger uncertainty reads as the largest).
  std::mt19937_64 rng(952);
  std::uniform_real_distribution<double> log2_u(-127.0, 127.0);
  for (int k = 0; k < 10000; ++k) {
    const double u = std::exp2(log2_u(rng));
    const float value = (k % 2 ? -1.0f : 1.0f) * static_cast<float>(u) * 0.75f;
    const auto back = std::get<Ieee952UnconstrainedMsg>(
        round_trip(Ieee952UnconstrainedMsg{1, Ieee952Term::rate_random_walk, value, u}));
    EXPECT_EQ(back.value, value);  // the sign too: a negative unconstrained square
    EXPECT_LE(std::abs(std::log2(back.uncertainty) - std::log2(u)), 1.0 / 512 + 1e-12) << u;
  }
  const auto saturated = [](double u) {
    return std::get<Ieee952UnconstrainedMsg>(round_trip(Ieee952UnconstrainedMsg{3, Ieee952Term::rate_ramp, -1.0f, u}))
        .uncertainty;
  };
  EXPECT_EQ(saturated(1e300), std::exp2(65535.0 / 256 - 128));
  EXPECT_EQ(saturated(DBL_MAX), std::exp2(65535.0 / 256 - 128));
  EXPECT_EQ(saturated(1e-300), std::exp2(1.0 / 256 - 128));
  EXPECT_EQ(saturated(DBL_TRUE_MIN), std::exp2(1.0 / 256 - 128));
  // Byte for byte: N, -2.5e-4f = 0xB983126F, 2^-12.5: code 256 (128 - 12.5) = 29568 = 0x7380.
  const CanFrame f = encoded(Ieee952UnconstrainedMsg{9, Ieee952Term::angle_random_walk, -2.5e-4f, std::exp2(-12.5)}, 0x2A);
  EXPECT_EQ(f.id, 0x18FF452Au);
  EXPECT_EQ(f.len, 8);
  const std::array<std::uint8_t, 8> want{0x01, 9, 0x6F, 0x12, 0x83, 0xB9, 0x80, 0x73};
  for (std::size_t k = 0; k < 8; ++k) EXPECT_EQ(f.data[k], want[k]) << k;
}

TEST(ProtocolDecode, UnconstrainedFramesOutOfRangeOrWithUnknownTermsAreRefused) {
  // Oracle: the layout and ranges of docs/protocol.md (Ieee952Unconstrained).
  CanFrame f;
  EXPECT_EQ(encode(Ieee952UnconstrainedMsg{0, Ieee952Term::quantization, 1.0f, 0.0}, 1, f), ProtocolError::out_of_range)
      << "a value without an uncertainty";
  EXPECT_EQ(encode(Ieee952UnconstrainedMsg{0, Ieee952Term::quantization, NAN, 1.0}, 1, f), ProtocolError::out_of_range);
  EXPECT_EQ(encode(Ieee952UnconstrainedMsg{0, Ieee952Term::quantization, -INFINITY, 1.0}, 1, f),
            ProtocolError::out_of_range);
  EXPECT_EQ(encode(Ieee952UnconstrainedMsg{0, Ieee952Term::quantization, 1.0f, -1.0}, 1, f), ProtocolError::out_of_range);
  EXPECT_EQ(encode(Ieee952UnconstrainedMsg{0, Ieee952Term::quantization, 1.0f, INFINITY}, 1, f),
            ProtocolError::out_of_range);
  EXPECT_EQ(encode(Ieee952UnconstrainedMsg{0, Ieee952Term::quantization, 1.0f, NAN}, 1, f), ProtocolError::out_of_range);
  EXPECT_EQ(encode(Ieee952UnconstrainedMsg{0, static_cast<Ieee952Term>(5), 1.0f, 1.0}, 1, f), ProtocolError::out_of_range);
  const CanFrame good = encoded(Ieee952UnconstrainedMsg{4, Ieee952Term::rate_ramp, -3.0f, 0.5}, 7);
  for (std::uint8_t term = 5; term < 8; ++term) {
    CanFrame g = good;
    g.data[0] = term;
    EXPECT_EQ(decode(g).error, ProtocolError::unknown_page) << int(term);
  }
  for (unsigned bit = 3; bit < 8; ++bit) {
    CanFrame g = good;
    g.data[0] = static_cast<std::uint8_t>(g.data[0] | 1u << bit);
    EXPECT_EQ(decode(g).error, ProtocolError::reserved_bits) << bit;
  }
  CanFrame no_uncertainty = good;
  no_uncertainty.data[6] = no_uncertainty.data[7] = 0;
  EXPECT_EQ(decode(no_uncertainty).error, ProtocolError::out_of_range) << "code 0 with a value";
  CanFrame nan = good;
  nan.data[5] = 0x7F, nan.data[4] = 0xC0;
  EXPECT_EQ(decode(nan).error, ProtocolError::out_of_range);
}

TEST(ProtocolQuantization, CountsOfTheWindowPageSaturate) {
  EXPECT_EQ(std::get<WindowMsg>(round_trip(WindowMsg{1, 3, true, 9, 256})).gaps, 255u);
}

TEST(ProtocolQuantization, RelativeUncertaintyInHundredthsOfAPercent) {
  const auto sent = [](double rel) {
    return std::get<Ieee952Msg>(round_trip(Ieee952Msg{1, Ieee952Term::rate_random_walk, true, 1.0f, rel})).rel_uncertainty;
  };
  EXPECT_NEAR(sent(0.123456), 0.1235, 1e-12);  // nearest 1e-4
  EXPECT_NEAR(sent(6.6), 6.5535, 1e-12);       // saturates at 655.35 %
  EXPECT_NEAR(sent(std::numeric_limits<double>::infinity()), 6.5535, 1e-12);
  EXPECT_EQ(sent(0.0), 0.0);
}

// --- rejections ----------------------------------------------------------------------------

TEST(ProtocolEncode, RejectsWhatTheWireCannotCarryAndLeavesTheFrameAlone) {
  const auto rejects = [](const Message& m, std::uint8_t node = 1) {
    CanFrame f;
    f.id = 0x123;
    const ProtocolError e = encode(m, node, f);
    EXPECT_EQ(f.id, 0x123u) << "frame modified";
    return e;
  };
  constexpr auto range = ProtocolError::out_of_range;
  EXPECT_EQ(rejects(StatusMsg{}, 0xFE), ProtocolError::bad_address);
  EXPECT_EQ(rejects(CounterInputMsg{}, 0xFF), ProtocolError::bad_address);
  EXPECT_EQ(rejects(StatusMsg{1, static_cast<NodeState>(3), 1, 1}), range);
  EXPECT_EQ(rejects(StatusMsg{1, NodeState::running, max_taus + 1, 1}), range);
  const TauDevMsg dev{1, 1, DevKind::adev, 1.0f, 10.0, NoiseType::white_fm, true};
  for (float bad : {nan_f, inf_f, -1.0f, -FLT_TRUE_MIN}) {
    TauDevMsg m = dev;
    m.dev_angle_per_s = bad;
    EXPECT_EQ(rejects(m), range) << bad;
  }
  for (double bad : {double(nan_f), double(inf_f), -1.0}) {
    TauDevMsg m = dev;
    m.edf = bad;
    EXPECT_EQ(rejects(m), range) << bad;
  }
  TauDevMsg m = dev;
  m.tau_index = max_taus;
  EXPECT_EQ(rejects(m), range);
  m = dev;
  m.kind = static_cast<DevKind>(2);
  EXPECT_EQ(rejects(m), range);
  m = dev;
  m.noise = static_cast<NoiseType>(8);
  EXPECT_EQ(rejects(m), range);
  EXPECT_EQ(rejects(TauTermsMsg{1, max_taus, 1}), range);
  EXPECT_EQ(rejects(TauInfoMsg{1, 1, 0, 0}), range);          // m = 0
  EXPECT_EQ(rejects(TauInfoMsg{1, 1, max40 + 1, 0}), range);  // m >= 2^40
  EXPECT_EQ(rejects(TauInfoMsg{1, 1, 96, 6}), range);         // 64 does not divide 96
  EXPECT_EQ(rejects(TauInfoMsg{1, 1, 1, 40}), range);
  EXPECT_EQ(rejects(TauInfoMsg{1, max_taus, 1, 0}), range);
  EXPECT_EQ(rejects(MetaSamplingMsg{1, 0.0f, 8}), range);
  EXPECT_EQ(rejects(MetaSamplingMsg{1, -1e-3f, 8}), range);
  EXPECT_EQ(rejects(MetaSamplingMsg{1, nan_f, 8}), range);
  EXPECT_EQ(rejects(MetaSamplingMsg{1, 1e-3f, 0}), range);
  EXPECT_EQ(rejects(MetaSamplingMsg{1, 1e-3f, 12}), range);
  EXPECT_EQ(rejects(MetaClockMsg{1, 1, 0}), range);
  EXPECT_EQ(rejects(MetaScaleMsg{1, 0.0f, AngleUnit::deg, InputSource::unknown}), range);
  EXPECT_EQ(rejects(MetaScaleMsg{1, inf_f, AngleUnit::deg, InputSource::unknown}), range);
  EXPECT_EQ(rejects(MetaScaleMsg{1, 1.0f, static_cast<AngleUnit>(5), InputSource::unknown}), range);
  EXPECT_EQ(rejects(MetaScaleMsg{1, 1.0f, AngleUnit::deg, static_cast<InputSource>(5)}), range);
  EXPECT_EQ(rejects(MetaConfigMsg{1, 1, 99}), range);
  EXPECT_EQ(rejects(MetaConfigMsg{1, 1, 2001}), range);
  EXPECT_EQ(rejects(Ieee952Msg{1, static_cast<Ieee952Term>(5), true, 1.0f, 0.1}), range);
  EXPECT_EQ(rejects(Ieee952Msg{1, Ieee952Term::quantization, true, -1.0f, 0.1}), range);
  EXPECT_EQ(rejects(Ieee952Msg{1, Ieee952Term::quantization, true, nan_f, 0.1}), range);
  EXPECT_EQ(rejects(Ieee952Msg{1, Ieee952Term::quantization, true, 1.0f, -0.1}), range);
  EXPECT_EQ(rejects(Ieee952Msg{1, Ieee952Term::quantization, true, 1.0f, double(nan_f)}), range);
  const Ieee952SummaryMsg summary{1, Ieee952Status::ok, 1.0f, 10, false, {3, 2}};
  Ieee952SummaryMsg bad = summary;
  bad.status = static_cast<Ieee952Status>(4);
  EXPECT_EQ(rejects(bad), range);
  for (float chi2 : {nan_f, inf_f, -1.0f, -FLT_TRUE_MIN}) {
    bad = summary;
    bad.chi2_per_dof = chi2;
    EXPECT_EQ(rejects(bad), range) << chi2;
  }
  for (std::size_t k = 0; k < 2; ++k) {
    bad = summary;
    bad.excluded_below_log2_m[k] = 32;  // 5 bits
    EXPECT_EQ(rejects(bad), range) << k;
    bad = summary;
    bad.quantization_white = true;  // white quantization leaves nothing out
    bad.excluded_below_log2_m[1 - k] = 0;
    EXPECT_EQ(rejects(bad), range) << k;
  }
  // Version 4's pages.
  const Ieee952ParameterMsg parameter{1, FitParameter::markov_sigma, 1, true, 1.0f, 0.1};
  EXPECT_EQ(rejects(Ieee952ParameterMsg{1, static_cast<FitParameter>(5), 0, false, 1.0f, 0.1}), range);
  for (FitParameter p : {FitParameter::markov_sigma, FitParameter::markov_tc, FitParameter::sinusoid_amplitude,
                         FitParameter::sinusoid_frequency})
    EXPECT_EQ(rejects(Ieee952ParameterMsg{1, p, 2, false, 1.0f, 0.1}), range) << name(p);           // two terms: index 0, 1
  EXPECT_EQ(rejects(Ieee952ParameterMsg{1, FitParameter::filter_tf, 1, false, 1.0f, 0.1}), range);  // one filter
  for (FitParameter p : {FitParameter::markov_tc, FitParameter::filter_tf, FitParameter::sinusoid_frequency})
    EXPECT_EQ(rejects(Ieee952ParameterMsg{1, p, 0, true, 1.0f, 0.1}), range) << name(p);  // no Resolved there
  for (float bad : {nan_f, inf_f, -1.0f, -FLT_TRUE_MIN}) {
    Ieee952ParameterMsg b = parameter;
    b.value = bad;
    EXPECT_EQ(rejects(b), range) << bad;
  }
  for (double bad : {double(nan_f), -0.1}) {
    Ieee952ParameterMsg b = parameter;
    b.rel_uncertainty = bad;
    EXPECT_EQ(rejects(b), range) << bad;
  }
  const Ieee952ModelMsg model{1, 1, 1, true, 2, true, 2, 1, true, 2.0f};
  for (auto mutate : std::vector<void (*)(Ieee952ModelMsg&)>{
           [](Ieee952ModelMsg& b) { b.markov = 3; }, [](Ieee952ModelMsg& b) { b.sinusoids = 3; },
           [](Ieee952ModelMsg& b) { b.runner_up_markov = 3; }, [](Ieee952ModelMsg& b) { b.runner_up_sinusoids = 3; },
           [](Ieee952ModelMsg& b) { b.bandwidth_excluded_below_log2_m = 32; },
           [](Ieee952ModelMsg& b) { b.criterion_margin = nan_f; }, [](Ieee952ModelMsg& b) { b.criterion_margin = -inf_f; },
           [](Ieee952ModelMsg& b) { b.runner_up = false; }}) {  // no runner-up, yet its fields
    Ieee952ModelMsg b = model;
    mutate(b);
    EXPECT_EQ(rejects(b), range);
  }
  EXPECT_EQ(rejects(WindowMsg{1, 0, true, 1, 0}), range);         // no window taus
  EXPECT_EQ(rejects(WindowMsg{1, max_taus, true, 1, 0}), range);  // 6 bits
  EXPECT_EQ(rejects(WindowMsg{1, 3, false, 1, 0}), range);        // no window completed, yet a number
  EXPECT_EQ(rejects(WindowMsg{1, 3, false, 0, 1}), range);
  EXPECT_EQ(rejects(WindowLengthMsg{1, 3}), range);
  EXPECT_EQ(rejects(WindowLengthMsg{1, max40 + 1}), range);
  EXPECT_EQ(rejects(WindowDevMsg{1, max_taus, 0, 1.0, 1.0}), range);
  EXPECT_EQ(rejects(WindowDevMsg{1, 1, 16, 1.0, 1.0}), range);
  for (double bad : {double(nan_f), double(inf_f), -1.0, -1e-300}) {
    EXPECT_EQ(rejects(WindowDevMsg{1, 1, 1, bad, 1.0}), range) << bad;
    EXPECT_EQ(rejects(WindowDevMsg{1, 1, 1, 1.0, bad}), range) << bad;
  }
}

/// decode() of a valid frame of `m` after `mutate` changed it.
template <class Mutate>
ProtocolError decode_mutated(const Message& m, Mutate mutate) {
  CanFrame f = encoded(m, 0x11);
  mutate(f);
  const Decoded d = decode(f);
  return d.error;
}
void put_float(CanFrame& f, float v) {
  std::uint32_t u = 0;
  static_assert(sizeof u == sizeof v);
  std::memcpy(&u, &v, sizeof u);
  for (int i = 0; i < 4; ++i) f.data[2 + i] = static_cast<std::uint8_t>(u >> (8 * i));
}

TEST(ProtocolDecode, RejectsMalformedFramesWithTheRightReason) {
  const Message status = StatusMsg{1, NodeState::running, 4, 1000};
  const Message adev = TauDevMsg{1, 2, DevKind::adev, 1.0f, 10.0, NoiseType::white_fm, true};
  const Message info = TauInfoMsg{1, 2, 96, 2};
  const Message sampling = MetaSamplingMsg{1, 1e-3f, 8};
  const Message clock = MetaClockMsg{1, 1000, 1};
  const Message scale = MetaScaleMsg{1, 1.0f, AngleUnit::deg, InputSource::unknown};
  const Message config = MetaConfigMsg{1, 7, 1000};
  const Message ieee = Ieee952Msg{1, Ieee952Term::bias_instability, true, 1.0f, 0.1};
  const Message summary = Ieee952SummaryMsg{1, Ieee952Status::ok, 1.0f, 10, true, {0, 0}};
  const Message counter = CounterInputMsg{1, 1, false, false};
  const Message window = WindowMsg{1, 4, true, 3, 0};
  const Message window_length = WindowLengthMsg{1, 1000};
  const Message window_dev = WindowDevMsg{1, 2, 3, 1.0, 0.5};

  // Envelope, in the order decode() checks it.
  EXPECT_EQ(decode_mutated(status, [](CanFrame& f) { f.error = true; }), ProtocolError::error_frame);
  EXPECT_EQ(decode_mutated(status, [](CanFrame& f) { f.extended = false; }), ProtocolError::not_extended);
  EXPECT_EQ(decode_mutated(status, [](CanFrame& f) { f.id = 0x14FF4411; }), ProtocolError::unknown_id);   // PGN
  EXPECT_EQ(decode_mutated(status, [](CanFrame& f) { f.id = 0x18FF4011; }), ProtocolError::unknown_id);   // priority
  EXPECT_EQ(decode_mutated(status, [](CanFrame& f) { f.id |= 0x20000000; }), ProtocolError::unknown_id);  // > 29 bits
  EXPECT_EQ(decode_mutated(status, [](CanFrame& f) { f.id = 0x14FF40FE; }), ProtocolError::bad_address);
  EXPECT_EQ(decode_mutated(counter, [](CanFrame& f) { f.id = 0x0CFF50FF; }), ProtocolError::bad_address);
  EXPECT_EQ(decode_mutated(status, [](CanFrame& f) { f.fd = true; }), ProtocolError::fd_frame);
  EXPECT_EQ(decode_mutated(status, [](CanFrame& f) { f.fd = true, f.id = 0x14FF40FE; }), ProtocolError::bad_address);
  for (std::uint8_t len : {0, 6, 7, 9, 64}) {
    EXPECT_EQ(decode_mutated(adev, [&](CanFrame& f) { f.len = len; }), ProtocolError::wrong_length) << int(len);
  }
  EXPECT_EQ(decode_mutated(counter, [](CanFrame& f) { f.len = 8; }), ProtocolError::wrong_length);
  EXPECT_EQ(decode_mutated(status, [](CanFrame& f) { f.len = 7, f.data[0] = 2; }), ProtocolError::wrong_length);

  // Multiplexor values without a layout.
  EXPECT_EQ(decode_mutated(status, [](CanFrame& f) { f.data[0] = 2; }), ProtocolError::unknown_page);
  EXPECT_EQ(decode_mutated(status, [](CanFrame& f) { f.data[0] = 3; }), ProtocolError::unknown_page);
  EXPECT_EQ(decode_mutated(window, [](CanFrame& f) { f.data[0] |= 3; }), ProtocolError::unknown_page);
  // Ieee952 has none left: 0-4 the terms, 5 the fit summary, 6 and 7 (version 4; a version-3
  // decoder refused them as unknown pages) a parameter and the model. A term frame renumbered 6
  // reads as a Markov sigma; renumbered 7, its value bytes make a runner-up margin without a
  // runner-up.
  EXPECT_EQ(decode_mutated(ieee, [&](CanFrame& f) { f.data[0] = ieee952_parameter_page; }), ProtocolError::none);
  EXPECT_EQ(decode_mutated(ieee, [&](CanFrame& f) { f.data[0] = ieee952_model_page; }), ProtocolError::out_of_range);

  // Reserved bits.
  for (std::uint8_t bit = 4; bit < 8; ++bit) {
    EXPECT_EQ(decode_mutated(status, [&](CanFrame& f) { f.data[0] |= std::uint8_t(1u << bit); }),
              ProtocolError::reserved_bits);
    if (bit == 4) continue;  // Fitted since version 2
    EXPECT_EQ(decode_mutated(ieee, [&](CanFrame& f) { f.data[0] |= std::uint8_t(1u << bit); }),
              ProtocolError::reserved_bits);
  }
  for (std::uint8_t bit = 2; bit < 8; ++bit) {
    for (const Message& meta : {sampling, clock, scale, config}) {
      EXPECT_EQ(decode_mutated(meta, [&](CanFrame& f) { f.data[0] |= std::uint8_t(1u << bit); }),
                ProtocolError::reserved_bits);
    }
    EXPECT_EQ(decode_mutated(counter, [&](CanFrame& f) { f.data[5] |= std::uint8_t(1u << bit); }),
              ProtocolError::reserved_bits);
    EXPECT_EQ(decode_mutated(window_length, [&](CanFrame& f) { f.data[0] |= std::uint8_t(1u << bit); }),
              ProtocolError::reserved_bits);
  }
  for (std::uint8_t bit = 0; bit < 8; ++bit) {
    EXPECT_EQ(decode_mutated(window_length, [&](CanFrame& f) { f.data[7] |= std::uint8_t(1u << bit); }),
              ProtocolError::reserved_bits);
    if (bit == 7) continue;  // Complete
    EXPECT_EQ(decode_mutated(window, [&](CanFrame& f) { f.data[7] |= std::uint8_t(1u << bit); }),
              ProtocolError::reserved_bits);
  }

  const Message parameter = Ieee952ParameterMsg{1, FitParameter::filter_tf, 0, false, 0.01f, 0.1};
  const Message model = Ieee952ModelMsg{1, 1, 0, false, 0, false, 0, 0, false, 0.0f};
  for (std::uint8_t bit = 3; bit < 8; ++bit)  // byte 3 bits 3-7 of the model page
    EXPECT_EQ(decode_mutated(model, [&](CanFrame& f) { f.data[3] |= std::uint8_t(1u << bit); }),
              ProtocolError::reserved_bits);

  // Values out of range.
  constexpr auto range = ProtocolError::out_of_range;
  for (std::uint8_t code : {5, 6, 7})  // Parameter codes without a meaning
    EXPECT_EQ(decode_mutated(parameter, [&](CanFrame& f) { f.data[0] = std::uint8_t(6u | code << 3); }), range);
  EXPECT_EQ(decode_mutated(parameter, [](CanFrame& f) { f.data[0] |= 0x40; }), range);  // a second filter
  EXPECT_EQ(decode_mutated(parameter, [](CanFrame& f) { f.data[0] |= 0x80; }), range);  // Resolved on a time
  EXPECT_EQ(decode_mutated(parameter, [](CanFrame& f) { put_float(f, -1.0f); }), range);
  EXPECT_EQ(decode_mutated(model, [](CanFrame& f) { f.data[0] |= 3u << 3; }), range);  // 3 Markov terms
  EXPECT_EQ(decode_mutated(model, [](CanFrame& f) { f.data[0] |= 3u << 5; }), range);  // 3 sinusoids
  EXPECT_EQ(decode_mutated(model, [](CanFrame& f) { f.data[3] = 4; }), range);         // runner-up field, no runner-up
  EXPECT_EQ(decode_mutated(model, [](CanFrame& f) { f.data[2] = 0x20, f.data[7] = 0x7F, f.data[6] = 0x80; }),
            range);                                                                 // margin inf
  EXPECT_EQ(decode_mutated(status, [](CanFrame& f) { f.data[0] = 0x0C; }), range);  // state 3
  EXPECT_EQ(decode_mutated(status, [](CanFrame& f) { f.data[2] = max_taus + 1; }), range);
  for (float bad : {nan_f, inf_f, -inf_f, -1.0f}) {
    EXPECT_EQ(decode_mutated(adev, [&](CanFrame& f) { put_float(f, bad); }), range) << bad;
  }
  EXPECT_EQ(decode_mutated(info, [](CanFrame& f) { f.data[2] = f.data[3] = 0; }), range);  // m = 0
  EXPECT_EQ(decode_mutated(info, [](CanFrame& f) { f.data[7] = 6; }), range);              // 2^6 does not divide 96
  EXPECT_EQ(decode_mutated(info, [](CanFrame& f) { f.data[7] = 200; }), range);
  for (float bad : {0.0f, -1e-3f, nan_f, inf_f}) {
    EXPECT_EQ(decode_mutated(sampling, [&](CanFrame& f) { put_float(f, bad); }), range) << bad;
    EXPECT_EQ(decode_mutated(scale, [&](CanFrame& f) { put_float(f, bad); }), range) << bad;
  }
  EXPECT_EQ(decode_mutated(sampling, [](CanFrame& f) { f.data[6] = 3; }), range);  // S = 3
  EXPECT_EQ(decode_mutated(sampling, [](CanFrame& f) { f.data[6] = 0; }), range);  // S = 0
  EXPECT_EQ(decode_mutated(clock, [](CanFrame& f) { f.data[7] = 0; }), range);     // version 0
  EXPECT_EQ(decode_mutated(scale, [](CanFrame& f) { f.data[6] = 5; }), range);
  EXPECT_EQ(decode_mutated(scale, [](CanFrame& f) { f.data[7] = 255; }), range);
  EXPECT_EQ(decode_mutated(config, [](CanFrame& f) { f.data[6] = 99, f.data[7] = 0; }), range);
  EXPECT_EQ(decode_mutated(config, [](CanFrame& f) { f.data[6] = 0xD1, f.data[7] = 0x07; }), range);  // 2001 ms
  for (float bad : {nan_f, -1.0f, inf_f}) {
    EXPECT_EQ(decode_mutated(ieee, [&](CanFrame& f) { put_float(f, bad); }), range) << bad;
    EXPECT_EQ(decode_mutated(summary, [&](CanFrame& f) { put_float(f, bad); }), range) << bad;  // chi2/dof
  }
  EXPECT_EQ(decode_mutated(window, [](CanFrame& f) { f.data[0] = 0; }), range);  // no window taus
  EXPECT_EQ(decode_mutated(window, [](CanFrame& f) { f.data[7] = 0; }), range);  // incomplete, number 3
  EXPECT_EQ(decode_mutated(window_length, [](CanFrame& f) { f.data[2] = 3, f.data[3] = 0; }), range);  // length 3
  EXPECT_EQ(decode_mutated(window_dev, [](CanFrame& f) { f.data[2] = 0xFF; }), ProtocolError::none);   // any code
  // White quantization with points left out.
  EXPECT_EQ(decode_mutated(summary, [](CanFrame& f) { f.data[0] |= 1u << 3; }), range);
  EXPECT_EQ(decode_mutated(summary, [](CanFrame& f) { f.data[7] |= 1u; }), range);
}

TEST(ProtocolDecode, VersionOneIeee952FramesStillDecode) {
  // A version-1 node: Fitted (then reserved) is 0, an unresolved term is all zeros. Written out by
  // hand from the version-1 layout: term N resolved, 3.0e-5f = 0x37FBA882, 1.25 % = 125.
  CanFrame f;
  f.id = 0x18FF4310;
  f.extended = true;
  f.len = 8;
  const std::array<std::uint8_t, 8> resolved{0x09, 0x21, 0x82, 0xA8, 0xFB, 0x37, 0x7D, 0x00};
  std::copy(resolved.begin(), resolved.end(), f.data.begin());
  Decoded d = decode(f);
  ASSERT_EQ(d.error, ProtocolError::none) << name(d.error);
  EXPECT_EQ(std::get<Ieee952Msg>(d.message),
            (Ieee952Msg{0x21, Ieee952Term::angle_random_walk, true, 3.0e-5f, 0.0125, false}));
  const std::array<std::uint8_t, 8> unresolved{0x04, 0x21, 0, 0, 0, 0, 0, 0};
  std::copy(unresolved.begin(), unresolved.end(), f.data.begin());
  d = decode(f);
  ASSERT_EQ(d.error, ProtocolError::none) << name(d.error);
  EXPECT_EQ(std::get<Ieee952Msg>(d.message), (Ieee952Msg{0x21, Ieee952Term::rate_ramp, false, 0.0f, 0.0, false}));
}

TEST(ProtocolDecode, RandomFramesNeverCrashAndAcceptedOnesAreCanonical) {
  // Half the frames are random, half are valid frames with 1 to 3 random bits flipped (in the data,
  // the identifier, the length or the flags: extended, FD). Oracle: any frame decode() accepts must come back bit
  // for bit from encode() of its message.
  std::mt19937_64 rng(20240611);
  const std::vector<Message> valid = typical_messages();
  std::map<std::size_t, int> accepted;  // by variant index
  std::map<ProtocolError, int> reasons;
  for (int i = 0; i < 200000; ++i) {
    CanFrame f;
    if (i % 2 == 0) {
      f.id = static_cast<std::uint32_t>(rng()) & 0x3FFFFFFF;
      f.extended = rng() % 8 != 0;
      f.fd = rng() % 8 == 0;
      f.error = rng() % 8 == 0;
      f.len = static_cast<std::uint8_t>(rng() % 65);
      for (auto& b : f.data) b = static_cast<std::uint8_t>(rng());
    } else {
      f = encoded(valid[rng() % valid.size()], static_cast<std::uint8_t>(rng() % (max_node_address + 1)));
      for (int flips = 1 + static_cast<int>(rng() % 3); flips > 0; --flips) {
        const unsigned where = static_cast<unsigned>(rng() % 100);
        const unsigned bit = static_cast<unsigned>(rng() % 64);
        if (where < 90) f.data[bit / 8] ^= static_cast<std::uint8_t>(1u << (bit % 8));
        else if (where < 96) f.id ^= 1u << (bit % 30);
        else if (where < 98) f.len = static_cast<std::uint8_t>(bit % 10);
        else if (where < 99) f.extended = !f.extended;
        else f.fd = !f.fd;
      }
    }
    const Decoded d = decode(f);
    ++reasons[d.error];
    if (d.error != ProtocolError::none) continue;
    ++accepted[d.message.index()];
    CanFrame again;
    ASSERT_EQ(encode(d.message, d.node, again), ProtocolError::none);
    EXPECT_EQ(again.id, f.id);
    EXPECT_EQ(again.len, f.len);
    for (std::size_t k = 0; k < f.len; ++k) ASSERT_EQ(again.data[k], f.data[k]) << "frame " << i << " byte " << k;
  }
  EXPECT_EQ(accepted.size(), std::variant_size_v<Message>) << "some frame kind was never accepted";
  for (const auto& [kind, count] : accepted) EXPECT_GT(count, 100) << "variant index " << kind;
  for (int e = 1; e <= static_cast<int>(ProtocolError::out_of_range); ++e)
    EXPECT_GT(reasons[static_cast<ProtocolError>(e)], 0) << name(static_cast<ProtocolError>(e));
}

// --- names and noise types -----------------------------------------------------------------

TEST(ProtocolNames, AlphaAndNoiseTypeAreInverse) {
  for (int a = -4; a <= 2; ++a) {
    EXPECT_NE(noise_type(a), NoiseType::not_identified);
    EXPECT_EQ(alpha(noise_type(a)), a);
  }
  EXPECT_EQ(noise_type(3), NoiseType::not_identified);
  EXPECT_EQ(noise_type(-5), NoiseType::not_identified);
  EXPECT_EQ(alpha(NoiseType::white_fm), 0);     // angle random walk
  EXPECT_EQ(alpha(NoiseType::flicker_fm), -1);  // bias instability
  EXPECT_EQ(alpha(NoiseType::white_pm), 2);     // quantization
}

TEST(ProtocolNames, EveryValueHasItsOwnName) {
  std::vector<std::string> seen;
  for (int k = 0; k < 8; ++k) seen.push_back(name(static_cast<NoiseType>(k)));
  for (int k = 0; k < 3; ++k) seen.push_back(name(static_cast<NodeState>(k)));
  for (int k = 0; k < 5; ++k) seen.push_back(name(static_cast<AngleUnit>(k)));
  for (int k = 0; k < 5; ++k) seen.push_back(name(static_cast<InputSource>(k)));
  for (int k = 0; k < 5; ++k) seen.push_back(name(static_cast<Ieee952Term>(k)));
  for (int k = 0; k < 4; ++k) seen.push_back(name(static_cast<Ieee952Status>(k)));
  for (int k = 0; k < 5; ++k) seen.push_back(name(static_cast<FitParameter>(k)));
  for (int k = 0; k <= static_cast<int>(ProtocolError::out_of_range); ++k)
    seen.push_back(name(static_cast<ProtocolError>(k)));
  for (const std::string& s : seen) EXPECT_NE(s, "invalid");
  EXPECT_STREQ(name(static_cast<NoiseType>(9)), "invalid");
  EXPECT_STREQ(name(static_cast<AngleUnit>(9)), "invalid");
  EXPECT_STREQ(name(static_cast<Ieee952Status>(4)), "invalid");
  EXPECT_STREQ(name(static_cast<FitParameter>(5)), "invalid");
  std::sort(seen.begin(), seen.end());
  EXPECT_EQ(std::adjacent_find(seen.begin(), seen.end()), seen.end()) << "two values share a name";
}

// --- schedule and bus load -----------------------------------------------------------------

TEST(ProtocolSchedule, FastFramesEveryReportSlowListOncePerCycle) {
  for (std::uint8_t protocol_version : {std::uint8_t{1}, std::uint8_t{2}, std::uint8_t{3}}) {
    for (std::size_t taus : {0u, 1u, 3u, 32u, 40u, 64u}) {
      // Brute force: count every slot over the four reports of a cycle.
      std::map<std::pair<Slot, int>, int> count;
      std::size_t longest = 0;
      for (std::uint8_t seq = 0; seq < slow_cycle_reports; ++seq) {
        const std::size_t n = report_frame_count(seq, taus, protocol_version);
        longest = std::max(longest, n);
        ASSERT_GE(n, 2 + 2 * taus);
        EXPECT_EQ(report_slot(seq, taus, 0, protocol_version).slot, Slot::status);  // the heartbeat opens every report
        EXPECT_EQ(report_slot(seq, taus, 1, protocol_version).slot, Slot::faults);
        for (std::size_t i = 0; i < taus; ++i) {
          const ReportSlot a = report_slot(seq, taus, 2 + 2 * i, protocol_version);
          const ReportSlot m = report_slot(seq, taus, 3 + 2 * i, protocol_version);
          EXPECT_EQ(a.slot, Slot::adev);
          EXPECT_EQ(m.slot, Slot::mdev);
          EXPECT_EQ(a.index, i);
          EXPECT_EQ(m.index, i);
        }
        for (std::size_t p = 2 + 2 * taus; p < n; ++p) {
          const ReportSlot s = report_slot(seq, taus, p, protocol_version);
          ++count[{s.slot, s.index}];
        }
      }
      // Every slow item exactly once per cycle: 4 metadata pages, tau info and terms per tau, 5
      // terms and (version 2) the fit summary.
      std::size_t slow = 0;
      for (Slot s : {Slot::sampling, Slot::clock, Slot::scale, Slot::config}) {
        EXPECT_EQ((count[{s, 0}]), 1);
        ++slow;
      }
      for (std::size_t i = 0; i < taus; ++i) {
        EXPECT_EQ((count[{Slot::tau_info, static_cast<int>(i)}]), 1) << i;
        EXPECT_EQ((count[{Slot::terms, static_cast<int>(i)}]), 1) << i;
        slow += 2;
      }
      for (int t = 0; t < 5; ++t) {
        EXPECT_EQ((count[{Slot::ieee952, t}]), 1) << t;
        ++slow;
      }
      if (protocol_version >= 2) {
        EXPECT_EQ((count[{Slot::ieee952, int{ieee952_summary_page}}]), 1);
        ++slow;
      }
      EXPECT_EQ(count.size(), slow);
      EXPECT_EQ(longest, 2 + 2 * taus + (slow + 3) / 4) << taus;
      // The cycle follows seq modulo 4, so it survives the wrap 255 -> 0.
      for (unsigned seq = 0; seq < 256; ++seq) {
        const auto s = static_cast<std::uint8_t>(seq);
        ASSERT_EQ(report_frame_count(s, taus, protocol_version), report_frame_count(s % 4, taus, protocol_version));
        const std::size_t last = report_frame_count(s, taus, protocol_version) - 1;
        EXPECT_EQ(report_slot(s, taus, last, protocol_version).slot, report_slot(s % 4, taus, last, protocol_version).slot);
        EXPECT_EQ(report_slot(s, taus, last, protocol_version).index,
                  report_slot(s % 4, taus, last, protocol_version).index);
      }
    }
  }
}

TEST(ProtocolSchedule, VersionTwoOnlyAppendsTheSummary) {
  // Brute force over every tau count: the version-1 frames keep their positions in version 2, and
  // over a cycle version 2 has exactly one frame more, the summary, last in its report.
  for (std::size_t taus = 0; taus <= max_taus; ++taus) {
    std::size_t extra = 0;
    for (std::uint8_t seq = 0; seq < slow_cycle_reports; ++seq) {
      const std::size_t v1 = report_frame_count(seq, taus, 1), v2 = report_frame_count(seq, taus, 2);
      ASSERT_GE(v2, v1);
      extra += v2 - v1;
      for (std::size_t p = 0; p < v1; ++p) {
        const ReportSlot a = report_slot(seq, taus, p, 1), b = report_slot(seq, taus, p, 2);
        EXPECT_EQ(a.slot, b.slot) << taus << " " << int(seq) << " " << p;
        EXPECT_EQ(a.index, b.index) << taus << " " << int(seq) << " " << p;
      }
      if (v2 > v1) {
        const ReportSlot s = report_slot(seq, taus, v2 - 1, 2);
        EXPECT_EQ(s.slot, Slot::ieee952);
        EXPECT_EQ(s.index, ieee952_summary_page);
      }
    }
    EXPECT_EQ(extra, 1u) << taus;
    EXPECT_EQ(report_frame_count(0, taus), report_frame_count(0, taus, version));  // the default is the current
  }
}

TEST(ProtocolSchedule, VersionThreeAppendsTheWindowListToEveryReport) {
  // Brute force over every tau count and window tau count: the version-2 frames keep their
  // positions; after them each report carries its part of the window list (window page, length
  // page, one dev page per window tau), so that over a cycle every window slot comes exactly once,
  // the window page first, in the report whose seq is a multiple of 4. Without window taus,
  // version 3 is version 2.
  for (std::size_t taus = 0; taus <= max_taus; ++taus) {
    for (std::size_t window_taus = 0; window_taus <= taus; ++window_taus) {
      std::map<std::pair<Slot, int>, int> count;
      std::size_t longest_tail = 0;
      for (std::uint8_t seq = 0; seq < slow_cycle_reports; ++seq) {
        const std::size_t v2 = report_frame_count(seq, taus, 2), v3 = report_frame_count(seq, taus, 3, window_taus);
        ASSERT_GE(v3, v2);
        longest_tail = std::max(longest_tail, v3 - v2);
        EXPECT_EQ(report_frame_count(seq, taus, 2, window_taus), v2) << "version 2 has no window";
        for (std::size_t p = 0; p < v3; ++p) {
          const ReportSlot a = report_slot(seq, taus, p, 3, window_taus);
          if (p < v2) {
            const ReportSlot b = report_slot(seq, taus, p, 2);
            ASSERT_EQ(a.slot, b.slot) << taus << " " << window_taus << " " << int(seq) << " " << p;
            ASSERT_EQ(a.index, b.index);
          } else {
            ASSERT_TRUE(a.slot == Slot::window || a.slot == Slot::window_length || a.slot == Slot::window_dev);
            if (a.slot == Slot::window) {
              EXPECT_EQ(seq, 0);
              EXPECT_EQ(p, v2) << "the window page opens the window list";
            }
            ++count[{a.slot, a.index}];
          }
        }
      }
      if (window_taus == 0) {
        EXPECT_TRUE(count.empty());
        continue;
      }
      EXPECT_EQ(count.size(), 2 + window_taus);
      EXPECT_EQ((count[{Slot::window, 0}]), 1);
      EXPECT_EQ((count[{Slot::window_length, 0}]), 1);
      for (std::size_t i = 0; i < window_taus; ++i) EXPECT_EQ((count[{Slot::window_dev, static_cast<int>(i)}]), 1) << i;
      EXPECT_EQ(longest_tail, (2 + window_taus + 3) / 4);
    }
  }
}

TEST(ProtocolSchedule, VersionFourAppendsTheModelListToEveryReport) {
  // Brute force over every tau count and window tau count: the version-3 frames keep their
  // positions; after them each report carries its part of the model list (the model page, then the
  // parameter pages in fit_parameter_slot() order), so that over a cycle every model slot comes
  // exactly once, the model page first, in the report whose seq is a multiple of 4.
  for (std::size_t taus = 0; taus <= max_taus; ++taus) {
    for (std::size_t window_taus : {std::size_t{0}, std::size_t{1}, taus / 2, taus}) {
      std::map<std::pair<Slot, int>, int> count;
      std::size_t longest_tail = 0;
      for (std::uint8_t seq = 0; seq < slow_cycle_reports; ++seq) {
        const std::size_t v3 = report_frame_count(seq, taus, 3, window_taus),
                          v4 = report_frame_count(seq, taus, 4, window_taus);
        ASSERT_GE(v4, v3);
        longest_tail = std::max(longest_tail, v4 - v3);
        for (std::size_t p = 0; p < v4; ++p) {
          const ReportSlot a = report_slot(seq, taus, p, 4, window_taus);
          if (p < v3) {
            const ReportSlot b = report_slot(seq, taus, p, 3, window_taus);
            ASSERT_EQ(a.slot, b.slot) << taus << " " << window_taus << " " << int(seq) << " " << p;
            ASSERT_EQ(a.index, b.index);
            continue;
          }
          ASSERT_TRUE(a.slot == Slot::fit_model || a.slot == Slot::fit_parameter);
          if (a.slot == Slot::fit_model) {
            EXPECT_EQ(seq, 0);
            EXPECT_EQ(p, v3) << "the model page opens the model list";
          }
          ++count[{a.slot, a.index}];
        }
      }
      ASSERT_EQ(count.size(), 1 + fit_parameter_pages);
      EXPECT_EQ((count[{Slot::fit_model, 0}]), 1);
      for (std::size_t k = 0; k < fit_parameter_pages; ++k)
        EXPECT_EQ((count[{Slot::fit_parameter, static_cast<int>(k)}]), 1) << k;
      EXPECT_EQ(longest_tail, (1 + fit_parameter_pages + 3) / 4);  // 10 entries: 3, 3, 3, 1
    }
  }
  // The parameter pages' order, and its inverse.
  for (std::size_t k = 0; k < fit_parameter_pages; ++k) {
    const FitParameterSlot s = fit_parameter_slot(k);
    EXPECT_EQ(fit_parameter_position(s.parameter, s.index), k);
  }
  EXPECT_EQ(fit_parameter_slot(0).parameter, FitParameter::markov_sigma);
  EXPECT_EQ(fit_parameter_slot(3).parameter, FitParameter::markov_tc);
  EXPECT_EQ(fit_parameter_slot(3).index, 1);
  EXPECT_EQ(fit_parameter_slot(4).parameter, FitParameter::filter_tf);
  EXPECT_EQ(fit_parameter_slot(8).parameter, FitParameter::sinusoid_frequency);
  EXPECT_EQ(fit_parameter_position(FitParameter::filter_tf, 1), fit_parameter_pages);  // no such page
}

TEST(ProtocolSchedule, VersionFiveAppendsTheUnconstrainedListToEveryReport) {
  // Brute force over every tau count and window tau count: the version-4 frames keep their
  // positions; after them each report carries its part of the unconstrained list (Q N B K R), cut
  // into parts of ceil(5 / 4) = 2 (2, 2, 1, 0), so that over a cycle every term comes exactly once.
  for (std::size_t taus = 0; taus <= max_taus; ++taus) {
    for (std::size_t window_taus : {std::size_t{0}, std::size_t{1}, taus / 2, taus}) {
      std::map<int, int> count;
      for (std::uint8_t seq = 0; seq < slow_cycle_reports; ++seq) {
        const std::size_t v4 = report_frame_count(seq, taus, 4, window_taus),
                          v5 = report_frame_count(seq, taus, 5, window_taus);
        ASSERT_EQ(v5 - v4, std::size_t{seq < 2 ? 2u : seq == 2 ? 1u : 0u});
        for (std::size_t p = 0; p < v5; ++p) {
          const ReportSlot a = report_slot(seq, taus, p, 5, window_taus);
          if (p < v4) {
            const ReportSlot b = report_slot(seq, taus, p, 4, window_taus);
            ASSERT_EQ(a.slot, b.slot) << taus << " " << window_taus << " " << int(seq) << " " << p;
            ASSERT_EQ(a.index, b.index);
            continue;
          }
          ASSERT_EQ(a.slot, Slot::unconstrained);
          EXPECT_EQ(a.index, 2 * seq + (p - v4)) << "in term order";
          ++count[a.index];
        }
      }
      ASSERT_EQ(count.size(), 5u);
      for (int k = 0; k < 5; ++k) EXPECT_EQ(count[k], 1) << k;
    }
  }
  EXPECT_EQ(report_frame_count(0, 32), report_frame_count(0, 32, 5)) << "the default is version 5";
}

TEST(ProtocolBusLoad, WorstCaseFrameLengthsAndLoadPerNode) {
  // Davis et al. 2007: 8 s + 67 + floor((54 + 8 s - 1) / 4) bits for a 29-bit identifier.
  EXPECT_EQ(worst_case_frame_bits(0), 80u);
  EXPECT_EQ(worst_case_frame_bits(6), 140u);
  EXPECT_EQ(worst_case_frame_bits(8), 160u);
  // 32 taus, one report per second: longest report 2 + 64 + ceil(74 / 4) = 85 frames of 160 bits
  // (version 1: ceil(73 / 4), the same 85: the summary fills a shorter report), version 4's
  // model list adds ceil(10 / 4) = 3 to it, version 5's unconstrained list ceil(5 / 4) = 2: 90 frames.
  const double load32 = worst_case_bus_load(32, 1.0, 500000.0);
  EXPECT_DOUBLE_EQ(load32, 90 * 160 / 500000.0);
  EXPECT_LE(load32, 0.03);
  // 40 taus (the design brief's example): 2 + 80 + ceil(90 / 4) + 3 + 2 = 110 frames.
  EXPECT_DOUBLE_EQ(worst_case_bus_load(40, 1.0, 500000.0), 110 * 160 / 500000.0);
  // With the window curve: 32 taus and 30 window taus (the board's most) add ceil((2 + 30) / 4) = 8
  // frames to the longest report: 98 frames, 3.136 % (version 4: 96; version 3: 93, within 3 %).
  const double window30 = worst_case_bus_load(32, 1.0, 500000.0, 30);
  EXPECT_DOUBLE_EQ(window30, 98 * 160 / 500000.0);
  EXPECT_DOUBLE_EQ(worst_case_bus_load(32, 1.0, 500000.0, 0), load32);
  // Averaged over the slow cycle (frames per second at the default 1 s report period), 32 taus
  // without window: version 3 sends 85, 85, 85, 83 frames, version 4 3, 3, 3, 1 more, version 5
  // 2, 2, 1, 0 more than version 4.
  std::size_t v3 = 0, v4 = 0, v5 = 0;
  for (std::uint8_t seq = 0; seq < slow_cycle_reports; ++seq)
    v3 += report_frame_count(seq, 32, 3), v4 += report_frame_count(seq, 32, 4), v5 += report_frame_count(seq, 32, 5);
  EXPECT_EQ(v3, 338u);  // 84.5 frames/s
  EXPECT_EQ(v4, 348u);  // 87 frames/s
  EXPECT_EQ(v5, 353u);  // 88.25 frames/s
}

}  // namespace
}  // namespace gyrochar::protocol
