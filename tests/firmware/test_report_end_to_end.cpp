// Board to host over the protocol: simulated gyro counts -> the board's estimator -> report frames
// (the codec) -> the host decoder. Oracles: the offline analyzer on the same counts (the decoded
// ADEV and MDEV must equal its values rounded to float32, exactly: both come from the same exact
// integer sums) and the decoder's own loss accounting (a complete report, nothing missing).
#include <gtest/gtest.h>

#include <memory>
#include <vector>

#include "analysis.hpp"
#include "decoder.hpp"
#include "gyro_sim.hpp"
#include "report.hpp"

namespace gyrochar {
namespace {

TEST(ReportEndToEnd, DecodedEstimatesEqualTheOfflineAnalyzer) {
  GyroParameters g;
  g.tau0_s = 0.01;
  g.pulse_weight_rad = units::arcsec;
  g.q_rad = 2 * units::arcsec;
  g.n_rad_sqrt_s = 0.003 * units::deg_per_sqrt_h;
  GyroSimulator sim(g);

  firmware::ReportSettings s;
  s.tau0_s = g.tau0_s;
  s.pulse_weight_arcsec = 1.0;
  s.stride_factor = 8;
  s.octaves = 16;
  s.source = protocol::InputSource::simulated;
  auto board = std::make_unique<firmware::BoardCharacterizer>();
  ASSERT_TRUE(firmware::configure(*board, s));

  AnalysisOptions o;
  o.type = DataType::counts;
  o.tau0_s = g.tau0_s;
  o.stride_factor = 8;
  o.stats = {DevStat::oadev, DevStat::mdev};
  for (unsigned k = 0; k < s.octaves; ++k) o.m_list.push_back(std::uint64_t{1} << k);
  Analyzer analyzer(o);

  Decoder decoder;
  double t = 0;
  const std::uint8_t node = 0x21;
  firmware::ReportContent content;
  firmware::ReportWorkspace workspace(s.octaves);
  for (std::uint8_t seq = 0; seq < 4; ++seq) {  // four reports: the whole slow cycle
    for (int k = 0; k < 100000; ++k) {
      const auto c = static_cast<std::int32_t>(sim.next_count());
      board->add_increment(c);
      analyzer.add(c);
    }
    firmware::build_report(*board, s, seq, 1000u * (seq + 1), {}, workspace, content);
    for (std::size_t k = 0; k < protocol::report_frame_count(seq, s.octaves); ++k) {
      CanFrame f;
      ASSERT_EQ(protocol::encode(firmware::report_message(content, k), node, f), protocol::ProtocolError::none);
      decoder.feed(f, t += 0.001);
    }
  }
  decoder.flush();
  const NodeView& v = decoder.nodes().at(node);
  EXPECT_EQ(v.health.reports_complete, 4u);
  EXPECT_EQ(v.health.frames_missing, 0u);
  EXPECT_EQ(v.status.sample_count, 400000u);
  const Analysis a = analyzer.result();
  std::size_t compared = 0;
  for (const auto& row : a.rows) {
    const std::size_t i = static_cast<std::size_t>(std::countr_zero(row.m));
    const TauView& tv = v.taus[i];
    EXPECT_EQ(tv.m, row.m);
    const float want = static_cast<float>(row.dev);  // pulses/s x 1 arcsec per pulse
    const float got = row.stat == DevStat::oadev ? tv.adev.dev : tv.mdev.dev;
    EXPECT_EQ(got, want) << name(row.stat) << " m=" << row.m;
    if (row.stat == DevStat::oadev) {
      // n travels in the slow cycle: it is the count at the report that carried it. Fully
      // overlapped taus (m <= S): (100000 (s+1) + 1) - 2m after report s (Stable32's N - 2m).
      EXPECT_GT(tv.n, 0u);
      EXPECT_LE(tv.n, row.n);
      if (row.m <= s.stride_factor) {
        EXPECT_EQ((tv.n + 2 * row.m - 1) % 100000, 0u) << "m=" << row.m << " n=" << tv.n;
      }
    }
    ++compared;
  }
  EXPECT_GE(compared, 2u * 15);
  EXPECT_TRUE(v.ieee952[1].resolved);  // angle random walk is there and resolved
}

}  // namespace
}  // namespace gyrochar
