// The decoder against the loss, restart and offline rules of docs/protocol.md section 5.
// Oracle: frames made by the codec from known values, then dropped, reordered or repeated on
// purpose; the expected counts follow from what the test removed.
#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include "decoder.hpp"
#include "limits.hpp"
#include "node_report.hpp"
#include "units.hpp"

namespace gyrochar {
namespace {

using namespace protocol;
using decoding::node_decisions;

const Ieee952SummaryMsg fit_summary{0, Ieee952Status::ok, 0.93f, 24, true, {0, 0}};

// Version 4's model pages: one Markov term (sigma 0.02 resolved, Tc 30 s) and the sensor's filter
// (Tf 0.005 s); the other parameter pages zeros.
Ieee952ModelMsg model_page(std::uint8_t seq) { return {seq, 1, 0, true, 0, false, 0, 0, false, 0.0f}; }
Ieee952ParameterMsg parameter_page(std::uint8_t seq, std::size_t k) {
  const FitParameterSlot p = fit_parameter_slot(k);
  Ieee952ParameterMsg m{seq, p.parameter, p.index, false, 0.0f, 0.0};
  if (p.index == 0 && p.parameter == FitParameter::markov_sigma) m.value = 0.02f, m.rel_uncertainty = 0.1, m.resolved = true;
  if (p.index == 0 && p.parameter == FitParameter::markov_tc) m.value = 30.0f, m.rel_uncertainty = 0.2;
  if (p.parameter == FitParameter::filter_tf) m.value = 0.005f, m.rel_uncertainty = 0.3;
  return m;
}

// Version 5's unconstrained estimates (angle unit arcsec, as the scale page says): N 0.3 (the term
// page shows 0.25) with uncertainty 0.05; K's unconstrained square negative, its signed root -0.125
// with uncertainty 0.5; B 0.5 with 1; Q and R none (not free in the fit).
Ieee952UnconstrainedMsg unconstrained_page(std::uint8_t seq, std::size_t k) {
  const auto term = static_cast<Ieee952Term>(k);
  if (k == 1) return {seq, term, 0.3f, 0.05};
  if (k == 2) return {seq, term, 0.5f, 1.0};
  if (k == 3) return {seq, term, -0.125f, 0.5};
  return {seq, term, 0.0f, 0.0};
}

// The frames of report `seq` of a node with `taus` taus, values derived from (seq, tau), speaking
// protocol version `protocol_version` (1: no summary page, no Fitted flag; B is fitted but not
// resolved in version 2, and goes out as zeros in version 1). With `window_taus` (version 3) the
// window frames describe window `window`, its ADEV at window tau i 1 + i + window, MDEV half that.
std::vector<CanFrame> report(std::uint8_t node, std::uint8_t seq, std::uint8_t taus, std::uint64_t samples,
                             std::uint64_t uptime_ms = 0, std::uint32_t hash = 7, std::uint8_t protocol_version = version,
                             std::uint8_t window_taus = 0, std::uint32_t window = 0) {
  std::vector<CanFrame> frames;
  const bool v2 = protocol_version >= 2;
  const auto window_dev = [&](std::size_t i) { return 1.0 + static_cast<double>(i + window); };
  for (std::size_t k = 0; k < report_frame_count(seq, taus, protocol_version, window_taus); ++k) {
    const ReportSlot s = report_slot(seq, taus, k, protocol_version, window_taus);
    Message m;
    switch (s.slot) {
      case Slot::status: m = StatusMsg{seq, NodeState::running, taus, samples}; break;
      case Slot::faults: m = StatusFaultsMsg{seq, 1, 2, 3, 0}; break;
      case Slot::adev:
        m = TauDevMsg{seq, s.index, DevKind::adev, 1.0f / (1 + s.index), 100.0, NoiseType::white_fm, true};
        break;
      case Slot::mdev:
        m = TauDevMsg{seq, s.index, DevKind::mdev, 0.5f / (1 + s.index), 90.0, NoiseType::white_fm, true};
        break;
      case Slot::terms: m = TauTermsMsg{seq, s.index, samples - 2}; break;
      case Slot::tau_info: m = TauInfoMsg{seq, s.index, std::uint64_t{1} << s.index, 0}; break;
      case Slot::sampling: m = MetaSamplingMsg{seq, 0.01f, 8}; break;
      case Slot::clock: m = MetaClockMsg{seq, uptime_ms ? uptime_ms : samples * 10, protocol_version}; break;
      case Slot::scale: m = MetaScaleMsg{seq, 1.5f, AngleUnit::arcsec, InputSource::simulated}; break;
      case Slot::config: m = MetaConfigMsg{seq, hash, 1000}; break;
      case Slot::ieee952:
        if (s.index == ieee952_summary_page) {
          Ieee952SummaryMsg f = fit_summary;
          f.seq = seq;
          m = f;
        } else if (s.index == 2) {  // B: in the model, not resolved
          m = v2 ? Ieee952Msg{seq, Ieee952Term::bias_instability, false, 0.5f, 2.0, true}
                 : Ieee952Msg{seq, Ieee952Term::bias_instability, false, 0.0f, 0.0};
        } else {
          m = Ieee952Msg{seq, static_cast<Ieee952Term>(s.index), true, 0.25f, 0.1, v2};
        }
        break;
      case Slot::window: m = WindowMsg{seq, window_taus, true, window, 0}; break;
      case Slot::window_length: m = WindowLengthMsg{seq, 1000}; break;
      case Slot::window_dev:
        m = WindowDevMsg{seq, s.index, static_cast<std::uint8_t>(window % 16), window_dev(s.index), window_dev(s.index) / 2};
        break;
      case Slot::fit_model: m = model_page(seq); break;
      case Slot::fit_parameter: m = parameter_page(seq, s.index); break;
      case Slot::unconstrained: m = unconstrained_page(seq, s.index); break;
    }
    CanFrame f;
    EXPECT_EQ(encode(m, node, f), ProtocolError::none);
    frames.push_back(f);
  }
  return frames;
}

struct Feed {
  Decoder decoder;
  double t = 0;
  void frames(const std::vector<CanFrame>& fs) {
    for (const auto& f : fs) decoder.feed(f, t += 0.01);
  }
  const NodeView& node(std::uint8_t a) { return decoder.nodes().at(a); }
};

TEST(Decoder, CompleteReportsCarryEveryValue) {
  Feed feed;
  for (std::uint8_t s = 0; s < 6; ++s) feed.frames(report(5, s, 8, 1000 + s * 100));
  feed.decoder.flush();
  const NodeView& v = feed.node(5);
  EXPECT_EQ(v.health.reports_complete, 6u);
  EXPECT_EQ(v.health.frames_missing, 0u);
  EXPECT_EQ(v.health.reports_lost, 0u);
  ASSERT_TRUE(v.sampling.has_value());
  EXPECT_FLOAT_EQ(v.sampling->tau0_s, 0.01f);
  EXPECT_EQ(v.taus[3].m, 8u);
  EXPECT_DOUBLE_EQ(v.tau_s(3), static_cast<double>(0.01f) * 8);
  EXPECT_FLOAT_EQ(v.taus[3].adev.dev, 0.25f);
  EXPECT_TRUE(v.ieee952[1].resolved);
  EXPECT_TRUE(v.ieee952[1].fitted);
  EXPECT_FALSE(v.ieee952[2].resolved);  // B in the model, not resolved: its value still arrives
  EXPECT_TRUE(v.ieee952[2].fitted);
  EXPECT_FLOAT_EQ(v.ieee952[2].value, 0.5f);
  EXPECT_DOUBLE_EQ(v.ieee952[2].rel_uncertainty, 2.0);
  ASSERT_TRUE(v.ieee952_summary.has_value());
  Ieee952SummaryMsg want = fit_summary;
  want.seq = v.ieee952_summary->seq;
  EXPECT_EQ(*v.ieee952_summary, want);
  EXPECT_EQ(v.schedule_version(), version);
  // Version 4: the model pages of the summary's slow cycle (reports 4 and 5 open the second cycle:
  // its pages so far are the current ones, the first cycle's whole beside them).
  EXPECT_EQ(v.ieee952_summary_cycle, 1u);
  EXPECT_EQ(v.fit_model.cycle, 2u);
  EXPECT_EQ(v.previous_fit_model.cycle, 1u);
  ASSERT_TRUE(v.previous_fit_model.complete());
  EXPECT_EQ(*v.previous_fit_model.model, model_page(0));
  for (std::size_t k = 0; k < fit_parameter_pages; ++k) {
    ASSERT_TRUE(v.previous_fit_model.parameters[k].has_value()) << k;
    Ieee952ParameterMsg want_k = parameter_page(v.previous_fit_model.parameters[k]->seq, k);
    want_k.rel_uncertainty = v.previous_fit_model.parameters[k]->rel_uncertainty;  // 0.01 % steps
    EXPECT_EQ(*v.previous_fit_model.parameters[k], want_k) << k;
    EXPECT_NEAR(v.previous_fit_model.parameters[k]->rel_uncertainty, parameter_page(0, k).rel_uncertainty, 1e-12);
    EXPECT_EQ(v.previous_fit_model.in_model(k), k == 0 || k == 1 || k == 4) << k;  // Markov 1 and the filter
  }
}

TEST(Decoder, VersionThreeNodeHasNoModelAndMissesNothing) {
  // A version-3 node sends no model list: the decoder expects none, and a version-4 decoder reads
  // every other frame as before.
  Feed feed;
  for (std::uint8_t s = 0; s < 8; ++s) feed.frames(report(5, s, 8, 1000 + s * 100, 0, 7, 3));
  feed.decoder.flush();
  const NodeView& v = feed.node(5);
  EXPECT_EQ(v.health.reports_complete, 8u);
  EXPECT_EQ(v.health.frames_missing, 0u);
  EXPECT_EQ(v.schedule_version(), 3);
  EXPECT_FALSE(v.fit_model.model.has_value());
  EXPECT_EQ(v.fit_model.cycle, 0u);
  ASSERT_TRUE(v.ieee952_summary.has_value());
}

TEST(Decoder, ModelPagesAreKeptPerSlowCycleAcrossLostReports) {
  // Reports 0-3 whole, 4-5 lost, 6-7 received: the second cycle's pages (of reports 6 and 7) start
  // a model of their own, never filled up with the first cycle's, and the cycles are counted from
  // Seq, lost reports included. Joining a node late (seq 250) counts the cycles the same way.
  Feed feed;
  for (std::uint8_t s = 0; s < 4; ++s) feed.frames(report(5, s, 8, 1000 + s * 100));
  for (std::uint8_t s = 6; s < 8; ++s) feed.frames(report(5, s, 8, 1000 + s * 100));
  feed.decoder.flush();
  const NodeView& v = feed.node(5);
  EXPECT_EQ(v.health.reports_lost, 2u);
  EXPECT_EQ(v.reports_made, 7u);
  EXPECT_EQ(v.cycle(), 2u);
  EXPECT_EQ(v.fit_model.cycle, 2u);
  EXPECT_FALSE(v.fit_model.model.has_value());  // the model page came in report 4
  EXPECT_FALSE(v.fit_model.complete());
  EXPECT_TRUE(v.previous_fit_model.complete());
  EXPECT_EQ(v.ieee952_summary_cycle, 2u);  // report 7 carried the second cycle's summary
  Feed late;
  for (unsigned s = 250; s < 258; ++s) late.frames(report(9, static_cast<std::uint8_t>(s), 8, 1000 + s * 100));
  late.decoder.flush();
  const NodeView& w = late.node(9);
  EXPECT_EQ(w.reports_made, 257u);  // 250 + 7 reports: Seq wrapped
  EXPECT_EQ(w.cycle(), 65u);
  EXPECT_TRUE(w.previous_fit_model.complete());  // seq 252-255
  EXPECT_TRUE(w.fit_model.complete());           // seq 0-3 (256-259): the page of seq 0 came
}

// The uncertainty the codec makes of `u` (log2 in 1/256 steps): what the decoder can know.
double on_the_wire(double u) {
  CanFrame f;
  EXPECT_EQ(encode(Ieee952UnconstrainedMsg{0, Ieee952Term::angle_random_walk, 1.0f, u}, 1, f), ProtocolError::none);
  return std::get<Ieee952UnconstrainedMsg>(decode(f).message).uncertainty;
}

TEST(Decoder, VerdictsJudgeTheUnconstrainedEstimateWhereTheNodeSendsIt) {
  // Oracles: the values encoded (unconstrained_page, term pages 0.25 arcsec-based with 10 %), the
  // codec's uncertainty grid (on_the_wire), 1 arcsec = units::arcsec rad, and the decision rule of
  // limits.hpp: value -+ 1.959964 u, the lower bound not below 0; K's negative unconstrained square
  // is judged as 0 (gyrochar-analyze's rule: Ieee952Parameter::unconstrained).
  const std::vector<Limit> limits = parse_limits("Q <= 1 arcsec\nN <= 1 rad/s^0.5\nK <= 1 rad/s^1.5\n");
  Feed feed;
  for (std::uint8_t s = 0; s < 4; ++s) feed.frames(report(5, s, 8, 1000 + s * 100));
  feed.decoder.flush();
  const NodeView& v = feed.node(5);
  EXPECT_EQ(v.health.frames_missing, 0u);
  EXPECT_EQ(v.schedule_version(), 5);
  const std::vector<Decision> d = node_decisions(v, limits);
  ASSERT_EQ(d.size(), 3u);
  // Q: no unconstrained estimate (not free): the shown value, and the verdict says so.
  EXPECT_EQ(d[0].estimate.kind, estimate_shown);
  EXPECT_DOUBLE_EQ(d[0].estimate.value, static_cast<double>(0.25f) * units::arcsec);
  EXPECT_NE(d[0].reason.find("no unconstrained estimate"), std::string::npos) << d[0].reason;
  // N: 0.3 arcsec/s^0.5 -+ z 0.05 (as the wire carries it).
  const double n = static_cast<double>(0.3f) * units::arcsec, un = on_the_wire(0.05) * units::arcsec;
  EXPECT_NEAR(on_the_wire(0.05), 0.05, 0.00136 * 0.05);
  EXPECT_EQ(d[1].estimate.kind, estimate_unconstrained);
  EXPECT_DOUBLE_EQ(d[1].estimate.value, n);
  EXPECT_DOUBLE_EQ(d[1].estimate.high, n + decision_z * un);
  EXPECT_DOUBLE_EQ(d[1].estimate.low, n - decision_z * un);
  EXPECT_EQ(d[1].verdict, Verdict::pass);
  EXPECT_EQ(d[1].reason, "upper bound within the limit");
  // K: signed root -0.125: estimate 0, upper bound z 0.5 (as on the wire).
  EXPECT_EQ(d[2].estimate.kind, estimate_unconstrained);
  EXPECT_EQ(d[2].estimate.value, 0.0);
  EXPECT_EQ(d[2].estimate.low, 0.0);
  EXPECT_DOUBLE_EQ(d[2].estimate.high, decision_z * on_the_wire(0.5) * units::arcsec);
  ASSERT_NE(v.unconstrained_estimate(3), nullptr);
  EXPECT_EQ(v.unconstrained_estimate(3)->value, -0.125f) << "the sign travels";

  // The same node at version 4: no unconstrained estimates; every term judged by its shown value.
  Feed old;
  for (std::uint8_t s = 0; s < 4; ++s) old.frames(report(5, s, 8, 1000 + s * 100, 0, 7, 4));
  old.decoder.flush();
  const NodeView& w = old.node(5);
  EXPECT_EQ(w.health.frames_missing, 0u);
  EXPECT_EQ(w.schedule_version(), 4);
  const std::vector<Decision> e = node_decisions(w, limits);
  for (const Decision& x : e) {
    EXPECT_EQ(x.estimate.kind, estimate_shown);
    EXPECT_NE(x.reason.find("(judged by the shown value: the node sends no unconstrained estimate)"), std::string::npos);
  }
  const double shown = static_cast<double>(0.25f) * units::arcsec;
  EXPECT_DOUBLE_EQ(e[1].estimate.value, shown);
  EXPECT_DOUBLE_EQ(e[1].estimate.high, shown * (1 + decision_z * 0.1));
  EXPECT_DOUBLE_EQ(e[2].estimate.value, shown);
}

TEST(Decoder, AnUnconstrainedEstimateIsUsedOnlyWithTheTermFrameOfItsOwnSlowCycle) {
  // 8 taus: N's unconstrained estimate comes in the first report of a cycle, its term page in the
  // last. Cycle 1 without its unconstrained frames, then reports 4-6 of cycle 2: N's term page is
  // still cycle 1's, and cycle 2's estimate (another fit, perhaps) is not taken for it. Report 7
  // brings cycle 2's term page: now they belong together.
  const std::vector<Limit> limits = parse_limits("N <= 1 rad/s^0.5\n");
  const auto without_unconstrained = [](std::vector<CanFrame> fs) {
    std::erase_if(fs, [](const CanFrame& f) { return (f.id & ~0xFFu) == unconstrained_id; });
    return fs;
  };
  Feed feed;
  for (std::uint8_t s = 0; s < 4; ++s) feed.frames(without_unconstrained(report(5, s, 8, 1000 + s * 100)));
  for (std::uint8_t s = 4; s < 7; ++s) feed.frames(report(5, s, 8, 1000 + s * 100));
  const NodeView& v = feed.node(5);
  EXPECT_EQ(v.ieee952[1].cycle, 1u);
  EXPECT_EQ(v.unconstrained[1].cycle, 2u);
  EXPECT_EQ(v.unconstrained_estimate(1), nullptr);
  EXPECT_EQ(node_decisions(v, limits)[0].estimate.kind, estimate_shown);
  feed.frames(report(5, 7, 8, 1700));
  EXPECT_EQ(v.ieee952[1].cycle, 2u);
  ASSERT_NE(v.unconstrained_estimate(1), nullptr);
  EXPECT_EQ(node_decisions(v, limits)[0].estimate.kind, estimate_unconstrained);
  EXPECT_DOUBLE_EQ(node_decisions(v, limits)[0].estimate.value, static_cast<double>(0.3f) * units::arcsec);
}

TEST(Decoder, VersionOneNodeHasNoSummaryAndMissesNothing) {
  // A version-1 node's reports have no summary frame: the decoder expects none (its clock page says
  // version 1), and reads Resolved as fitted.
  Feed feed;
  for (std::uint8_t s = 0; s < 8; ++s) feed.frames(report(5, s, 8, 1000 + s * 100, 0, 7, 1));
  feed.decoder.flush();
  const NodeView& v = feed.node(5);
  EXPECT_EQ(v.health.reports_complete, 8u);
  EXPECT_EQ(v.health.frames_missing, 0u);
  EXPECT_FALSE(v.ieee952_summary.has_value());
  EXPECT_EQ(v.schedule_version(), 1);
  EXPECT_TRUE(v.ieee952[1].resolved);
  EXPECT_TRUE(v.ieee952[1].fitted);
  EXPECT_FALSE(v.ieee952[2].resolved);
  EXPECT_FALSE(v.ieee952[2].fitted);
}

TEST(Decoder, VersionTwoNodeJoinedLateMissesNothingAndItsLostSummaryCounts) {
  // Joining in the cycle's last report (3 taus: the summary is in part 3, the clock page in part
  // 0): the summary arrives before the clock page and tells the decoder the node's version.
  Feed feed;
  for (std::uint8_t s = 3; s < 8; ++s) feed.frames(report(6, s, 3, 1000 + s * 100, 0, 7, 2));
  auto lost = report(6, 11, 3, 2100, 0, 7, 2);
  lost.pop_back();  // the summary, last of its report
  feed.frames(lost);
  feed.decoder.flush();
  const NodeView& v = feed.node(6);
  EXPECT_EQ(v.health.reports_complete, 5u);
  EXPECT_EQ(v.health.reports_incomplete, 1u);
  EXPECT_EQ(v.health.frames_missing, 1u);
  ASSERT_TRUE(v.ieee952_summary.has_value());
  EXPECT_EQ(v.ieee952_summary->seq, 7);
}

TEST(Decoder, UnknownProtocolVersionStopsDecodingUntilAKnownOneReturns) {
  // docs/protocol.md 2.2. A node announcing version 6 (its clock page, in report 0 of the 4-report
  // slow cycle, comes after the 2 + 2 x 8 fast frames and the sampling page) is decoded no further: the frames after
  // its clock page and of its next reports are counted as not decoded and change no value. When it
  // announces version 5 (this decoder's) again, a new session starts.
  Feed feed;
  std::vector<DecoderEvent> events;
  feed.decoder = Decoder([&](DecoderEvent e, const NodeView&, std::uint8_t) { events.push_back(e); });
  for (std::uint8_t s = 0; s < 4; ++s) feed.frames(report(5, s, 8, 1000 + s * 100));
  const float adev_before = feed.node(5).taus[0].adev.dev;
  const std::uint64_t frames_before = feed.node(5).health.frames;
  std::size_t sent = 0;
  for (std::uint8_t s = 4; s < 8; ++s) {
    auto frames = report(5, s, 8, 1000 + s * 100, 0, 7, version + 1);
    // Tau 0's ADEV (position 2) differs in every report, so that a decoded frame would show.
    EXPECT_EQ(encode(TauDevMsg{s, 0, DevKind::adev, 10.0f + s, 100.0, NoiseType::white_fm, true}, 5, frames[2]),
              ProtocolError::none);
    frames.back().data[0] |= 0xE0;  // a frame this decoder would reject: not its business either
    sent += frames.size();
    feed.frames(frames);
  }
  const NodeView& v = feed.node(5);
  EXPECT_EQ(v.unknown_version, version + 1);
  EXPECT_EQ(std::count(events.begin(), events.end(), DecoderEvent::unknown_version), 1);
  const std::size_t before_clock = 19;  // report 4's frames before its clock page
  EXPECT_EQ(v.health.frames, frames_before + before_clock);
  EXPECT_EQ(v.health.not_decoded, sent - before_clock);
  EXPECT_EQ(v.health.restarts, 0u);
  EXPECT_NE(adev_before, 14.0f);
  EXPECT_EQ(v.taus[0].adev.dev, 14.0f);  // report 4's, before its clock page; none of 5 .. 7's
  EXPECT_TRUE(v.health.rejected.empty());
  for (std::uint8_t s = 8; s < 13; ++s) feed.frames(report(5, s, 8, 1000 + s * 100, 2000));
  feed.decoder.flush();
  const NodeView& w = feed.node(5);
  EXPECT_EQ(w.unknown_version, 0);
  EXPECT_EQ(w.health.restarts, 1u);
  EXPECT_EQ(w.schedule_version(), version);
  EXPECT_EQ(w.taus[0].adev.dev, 1.0f);
}

TEST(Decoder, MissingFramesAndLostReportsAreCounted) {
  Feed feed;
  auto r0 = report(5, 0, 8, 1000);
  r0.erase(r0.begin() + 4);  // one ADEV/MDEV frame lost
  r0.erase(r0.begin() + 9);
  feed.frames(r0);
  feed.frames(report(5, 1, 8, 1100));
  feed.frames(report(5, 4, 8, 1400));  // reports 2 and 3 never seen
  feed.decoder.flush();
  const NodeView& v = feed.node(5);
  EXPECT_EQ(v.health.frames_missing, 2u);
  EXPECT_EQ(v.health.reports_incomplete, 1u);
  EXPECT_EQ(v.health.reports_complete, 2u);
  EXPECT_EQ(v.health.reports_lost, 2u);
  EXPECT_EQ(v.health.restarts, 0u);
}

TEST(Decoder, RestartWhenSeqOrSampleCountGoesBack) {
  Feed feed;
  feed.frames(report(9, 40, 4, 5000));
  feed.frames(report(9, 41, 4, 5100));
  feed.frames(report(9, 0, 4, 10));  // Seq backwards and SampleCount backwards
  feed.decoder.flush();
  const NodeView& v = feed.node(9);
  EXPECT_EQ(v.health.restarts, 1u);
  EXPECT_EQ(v.session, 1u);
  EXPECT_EQ(v.status.sample_count, 10u);
  EXPECT_EQ(v.health.reports_lost, 0u);  // a restart is not a loss
}

TEST(Decoder, SeqWrapIsNotARestart) {
  Feed feed;
  feed.frames(report(9, 254, 4, 5000));
  feed.frames(report(9, 255, 4, 5100));
  feed.frames(report(9, 0, 4, 5200));
  feed.decoder.flush();
  EXPECT_EQ(feed.node(9).health.restarts, 0u);
  EXPECT_EQ(feed.node(9).health.reports_complete, 3u);
}

TEST(Decoder, SilenceMakesANodeOfflineThenOnline) {
  std::vector<DecoderEvent> events;
  Decoder decoder([&](DecoderEvent e, const NodeView&, std::uint8_t) { events.push_back(e); });
  for (const auto& f : report(3, 0, 2, 100)) decoder.feed(f, 1.0);
  decoder.tick(3.9);
  EXPECT_TRUE(decoder.nodes().at(3).online);
  decoder.tick(4.1);  // 3 s after the last frame
  EXPECT_FALSE(decoder.nodes().at(3).online);
  EXPECT_EQ(decoder.nodes().at(3).health.offline_events, 1u);
  for (const auto& f : report(3, 1, 2, 200)) decoder.feed(f, 10.0);
  EXPECT_TRUE(decoder.nodes().at(3).online);
  EXPECT_NE(std::find(events.begin(), events.end(), DecoderEvent::offline), events.end());
}

// The bench's observation (sja1000-bus-fault): the node's bus was down for 5 s, its Seq advanced by
// about 5 while none of its frames arrived. Rule 4 closes the report at the offline event, but the
// last Seq stays: the reports made meanwhile are lost reports (rule 2), besides the offline event.
TEST(Decoder, ReportsMadeWhileOfflineAreLost) {
  Decoder decoder;
  for (const auto& f : report(3, 10, 2, 1000)) decoder.feed(f, 1.0);
  for (const auto& f : report(3, 11, 2, 1100)) decoder.feed(f, 2.0);
  decoder.tick(6.0);                                                  // offline
  for (const auto& f : report(3, 17, 2, 1700)) decoder.feed(f, 8.0);  // 12..16 never arrived
  decoder.flush();
  const NodeView& v = decoder.nodes().at(3);
  EXPECT_EQ(v.health.offline_events, 1u);
  EXPECT_EQ(v.health.reports_lost, 5u);
  EXPECT_EQ(v.health.reports_complete, 3u);
  EXPECT_EQ(v.health.restarts, 0u);
  EXPECT_EQ(v.session, 0u);
}

// A node that restarts (SampleCount back) with a Seq that happens to be a few ahead is a restart,
// not lost reports; the reports lost before an offline period that ends without a restart stay.
TEST(Decoder, RestartAfterASeqJumpIsNotALoss) {
  Decoder decoder;
  for (const auto& f : report(4, 250, 2, 5000)) decoder.feed(f, 1.0);
  decoder.tick(5.0);                                               // offline
  for (const auto& f : report(4, 3, 2, 20)) decoder.feed(f, 9.0);  // d = 9, but SampleCount went back
  decoder.flush();
  const NodeView& v = decoder.nodes().at(4);
  EXPECT_EQ(v.health.restarts, 1u);
  EXPECT_EQ(v.health.reports_lost, 0u);
  EXPECT_EQ(v.session, 1u);
}

TEST(Decoder, SeveralNodesAreKeptApart) {
  Feed feed;
  auto a = report(1, 0, 4, 100), b = report(2, 7, 6, 900);
  std::vector<CanFrame> mixed;
  for (std::size_t i = 0; i < std::max(a.size(), b.size()); ++i) {
    if (i < a.size()) mixed.push_back(a[i]);
    if (i < b.size()) mixed.push_back(b[i]);
  }
  feed.frames(mixed);
  feed.decoder.flush();
  EXPECT_EQ(feed.node(1).health.reports_complete, 1u);
  EXPECT_EQ(feed.node(2).health.reports_complete, 1u);
  EXPECT_EQ(feed.node(1).status.tau_count, 4);
  EXPECT_EQ(feed.node(2).status.tau_count, 6);
}

TEST(Decoder, BadFramesAreCountedNeverFatal) {
  Feed feed;
  auto r = report(5, 0, 4, 100);
  CanFrame bad = r[2];
  bad.len = 5;  // wrong length
  CanFrame reserved = r[0];
  reserved.data[0] |= 0xF0;  // reserved bits of the heartbeat
  CanFrame other;
  other.id = 0x123;  // unrelated 11-bit traffic
  other.len = 2;
  feed.frames({bad, reserved, other});
  feed.frames(r);
  feed.frames({r[3]});  // a duplicate slot
  feed.decoder.flush();
  const NodeView& v = feed.node(5);
  EXPECT_EQ(feed.decoder.rejected_frames(), 2u);
  EXPECT_EQ(v.health.rejected.at(ProtocolError::wrong_length), 1u);
  EXPECT_EQ(v.health.rejected.at(ProtocolError::reserved_bits), 1u);
  EXPECT_EQ(feed.decoder.other_frames(), 1u);
  EXPECT_EQ(v.health.duplicates, 1u);
}

// A CAN FD frame with a protocol identifier is refused (the protocol is classic CAN) and counted
// against the node its identifier names, never against a node 0x00 that does not exist.
TEST(Decoder, CanFdFrameIsCountedAgainstItsSender) {
  Feed feed;
  CanFrame fd = report(0x11, 0, 4, 100)[0];
  fd.fd = true;
  fd.len = 16;
  feed.frames({fd});
  EXPECT_EQ(feed.decoder.rejected_frames(), 1u);
  EXPECT_EQ(feed.node(0x11).health.rejected.at(ProtocolError::fd_frame), 1u);
  EXPECT_EQ(feed.decoder.nodes().count(0x00), 0u);
}

// --- the window curves (protocol version 3) ----------------------------------------------------

TEST(Decoder, WindowCurvesAreKeptPerWindowAndCountedAsExpectedFrames) {
  // A node with 8 taus and 5 window taus: window 3 for two slow cycles, then window 4. Oracle: the
  // values the frames carry, and the schedule (report_slot with the window taus).
  Feed feed;
  std::vector<std::uint32_t> completed;
  feed.decoder = Decoder([&](DecoderEvent e, const NodeView& v, std::uint8_t) {
    if (e == DecoderEvent::window_complete) completed.push_back(*v.current_window());
  });
  for (std::uint8_t s = 0; s < 12; ++s) feed.frames(report(5, s, 8, 1000 + s * 100, 0, 7, version, 5, s < 8 ? 3 : 4));
  feed.decoder.flush();
  const NodeView& v = feed.node(5);
  EXPECT_EQ(v.window_taus, 5u);
  EXPECT_EQ(v.window_length, 1000u);
  EXPECT_EQ(v.health.frames_missing, 0u);
  EXPECT_EQ(v.health.reports_complete, 12u);
  EXPECT_EQ(v.health.window_frames_unplaced, 0u);
  EXPECT_EQ(completed, (std::vector<std::uint32_t>{3, 4})) << "once per window, though sent in two cycles";
  ASSERT_EQ(v.windows.size(), 2u);
  for (const std::uint32_t k : {3u, 4u}) {
    const WindowView& w = v.windows.at(k);
    ASSERT_TRUE(w.complete());
    for (std::size_t i = 0; i < 5; ++i) {
      EXPECT_NEAR(w.adev[i], 1.0 + static_cast<double>(i + k), 2.2e-5 * w.adev[i]);
      EXPECT_NEAR(w.mdev[i], w.adev[i] / 2, 2.2e-5 * w.adev[i]);
    }
  }
}

TEST(Decoder, WindowFramesWithoutTheirPageAreNotTakenForAnotherWindow) {
  // Window 3, then window 4 whose window page is lost: its frames (WindowMod16 = 4) are counted as
  // unplaced, never stored as window 3's; the next cycle's page brings window 4.
  Feed feed;
  for (std::uint8_t s = 0; s < 4; ++s) feed.frames(report(5, s, 8, 1000 + s * 100, 0, 7, version, 5, 3));
  for (std::uint8_t s = 4; s < 8; ++s) {
    auto frames = report(5, s, 8, 1000 + s * 100, 0, 7, version, 5, 4);
    if (s == 4) {
      const auto page = std::find_if(frames.begin(), frames.end(), [](const CanFrame& f) {
        const Decoded d = decode(f);
        return std::holds_alternative<WindowMsg>(d.message);
      });
      ASSERT_NE(page, frames.end());
      frames.erase(page);
    }
    feed.frames(frames);
  }
  const NodeView& v = feed.node(5);
  EXPECT_EQ(v.health.window_frames_unplaced, 5u);
  EXPECT_EQ(v.windows.count(4), 0u);
  EXPECT_NEAR(v.windows.at(3).adev[0], 4.0, 1e-4) << "window 3 keeps its own values";
  for (std::uint8_t s = 8; s < 12; ++s) feed.frames(report(5, s, 8, 1000 + s * 100, 0, 7, version, 5, 4));
  ASSERT_EQ(v.windows.count(4), 1u);
  EXPECT_TRUE(v.windows.at(4).complete());
}

TEST(Decoder, AChangedWindowTauCountEndsTheSession) {
  Feed feed;
  for (std::uint8_t s = 0; s < 4; ++s) feed.frames(report(5, s, 8, 1000 + s * 100, 0, 7, version, 5, 3));
  for (std::uint8_t s = 4; s < 8; ++s) feed.frames(report(5, s, 8, 1000 + s * 100, 0, 7, version, 6, 3));
  const NodeView& v = feed.node(5);
  EXPECT_EQ(v.health.restarts, 1u);
  EXPECT_EQ(v.window_taus, 6u);
  ASSERT_EQ(v.windows.size(), 1u);
  EXPECT_EQ(v.windows.at(3).adev.size(), 6u) << "the new session's window";
}

}  // namespace
}  // namespace gyrochar
