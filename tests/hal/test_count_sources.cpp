// The pure count-source decoders: quadrature (every transition, illegal ones, binning by timestamp
// at interval edges, late edges, silence and stalls), strobe + counter (wrap, missed strobes,
// glitches) and CounterInput frames (sequence jumps, error flags). Oracle: the 4x quadrature state
// table (AB: 00 -> 10 -> 11 -> 01 -> 00 counts up) and the definitions in the headers.
#include <gtest/gtest.h>

#include <vector>

#include "gyrochar/wire/protocol.hpp"
#include "hal/can_counter.hpp"
#include "hal/quadrature.hpp"
#include "hal/strobe.hpp"

namespace gyrochar::hal {
namespace {

struct Recorder final : CountSink {
  std::vector<CountSample> samples;
  void on_sample(const CountSample& s) override { samples.push_back(s); }
};

constexpr std::uint64_t ms = 1000000;

QuadratureSettings settings(bool a = false, bool b = false) {
  QuadratureSettings s;
  s.start_ns = 0;
  s.tau0_ns = 10 * ms;
  s.initial_a = a;
  s.initial_b = b;
  return s;
}

TEST(Quadrature, EveryLegalTransitionCountsOneWayOrTheOther) {
  // Forward sequence of AB states; an edge from state k to k+1 is +1, to k-1 is -1.
  const bool seq[4][2] = {{false, false}, {true, false}, {true, true}, {false, true}};
  for (int k = 0; k < 4; ++k) {
    for (const int step : {+1, -1}) {
      const int j = (k + step + 4) % 4;
      const QuadratureLine line = seq[k][0] != seq[j][0] ? QuadratureLine::a : QuadratureLine::b;
      const bool level = line == QuadratureLine::a ? seq[j][0] : seq[j][1];
      QuadratureDecoder d(settings(seq[k][0], seq[k][1]));
      Recorder r;
      d.on_edge(1 * ms, line, level, r);
      d.close_until(10 * ms, r);
      ASSERT_EQ(r.samples.size(), 1u);
      EXPECT_EQ(r.samples[0].count, step) << "from state " << k;
      EXPECT_EQ(r.samples[0].lost_edges, 0u);
    }
  }
}

TEST(Quadrature, AnEdgeThatDoesNotChangeItsLineIsALostEdge) {
  for (const bool a : {false, true})
    for (const bool b : {false, true})
      for (const QuadratureLine line : {QuadratureLine::a, QuadratureLine::b}) {
        QuadratureDecoder d(settings(a, b));
        Recorder r;
        d.on_edge(1 * ms, line, line == QuadratureLine::a ? a : b, r);  // same level again
        d.close_until(10 * ms, r);
        ASSERT_EQ(r.samples.size(), 1u);
        EXPECT_EQ(r.samples[0].count, 0);
        EXPECT_EQ(r.samples[0].lost_edges, 1u);
        EXPECT_EQ(d.counters().lost_edges, 1u);
      }
}

TEST(Quadrature, FullCyclesAndBinningAtIntervalEdges) {
  QuadratureDecoder d(settings());
  Recorder r;
  // Four edges (one full forward cycle) in [0, 10 ms), the last one just before the boundary;
  // an edge exactly at 10 ms belongs to the second interval.
  d.on_edge(1 * ms, QuadratureLine::a, true, r);
  d.on_edge(2 * ms, QuadratureLine::b, true, r);
  d.on_edge(3 * ms, QuadratureLine::a, false, r);
  d.on_edge(10 * ms - 1, QuadratureLine::b, false, r);
  d.on_edge(10 * ms, QuadratureLine::b, true, r);  // backwards: -1
  d.close_until(19 * ms, r);
  ASSERT_EQ(r.samples.size(), 1u) << "the second interval is still open at 19 ms";
  d.close_until(20 * ms, r);
  ASSERT_EQ(r.samples.size(), 2u);
  EXPECT_EQ(r.samples[0].count, 4);
  EXPECT_EQ(r.samples[0].end_ns, 10 * ms);
  EXPECT_EQ(r.samples[1].count, -1);
  EXPECT_EQ(r.samples[1].end_ns, 20 * ms);
}

TEST(Quadrature, CloseMarginWaitsForLateEventsAndLateOnesStillCount) {
  QuadratureSettings s = settings();
  s.close_margin_ns = 3 * ms;
  QuadratureDecoder d(s);
  Recorder r;
  d.close_until(12 * ms, r);
  EXPECT_TRUE(r.samples.empty()) << "interval 0 closes only at 13 ms";
  d.on_edge(9 * ms, QuadratureLine::a, true, r);  // arrives within the margin: binned in interval 0
  d.close_until(13 * ms, r);
  d.on_edge(8 * ms, QuadratureLine::b, true, r);  // arrives too late: counted in the open interval
  d.close_until(23 * ms, r);
  ASSERT_EQ(r.samples.size(), 2u);
  EXPECT_EQ(r.samples[0].count, 1);
  EXPECT_EQ(r.samples[1].count, 1);
  EXPECT_EQ(d.counters().late_edges, 1u);
}

TEST(Quadrature, ShortSilenceIsZerosALongOneIsOneGap) {
  QuadratureSettings s = settings();
  s.max_silent_intervals = 5;
  QuadratureDecoder d(s);
  Recorder r;
  d.on_edge(1 * ms, QuadratureLine::a, true, r);
  d.on_edge(41 * ms, QuadratureLine::b, true, r);  // three silent intervals in between
  d.close_until(50 * ms, r);
  ASSERT_EQ(r.samples.size(), 5u);
  const std::int64_t want[5] = {1, 0, 0, 0, 1};
  for (int k = 0; k < 5; ++k) {
    EXPECT_EQ(r.samples[k].count, want[k]);
    EXPECT_FALSE(r.samples[k].gap);
    EXPECT_EQ(r.samples[k].end_ns, (k + 1) * 10 * ms);
  }
  // A clock jump of a day: one gap sample, bounded work.
  r.samples.clear();
  d.close_until(86400000 * ms, r);
  ASSERT_EQ(r.samples.size(), 1u);
  EXPECT_TRUE(r.samples[0].gap);
  EXPECT_EQ(r.samples[0].gap_intervals, 8640000u - 5u);
  EXPECT_EQ(d.counters().gaps, 1u);
}

TEST(Strobe, CountsAreCounterDifferencesModuloItsWidth) {
  StrobeDecoder d({10 * ms, 16});
  Recorder r;
  d.on_strobe(0, 65530, r);        // reference
  d.on_strobe(10 * ms, 4, r);      // wrapped: +10
  d.on_strobe(20 * ms, 65534, r);  // backwards: -6
  ASSERT_EQ(r.samples.size(), 2u);
  EXPECT_EQ(r.samples[0].count, 10);
  EXPECT_EQ(r.samples[1].count, -6);
}

TEST(Strobe, MissedStrobesAreAGapAndGlitchesAreIgnored) {
  StrobeDecoder d({10 * ms, 32});
  Recorder r;
  d.on_strobe(0, 100, r);
  d.on_strobe(2 * ms, 101, r);  // glitch: ignored
  d.on_strobe(10 * ms, 110, r);
  d.on_strobe(40 * ms, 140, r);  // two strobes missed
  d.on_strobe(50 * ms, 150, r);
  ASSERT_EQ(r.samples.size(), 3u);
  EXPECT_EQ(r.samples[0].count, 10);
  EXPECT_TRUE(r.samples[1].gap);
  EXPECT_EQ(r.samples[1].gap_intervals, 3u);
  EXPECT_EQ(r.samples[2].count, 10);
  EXPECT_EQ(d.counters().lost_edges, 1u);
}

CanFrame counter_frame(std::uint8_t node, std::uint32_t count, std::uint8_t seq, bool error = false) {
  protocol::CounterInputMsg m;
  m.count = count;
  m.seq = seq;
  m.count_error = error;
  CanFrame f;
  EXPECT_EQ(protocol::encode(m, node, f), protocol::ProtocolError::none);
  return f;
}

TEST(CanCounter, SequenceJumpsAndErrorFlagsAreGapsWrapIsNot) {
  CanCounterDecoder d(0x80);
  Recorder r;
  EXPECT_TRUE(d.on_frame(counter_frame(0x80, 0xFFFFFFF0u, 255), 0, r));
  EXPECT_FALSE(d.on_frame(counter_frame(0x81, 5, 0), 0, r)) << "another node's frames are not ours";
  EXPECT_TRUE(d.on_frame(counter_frame(0x80, 0x10, 0), 0, r));  // wraps: +32
  EXPECT_TRUE(d.on_frame(counter_frame(0x80, 0x20, 3), 0, r));  // seq 1, 2 lost
  EXPECT_TRUE(d.on_frame(counter_frame(0x80, 0x30, 4, true), 0, r));
  EXPECT_TRUE(d.on_frame(counter_frame(0x80, 0x2C, 5), 0, r));  // -4
  ASSERT_EQ(r.samples.size(), 4u);
  EXPECT_EQ(r.samples[0].count, 32);
  EXPECT_TRUE(r.samples[1].gap);
  EXPECT_EQ(r.samples[1].gap_intervals, 3u);
  EXPECT_TRUE(r.samples[2].gap);
  EXPECT_EQ(r.samples[2].lost_edges, 1u);
  EXPECT_EQ(r.samples[3].count, -4);
}

}  // namespace
}  // namespace gyrochar::hal
