// The pieces behind gyrochar-decode's outputs (display_units, confidence, decoder's slot table,
// rows, view, plot_data, session): units, memoized confidence intervals, which values a closed
// report really carried, the plot's IEEE-952 lines and read-off points, and the line reader. Oracles: closed forms (1 rad = 180/pi deg,
// 1 h = 3600 s; the IEEE Std 952 AVAR terms of the design brief section 3), confidence.hpp
// (Boost.Math chi-squared, NIST SP 1065 eq. 45) and values the test encodes with the codec.
#include <gtest/gtest.h>
#include <fcntl.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include "plot_data.hpp"
#include "session.hpp"
#include "view.hpp"
#include "support/shell.hpp"

namespace gyrochar::decoding {
namespace {

using namespace protocol;

constexpr double rad_to_deg = 180.0 / std::numbers::pi;

NodeView node_in(AngleUnit unit) {
  NodeView v;
  v.address = 0x12;
  v.scale = MetaScaleMsg{0, 1.0f, unit, InputSource::simulated};
  return v;
}

void expect_rel(double got, double want, double rel = 1e-15) { EXPECT_NEAR(got, want, rel * std::abs(want)); }

TEST(DecodeOutput, UnitsConvertAnglesButNeverPulses) {
  // 1 arcsec/s = (1/3600) deg/s = 3600/3600 deg/h.
  Units u = units_for(node_in(AngleUnit::arcsec), rate_unit("deg/h"));
  EXPECT_EQ(u.rate_name, "deg/h");
  expect_rel(u.rate, 1.0);
  u = units_for(node_in(AngleUnit::rad), rate_unit("deg/h"));
  expect_rel(u.rate, rad_to_deg * 3600.0);
  // IEEE-952 terms from rad and s: Q arcsec, N deg/sqrt(h) = 60 deg/sqrt(s), B deg/h,
  // K deg/h/sqrt(h) = 3600^1.5 deg/s^1.5, R deg/h/h = 3600^2 deg/s^2.
  const std::array<double, 5> gyro{rad_to_deg * 3600.0, rad_to_deg * 60.0, rad_to_deg * 3600.0,
                                   rad_to_deg * std::pow(3600.0, 1.5), rad_to_deg * 3600.0 * 3600.0};
  const std::array<const char*, 5> names{"arcsec", "deg/sqrt(h)", "deg/h", "deg/h/sqrt(h)", "deg/h/h"};
  for (std::size_t k = 0; k < 5; ++k) {
    expect_rel(u.ieee[k], gyro[k]);
    EXPECT_EQ(u.ieee_name[k], names[k]);
  }
  u = units_for(node_in(AngleUnit::rad), rate_unit("deg/s"));
  EXPECT_EQ(u.rate_name, "deg/s");
  expect_rel(u.rate, rad_to_deg);
  u = units_for(node_in(AngleUnit::urad), rate_unit("rad/s"));
  EXPECT_EQ(u.rate_name, "rad/s");
  expect_rel(u.rate, 1e-6);
  u = units_for(node_in(AngleUnit::deg), DisplayRate{});
  EXPECT_EQ(u.rate_name, "deg/s");
  EXPECT_EQ(u.rate, 1.0);
  EXPECT_EQ(u.ieee_name[1], "deg/sqrt(s)");

  u = units_for(node_in(AngleUnit::pulse), rate_unit("deg/h"));
  EXPECT_TRUE(u.pulses);
  EXPECT_EQ(u.rate_name, "pulse/s");
  EXPECT_EQ(u.rate, 1.0);
  for (std::size_t k = 0; k < 5; ++k) EXPECT_EQ(u.ieee[k], 1.0);
  EXPECT_EQ(u.ieee_name[3], "pulse/s/sqrt(s)");

  u = units_for(NodeView{}, rate_unit("deg/h"));  // no metadata yet: shown as sent, unit unknown
  EXPECT_FALSE(u.known);
  EXPECT_EQ(u.rate_name, "unknown");
  EXPECT_EQ(u.rate, 1.0);
}

TEST(DecodeOutput, MemoizedConfidenceIntervalsEqualTheDirectOnes) {
  for (const double confidence : {0.683, 0.95}) {
    ConfidenceIntervals intervals(confidence);
    for (const double edf : {0.5, 3.0, 17.4, 1e6}) {
      for (const double dev : {1e-6, 2.5, 3e4}) {
        for (int pass = 0; pass < 2; ++pass) {  // computed, then looked up
          const Interval got = intervals(dev, edf), want = confidence_interval(dev, edf, confidence);
          ASSERT_TRUE(got.valid);
          expect_rel(got.low, want.low, 1e-14);
          expect_rel(got.high, want.high, 1e-14);
          EXPECT_LT(got.low, dev);
          EXPECT_GT(got.high, dev);
        }
      }
    }
    EXPECT_FALSE(intervals(1.0, 0.0).valid);  // EDF not available
    EXPECT_FALSE(intervals(1.0, std::nan("")).valid);
  }
}

CanFrame frame_of(const Message& m, std::uint8_t node) {
  CanFrame f;
  EXPECT_EQ(encode(m, node, f), ProtocolError::none);
  return f;
}

TEST(DecodeOutput, TheDecodersSlotTableAndRowsTellMissingFromInvalidFromOk) {
  std::optional<Decoder::Report> closed;  // the slot table as the report_closed listener sees it
  Decoder decoder([&](DecoderEvent e, const NodeView& node, std::uint8_t) {
    if (e == DecoderEvent::report_closed && node.address == 0x12) closed = *decoder.report(0x12);
  });
  decoder.feed(frame_of(StatusMsg{5, NodeState::running, 3, 500}, 0x12), 10.0);
  decoder.feed(frame_of(TauDevMsg{5, 0, DevKind::adev, 2.0f, 16.0, NoiseType::white_fm, true}, 0x12), 10.1);
  decoder.feed(frame_of(TauDevMsg{5, 0, DevKind::mdev, 1.0f, 8.0, NoiseType::white_fm, true}, 0x12), 10.2);
  decoder.feed(frame_of(TauDevMsg{5, 1, DevKind::adev, 0.0f, 0.0, NoiseType::not_identified, false}, 0x12), 10.3);
  decoder.feed(frame_of(TauDevMsg{9, 2, DevKind::adev, 1.0f, 4.0, NoiseType::white_fm, true}, 0x13),
               10.4);  // other node
  decoder.flush();
  ASSERT_TRUE(closed.has_value());
  const Decoder::Report& r = *closed;
  EXPECT_EQ(r.seq, 5);
  EXPECT_EQ(r.start_s, 10.0);
  EXPECT_TRUE(r.received(Slot::adev, 0) && r.received(Slot::mdev, 0) && r.received(Slot::adev, 1));
  EXPECT_FALSE(r.received(Slot::mdev, 1) || r.received(Slot::adev, 2) || r.received(Slot::mdev, 2));
  EXPECT_FALSE(r.received(Slot::adev, 3));  // beyond the report's TauCount: not in its schedule

  // The view holds stale values for tau 2 (from an earlier report): the row must not show them.
  NodeView v = node_in(AngleUnit::arcsec);
  v.status = {5, NodeState::running, 3, 500};
  v.sampling = MetaSamplingMsg{5, 0.5f, 8};
  v.session = 2;
  v.taus[0] = {1, 0, 77, {true, 2.0f, 16.0, NoiseType::white_fm, true}, {true, 1.0f, 8.0, NoiseType::white_fm, true}};
  v.taus[1] = {2, 0, 0, {true, 0.0f, 0.0, NoiseType::not_identified, false}, {}};
  v.taus[2] = {4, 0, 99, {true, 9.0f, 4.0, NoiseType::white_fm, true}, {true, 9.0f, 4.0, NoiseType::white_fm, true}};
  ConfidenceIntervals intervals(0.683);
  std::vector<TauRow> rows;
  tau_rows(v, r, units_for(v, DisplayRate{}), intervals, rows);
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_EQ(rows[0].adev.status, DevCell::Status::ok);
  EXPECT_EQ(rows[0].adev.value, 2.0);
  EXPECT_EQ(rows[0].m, 1u);
  EXPECT_EQ(rows[0].n, 77u);
  EXPECT_EQ(rows[0].tau_s, 0.5);
  EXPECT_EQ(rows[0].session, 2u);
  EXPECT_EQ(rows[0].seq, 5);
  expect_rel(rows[0].mdev.ci.low, confidence_interval(1.0, 8.0, 0.683).low, 1e-14);
  EXPECT_EQ(rows[1].adev.status, DevCell::Status::invalid);
  EXPECT_EQ(rows[1].mdev.status, DevCell::Status::missing);
  EXPECT_EQ(rows[2].adev.status, DevCell::Status::missing);
  EXPECT_EQ(rows[2].mdev.status, DevCell::Status::missing);
  EXPECT_FALSE(rows[2].adev.ci.valid);

  decoder.feed(frame_of(StatusFaultsMsg{5, 0, 0, 0, 0}, 0x12), 11.0);  // same seq after a close: a new report
  EXPECT_EQ(decoder.report(0x12)->start_s, 11.0);
  EXPECT_FALSE(decoder.report(0x12)->received(Slot::adev, 0));
  EXPECT_EQ(decoder.report(0x99), nullptr);  // never heard
}

// viewed_row's rule (rows.hpp), case by case: a row shows one report's values; the other is
// missing (the report closed without it) or pending (the report is still being received).
// Oracle: the rule as rows.hpp states it.
TEST(DecodeOutput, ARowOfTheViewsShowsTheValuesOfOneReport) {
  NodeView v = node_in(AngleUnit::arcsec);
  v.status.tau_count = 1;
  const auto row = [&](std::uint64_t adev_report, std::uint64_t mdev_report, std::uint64_t latest, bool open) {
    v.taus[0].adev = {true, 1.0f, 0.0, NoiseType::white_fm, true, adev_report};
    v.taus[0].mdev = {true, 1.0f, 0.0, NoiseType::white_fm, true, mdev_report};
    v.report = latest;
    v.report_open = open;
    const ViewedRow r = viewed_row(v, 0);
    return std::string(name(r.adev)) + "," + name(r.mdev);
  };
  EXPECT_EQ(row(3, 3, 3, false), "shown,shown");
  EXPECT_EQ(row(3, 2, 3, false), "shown,missing");  // the MDEV frame of report 3 was lost
  EXPECT_EQ(row(2, 3, 3, false), "missing,shown");
  EXPECT_EQ(row(2, 2, 3, false), "missing,missing");  // both lost: report 2's values are not shown
  EXPECT_EQ(row(3, 2, 3, true), "shown,pending");     // report 3's MDEV may still come
  EXPECT_EQ(row(2, 2, 3, true), "shown,shown");       // report 3 has none of them yet: report 2's
  EXPECT_EQ(row(2, 1, 3, true), "shown,missing");     // report 2 lost its MDEV
  v.taus[0].mdev.received = false;                    // never received: nothing to show yet
  v.report = 1;
  v.report_open = true;
  v.taus[0].adev.report = 1;
  EXPECT_EQ(name(viewed_row(v, 0).mdev), std::string("pending"));
  v.taus[0].adev.received = false;
  EXPECT_EQ(name(viewed_row(v, 0).adev), std::string("shown"));  // shown as "-"
  // The plot leaves a stale value out: report 3 closed without tau 0's MDEV.
  v.sampling = MetaSamplingMsg{0, 0.125f, 8};
  v.taus[0].m = 1;
  row(3, 2, 3, false);
  ConfidenceIntervals intervals(0.683);
  const NodePlot p = plot_data(v, rate_unit("deg/h"), intervals);
  EXPECT_EQ(p.adev.size(), 1u);
  EXPECT_EQ(p.mdev.size(), 0u);
}

TEST(DecodeOutput, PlotDrawsEachIeeeTermAsItsOwnLineAndReadsItOff) {
  // Parameters in arcsec and s; the rate unit deg/h is numerically arcsec/s, so every closed form
  // below is in the wire's numbers.
  const std::array<float, 5> qnbkr{2.0f, 0.1f, 0.01f, 0.001f, 1e-5f};
  NodeView v = node_in(AngleUnit::arcsec);
  v.status.tau_count = 10;
  v.sampling = MetaSamplingMsg{0, 0.125f, 8};
  for (std::size_t i = 0; i < 10; ++i) {
    v.taus[i].m = std::uint64_t{1} << i;  // tau 0.125 .. 64 s
    v.taus[i].adev = {true, 1.0f / static_cast<float>(i + 1), 50.0, NoiseType::white_fm, i != 4};
    v.taus[i].mdev = {true, 0.5f / static_cast<float>(i + 1), 0.0, NoiseType::white_fm, true};
  }
  for (std::size_t k = 0; k < 5; ++k) v.ieee952[k] = {true, true, qnbkr[k], 0.1};
  ConfidenceIntervals intervals(0.683);
  const NodePlot p = plot_data(v, rate_unit("deg/h"), intervals);

  EXPECT_EQ(p.rate_name, "deg/h");
  ASSERT_EQ(p.adev.size(), 9u);  // tau 4 is not valid
  ASSERT_EQ(p.mdev.size(), 10u);
  EXPECT_TRUE(p.adev[0].ci.valid);
  EXPECT_FALSE(p.mdev[0].ci.valid);  // no EDF, no error bar
  EXPECT_DOUBLE_EQ(p.tau_min_s, 0.125 / 2);
  EXPECT_DOUBLE_EQ(p.tau_max_s, 64.0 * 2);

  const double q = qnbkr[0], n = qnbkr[1], b = qnbkr[2], k = qnbkr[3], r = qnbkr[4];
  const double b_floor = std::sqrt(2.0 * std::log(2.0) / std::numbers::pi);  // 0.6643
  ASSERT_EQ(p.terms.size(), 6u);                                             // Q N B K R and their sum
  for (std::size_t j = 0; j < p.terms[0].tau_s.size(); ++j) {
    const double t = p.terms[0].tau_s[j];
    const std::array<double, 5> want{std::sqrt(3.0) * q / t, n / std::sqrt(t), b_floor * b, k * std::sqrt(t / 3.0),
                                     r * t / std::sqrt(2.0)};
    double sum2 = 0;
    for (std::size_t term = 0; term < 5; ++term) {
      expect_rel(p.terms[term].dev[j], want[term], 1e-12);
      sum2 += want[term] * want[term];
    }
    expect_rel(p.terms[5].dev[j], std::sqrt(sum2), 1e-12);
  }
  EXPECT_EQ(p.terms[1].label, "N 0.00167 deg/sqrt(h) (±10%)");  // 0.1 arcsec/sqrt(s) = 0.1 x 60 / 3600 deg/sqrt(h)
  EXPECT_EQ(p.terms[5].label, "IEEE-952 model (sum)");

  ASSERT_EQ(p.read_offs.size(), 5u);
  const auto read = [&](const std::string& label) {
    for (const ReadOffPoint& x : p.read_offs)
      if (x.label == label) return x;
    ADD_FAILURE() << "no read-off " << label;
    return ReadOffPoint{};
  };
  // Where each term's ADEV equals its parameter.
  EXPECT_DOUBLE_EQ(read("Q at sqrt(3) s").tau_s, std::sqrt(3.0));
  expect_rel(read("Q at sqrt(3) s").dev, q, 1e-12);
  EXPECT_EQ(read("N at 1 s").tau_s, 1.0);
  expect_rel(read("N at 1 s").dev, n, 1e-12);
  EXPECT_EQ(read("K at 3 s").tau_s, 3.0);
  expect_rel(read("K at 3 s").dev, k, 1e-12);
  EXPECT_DOUBLE_EQ(read("R at sqrt(2) s").tau_s, std::sqrt(2.0));
  expect_rel(read("R at sqrt(2) s").dev, r, 1e-12);
  const ReadOffPoint floor = read("0.664 B");
  expect_rel(floor.dev, b_floor * b, 1e-12);
  const double model_at_floor = p.terms[5].dev[static_cast<std::size_t>(
      std::find(p.terms[5].tau_s.begin(), p.terms[5].tau_s.end(), floor.tau_s) - p.terms[5].tau_s.begin())];
  for (std::size_t j = 0; j < p.terms[5].tau_s.size(); ++j) {  // at the model's minimum within the points
    if (p.terms[5].tau_s[j] >= 0.125 && p.terms[5].tau_s[j] <= 64.0) {
      EXPECT_GE(p.terms[5].dev[j], model_at_floor);
    }
  }

  v.ieee952[1].resolved = false;  // N not resolved: no line, no read-off
  v.ieee952[3].received = false;  // K never received
  const NodePlot fewer = plot_data(v, rate_unit("deg/h"), intervals);
  EXPECT_EQ(fewer.terms.size(), 4u);  // Q B R and the sum
  EXPECT_EQ(fewer.read_offs.size(), 3u);
}

/// A node with ten octave taus (0.125 .. 64 s) in arcsec, its fit's terms in arcsec and s.
NodeView node_with_curve(const std::array<float, 5>& qnbkr) {
  NodeView v = node_in(AngleUnit::arcsec);
  v.status.tau_count = 10;
  v.sampling = MetaSamplingMsg{0, 0.125f, 8};
  for (std::size_t i = 0; i < 10; ++i) {
    v.taus[i].m = std::uint64_t{1} << i;
    v.taus[i].adev = {true, 1.0f / static_cast<float>(i + 1), 50.0, NoiseType::white_fm, true};
    v.taus[i].mdev = {true, 0.5f / static_cast<float>(i + 1), 50.0, NoiseType::white_fm, true};
  }
  for (std::size_t k = 0; k < 5; ++k) v.ieee952[k] = {true, qnbkr[k] > 0, qnbkr[k], 0.1, qnbkr[k] > 0};
  return v;
}

TEST(DecodeOutput, PlotTruthCarriesTheSimulatedMarkovTerm) {
  // A simulated gyro with N and a Gauss-Markov rate of sigma 0.2 arcsec/s (deg/h) and Tc 30 s: its
  // truth line is the exact sampled curve from tau0 (0.125 s) on. Oracle: the continuous-time AVAR
  // of the two, N^2/tau + (sigma Tc / tau)^2 (2 tau/Tc - 3 + 4 e^(-tau/Tc) - e^(-2 tau/Tc)) (IEEE
  // 952 Annex C), which the sampled one approaches within 0.5 % at tau >= 8 tau0 (the N term is
  // exact there, the Markov term's sampling correction of order (tau0 / tau)^2).
  NodeView v = node_with_curve({0.0f, 0.1f, 0.0f, 0.0f, 0.0f});
  v.ieee952_summary = Ieee952SummaryMsg{0, Ieee952Status::ok, 0.9f, 18, true, {0, 0}};
  const double arcsec = std::numbers::pi / 648000, n = 0.12, sigma = 0.2, tc = 30;
  const TrueTerms truth{{0.0, n * arcsec, 0.0, 0.0, 0.0}, {{sigma * arcsec, tc}}, {}};
  ConfidenceIntervals intervals(0.683);
  const NodePlot p = plot_data(v, rate_unit("deg/h"), intervals, &truth);
  ASSERT_TRUE(p.truth.has_value());
  EXPECT_GE(p.truth->tau_s.front(), 0.125);
  std::size_t checked = 0;
  for (std::size_t j = 0; j < p.truth->tau_s.size(); ++j) {
    const double t = p.truth->tau_s[j], x = t / tc;
    if (t < 1.0) continue;
    const double markov = sigma * sigma / (x * x) * (2 * x - 3 + 4 * std::exp(-x) - std::exp(-2 * x));
    expect_rel(p.truth->dev[j], std::sqrt(n * n / t + markov), 5e-3);
    ++checked;
  }
  EXPECT_GT(checked, 10u);
  // Without the Markov term the line would be N's alone: near its peak (1.89 Tc) the two differ.
  const TrueTerms five{{0.0, n * arcsec, 0.0, 0.0, 0.0}, {}, {}};
  const NodePlot q = plot_data(v, rate_unit("deg/h"), intervals, &five);
  ASSERT_TRUE(q.truth.has_value());
  EXPECT_GT(p.truth->dev.back(), 1.5 * q.truth->dev.back());
}

TEST(DecodeOutput, PlotOfARejectedFitDrawsNoModelAndSaysSo) {
  NodeView v = node_with_curve({2.0f, 0.1f, 0.01f, 0.0f, 0.0f});
  v.ieee952_summary = Ieee952SummaryMsg{0, Ieee952Status::rejected, 12.5f, 20, true, {0, 0}};
  for (auto& t : v.ieee952) t.resolved = false;  // a rejected fit resolves nothing
  ConfidenceIntervals intervals(0.683);
  const NodePlot p = plot_data(v, rate_unit("deg/h"), intervals);
  EXPECT_EQ(p.adev.size(), 10u);  // the measurements are still drawn
  EXPECT_TRUE(p.terms.empty());
  EXPECT_TRUE(p.read_offs.empty());
  ASSERT_EQ(p.notes.size(), 2u);  // two legend lines
  EXPECT_EQ(p.notes[0], "IEEE-952 fit REJECTED (chi2/dof 12.5):");
  EXPECT_EQ(p.notes[1], "the model does not describe the curve");

  v.ieee952_summary->status = Ieee952Status::too_few_points;
  const NodePlot none = plot_data(v, rate_unit("deg/h"), intervals);
  EXPECT_TRUE(none.terms.empty());
  ASSERT_EQ(none.notes.size(), 1u);
  EXPECT_EQ(none.notes[0], "no IEEE-952 fit: too few points");
}

TEST(DecodeOutput, PlotOfAVersionFourModelDrawsItsMarkovTermAndNeverAnotherCyclesModel) {
  // N 0.1 arcsec/sqrt(s) and a Markov term of sigma 0.05 arcsec/s, Tc 5 s, in the summary's slow
  // cycle. Oracle for the lines: IEEE 952 Annex C's AVAR of exponentially correlated rate noise,
  // (q Tc)^2 / tau [1 - Tc / (2 tau) (3 - 4 e^(-tau/Tc) + e^(-2 tau/Tc))] with (q Tc)^2 = 2 sigma^2 Tc,
  // the continuous limit of the sampled estimator the plot draws: within 2 % from tau = 16 tau0.
  NodeView v = node_with_curve({0.0f, 0.1f, 0.0f, 0.0f, 0.0f});
  v.clock = MetaClockMsg{0, 1000, 4};
  v.ieee952_summary = Ieee952SummaryMsg{0, Ieee952Status::ok, 1.1f, 20, true, {0, 0}};
  v.report = 4;  // the latest report, closed; the curve's values are from it
  v.reports_made = 3;
  for (std::size_t i = 0; i < 10; ++i) v.taus[i].adev.report = v.taus[i].mdev.report = 4;
  v.ieee952_summary_cycle = 1;
  v.fit_model.cycle = 1;
  v.fit_model.model = Ieee952ModelMsg{0, 1, 0, false, 0, false, 0, 0, false, 0.0f};
  for (std::size_t k = 0; k < fit_parameter_pages; ++k) {
    const FitParameterSlot p = fit_parameter_slot(k);
    v.fit_model.parameters[k] = Ieee952ParameterMsg{0, p.parameter, p.index, false, 0.0f, 0.0};
  }
  v.fit_model.parameters[0] = Ieee952ParameterMsg{0, FitParameter::markov_sigma, 0, true, 0.05f, 0.1};
  v.fit_model.parameters[1] = Ieee952ParameterMsg{0, FitParameter::markov_tc, 0, false, 5.0f, 0.2};
  ConfidenceIntervals intervals(0.683);
  const NodePlot p = plot_data(v, rate_unit("deg/h"), intervals);  // deg/h: numerically arcsec/s
  ASSERT_EQ(p.terms.size(), 3u);                                   // N, the Markov term, the sum
  EXPECT_TRUE(p.terms[1].markov);
  EXPECT_EQ(p.terms[1].label, "Markov 0.05 deg/h (±10%), Tc 5 s");  // sigma, its uncertainty, Tc
  const double n = 0.1f, sigma = 0.05f, tc = 5.0;
  const auto markov_avar = [&](double t) {
    return 2 * sigma * sigma * tc / t * (1 - tc / (2 * t) * (3 - 4 * std::exp(-t / tc) + std::exp(-2 * t / tc)));
  };
  std::size_t compared = 0;
  for (std::size_t j = 0; j < p.terms[1].tau_s.size(); ++j) {
    const double t = p.terms[1].tau_s[j];
    if (t < 16 * 0.125) continue;
    expect_rel(p.terms[1].dev[j], std::sqrt(markov_avar(t)), 0.02);
    expect_rel(p.terms[2].dev[j], std::sqrt(n * n / t + markov_avar(t)), 0.02);
    ++compared;
  }
  EXPECT_GT(compared, 40u);
  // The summary of the next cycle has come, its model pages not all: no model is drawn.
  v.ieee952_summary_cycle = 2;
  v.reports_made = 6;
  v.report = 7;
  v.report_open = true;
  for (std::size_t i = 0; i < 10; ++i) v.taus[i].adev.report = v.taus[i].mdev.report = 7;
  const NodePlot pending = plot_data(v, rate_unit("deg/h"), intervals);
  ASSERT_EQ(pending.notes.size(), 2u);
  EXPECT_EQ(pending.notes[0], "fit's model pages pending:");
  EXPECT_EQ(pending.terms.size(), 1u);  // N's own line only: no Markov line, no sum
}

TEST(DecodeOutput, PlotSumIsTheFittedModelWithHeldQAndTheTruthBeside) {
  // Q held (quantization not white, pulse weight 1 arcsec), N resolved, B fitted but not resolved.
  NodeView v = node_with_curve({0.0f, 0.1f, 0.01f, 0.0f, 0.0f});
  v.ieee952[2].resolved = false;
  v.ieee952_summary = Ieee952SummaryMsg{0, Ieee952Status::ok, 0.875f, 18, false, {3, 2}};
  const TrueTerms truth{{2.5 * std::numbers::pi / 648000, 0.12 * std::numbers::pi / 648000, 0.0, 0.0, 0.0},
                        {},
                        {}};  // arcsec -> rad
  ConfidenceIntervals intervals(0.683);
  const NodePlot p = plot_data(v, rate_unit("deg/h"), intervals, &truth);
  ASSERT_EQ(p.terms.size(), 2u);  // N's own line and the model
  EXPECT_EQ(p.terms[0].term, Ieee952Term::angle_random_walk);
  EXPECT_EQ(p.terms[1].label, "IEEE-952 model, chi2/dof 0.88");
  // Oracle: IEEE 952's closed form, 3Q^2/tau^2 + N^2/tau + (2 ln2/pi) B^2, Q = 1/sqrt(12) arcsec;
  // deg/h is numerically arcsec/s.
  const double q2 = 1.0 / 12, floor = 2 * std::log(2.0) / std::numbers::pi;
  for (std::size_t j = 0; j < p.terms[1].tau_s.size(); ++j) {
    const double t = p.terms[1].tau_s[j];
    expect_rel(p.terms[1].dev[j],
               std::sqrt(3 * q2 / (t * t) + static_cast<double>(0.1f) * 0.1f / t +
                         floor * static_cast<double>(0.01f) * 0.01f),
               1e-12);
  }
  ASSERT_TRUE(p.truth.has_value());
  for (std::size_t j = 0; j < p.truth->tau_s.size(); ++j) {
    const double t = p.truth->tau_s[j];
    expect_rel(p.truth->dev[j], std::sqrt(3 * 2.5 * 2.5 / (t * t) + 0.12 * 0.12 / t), 1e-12);
  }
  ASSERT_EQ(p.notes.size(), 2u);
  EXPECT_EQ(p.notes[0], "quantization not white, fit");
  EXPECT_EQ(p.notes[1], "left out: ADEV < 1 s, MDEV < 0.5 s");  // 0.125 s x 2^3, 2^2
  EXPECT_EQ(p.read_offs.size(), 1u);                            // N at 1 s only: B is not resolved

  // A node reporting pulses: no angle to put the truth in.
  NodeView pulses = v;
  pulses.scale->angle_unit = AngleUnit::pulse;
  EXPECT_FALSE(plot_data(pulses, rate_unit("deg/h"), intervals, &truth).truth.has_value());
}

TEST(DecodeOutput, ViewShowsTheSimulatedValueBesideEachTerm) {
  // Through the decoder, from frames: a node in arcsec with N = 0.18 arcsec/sqrt(s) = 0.003 deg/sqrt(h).
  Decoder decoder;
  double t = 1.0;
  for (const Message& m : std::vector<Message>{StatusMsg{3, NodeState::running, 1, 100},
                                               MetaScaleMsg{3, 1.0f, AngleUnit::arcsec, InputSource::simulated},
                                               Ieee952Msg{3, Ieee952Term::angle_random_walk, true, 0.18f, 0.018, true},
                                               Ieee952Msg{3, Ieee952Term::bias_instability, false, 0.01f, 1.5,
                                                          true},  // 0.01 arcsec/s = 0.01 deg/h
                                               Ieee952SummaryMsg{3, Ieee952Status::ok, 0.93f, 24, true, {0, 0}}})
    decoder.feed(frame_of(m, 0x12), t += 0.01);
  TrueTermsByNode truth;
  truth[0x12] = {{0.0, 0.003 * std::numbers::pi / 180 / 60, 0.01 * std::numbers::pi / 180 / 3600, 0.0, 0.0}, {}, {}};
  InputCounters input;
  ConfidenceIntervals intervals(0.683);
  const std::string view = format_view(decoder, input, NodeFilter{}.set(), rate_unit("deg/h"), intervals, &truth);
  EXPECT_NE(view.find("IEEE-952 (node's fit of both curves, chi2/dof 0.93 on 24 points):"), std::string::npos) << view;
  EXPECT_NE(view.find("  N 0.003 deg/sqrt(h) (+-1.8%), simulated 0.003"), std::string::npos) << view;
  EXPECT_NE(view.find("  B 0.01 deg/h (not resolved, +-150.0%), simulated 0.01"), std::string::npos) << view;
  EXPECT_NE(view.find("  K -, simulated 0"), std::string::npos) << view;  // K's frame not received
  const std::string plain = format_view(decoder, input, NodeFilter{}.set(), rate_unit("deg/h"), intervals);
  EXPECT_EQ(plain.find(", simulated"), std::string::npos) << plain;
}

TEST(DecodeOutput, LineReaderGivesWholeLinesWhateverTheReads) {
  int fds[2];
  ASSERT_EQ(pipe(fds), 0);
  const std::string text = "a\r\nbb\n\n0123456789abcdefXY\nlast";
  ASSERT_EQ(write(fds[1], text.data(), text.size()), static_cast<ssize_t>(text.size()));
  close(fds[1]);
  LineReader reader(fds[0], 8);  // a line longer than 8 bytes: its first 9 bytes, the rest skipped
  std::vector<std::string> lines;
  std::string_view line;
  for (LineReader::Result r; (r = reader.next(line)) != LineReader::Result::end;) {
    ASSERT_NE(r, LineReader::Result::error);
    if (r == LineReader::Result::line) lines.emplace_back(line);
  }
  close(fds[0]);
  const std::vector<std::string> want{"a", "bb", "", "012345678", "last"};
  EXPECT_EQ(lines, want);
}

// A line of 5 MB, far longer than the reader's buffer, is skipped across many reads: the reader
// returns its first max_candump_line_bytes + 1 bytes once, then the next line whole.
TEST(DecodeOutput, LineReaderSkipsAnOverlongLineAcrossReads) {
  const std::string path = gyrochar::test_support::temp_path("long_line.txt");
  {
    std::FILE* f = std::fopen(path.c_str(), "w");
    ASSERT_NE(f, nullptr);
    const std::string chunk(1 << 20, 'x');
    for (int k = 0; k < 5; ++k) std::fputs(chunk.c_str(), f);
    std::fputs("\r\nnext\nlast", f);
    std::fclose(f);
  }
  const int fd = open(path.c_str(), O_RDONLY);
  ASSERT_GE(fd, 0);
  LineReader reader(fd);
  std::vector<std::string> lines;
  std::string_view line;
  for (LineReader::Result r; (r = reader.next(line)) != LineReader::Result::end;) {
    ASSERT_NE(r, LineReader::Result::error);
    if (r == LineReader::Result::line) lines.emplace_back(line);
  }
  close(fd);
  std::remove(path.c_str());
  ASSERT_EQ(lines.size(), 3u);
  EXPECT_EQ(lines[0], std::string(max_candump_line_bytes + 1, 'x'));
  EXPECT_EQ(lines[1], "next");
  EXPECT_EQ(lines[2], "last");
}

}  // namespace
}  // namespace gyrochar::decoding
