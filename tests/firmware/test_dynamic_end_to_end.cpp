// The dynamic Allan deviation from end to end on the fakes: a simulated gyro whose angle random walk
// doubles halfway -> the board program (firmware::Board: its window beside the cumulative
// characterizer, the Window frames of its reports) -> the in-process CAN bus -> the decoder's
// session (window curves per node, CSV and JSON lines window rows) -> and the same counts offline
// through gyrochar-analyze's engine (--dynamic).
// Oracles: the offline analysis of each window (the same exact integer sums: the decoded deviations
// equal its values within the wire's rounding of 2^-15 octave, 2.2e-5); the closed-form Allan
// deviation of white rate noise and white quantization, sqrt(N^2 / tau + 3 Q^2 / tau^2) with
// Q = pulse / sqrt(12), in each half of the run, within 4 standard errors from the analysis's EDF;
// and the decoder's own accounting (every window complete, no window frame without its page).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "board.hpp"
#include "session.hpp"
#include "dynamic.hpp"
#include "hal/fake/fake_can_bus.hpp"
#include "hal/fake/fake_clock.hpp"
#include "hal/fake/fake_count_source.hpp"
#include "sim_truth.hpp"

namespace gyrochar {
namespace {

constexpr double tau0_s = 0.01;
constexpr std::uint64_t window = 6000;  // 60 s
constexpr std::size_t windows = 16;

// 1 arcsec pulses, N = 0.2 deg/sqrt(h) (1.2 pulses of random angle per sample: white
// quantization), doubling at 480 s, the start of window 8.
SimOptions doubling_gyro() {
  SimOptions o;
  o.duration_s = 1000;
  o.tau0_s = tau0_s;
  o.arw_deg_per_sqrt_h = 0.2;
  o.seed = 5;
  SimSegment g;
  g.start_s = 480;
  g.arw_deg_per_sqrt_h = 0.4;
  o.segments = {g};
  return o;
}

double closed_form_adev(double n_deg_per_sqrt_h, double tau_s) {  // arcsec/s
  const double n = n_deg_per_sqrt_h * 60.0, q = 1.0 / std::sqrt(12.0);
  return std::sqrt(n * n / tau_s + 3 * q * q / (tau_s * tau_s));
}

std::string contents(std::FILE* f) {
  std::rewind(f);
  std::string s;
  char buf[4096];
  while (const std::size_t n = std::fread(buf, 1, sizeof buf, f)) s.append(buf, n);
  return s;
}

std::size_t count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t at = 0; (at = text.find(what, at)) != std::string::npos; at += what.size()) ++n;
  return n;
}

TEST(DynamicEndToEnd, TheBoardTheDecoderAndTheAnalyzerSeeTheAngleRandomWalkDouble) {
  const SimOptions sim = doubling_gyro();
  firmware::Config c;
  c.node = 0x21;
  c.source = firmware::SourceKind::quadrature;  // the fake source stands in for it
  c.tau0_s = tau0_s;
  c.octaves = 16;
  c.report_period_s = 1.0;
  c.window_s = static_cast<double>(window) * tau0_s;

  hal::FakeClock clock;
  hal::FakeCanBus bus;
  auto board_node = bus.attach(), host = bus.attach(1 << 16);
  hal::FakeTimer timer(clock);
  hal::FakeCountSource source;
  firmware::Board board(c, firmware::BoardIo{*board_node, &source, clock, timer});
  ASSERT_EQ(board.window().taus(), 11u);  // 4 m <= 6000: m up to 1024

  std::unique_ptr<std::FILE, int (*)(std::FILE*)> csv(std::tmpfile(), std::fclose), jsonl(std::tmpfile(), std::fclose);
  decoding::SessionOptions so;
  so.rate_unit = std::nullopt;  // native: arcsec/s, as the analyzer's counts of 1 arcsec
  so.csv = csv.get();
  so.jsonl = jsonl.get();
  decoding::Session session(so);

  AnalysisOptions ao;
  ao.type = DataType::counts;
  ao.tau0_s = tau0_s;
  ao.stride_factor = c.stride_factor;
  for (unsigned k = 0; k < board.window().taus(); ++k) ao.m_list.push_back(std::uint64_t{1} << k);
  DynamicAnalyzer offline(ao, window, window);
  std::vector<WindowAnalysis> analysed;

  // The demo's loop: the clock moves a quarter second, that quarter's counts go to the board's
  // source and to the offline engine, the board runs, what crossed the bus goes to the decoder.
  SimRun run(sim);
  const auto tau0_ns = static_cast<std::uint64_t>(std::llround(tau0_s * 1e9));
  const std::uint64_t start_ns = clock.now_ns(), step_ns = 250000000;
  std::uint64_t scripted_ns = start_ns, samples = 0;
  std::vector<std::int64_t> counts;
  while (samples < run.samples()) {
    clock.advance(step_ns);
    counts.resize(std::min<std::uint64_t>((clock.now_ns() - scripted_ns) / tau0_ns, run.samples() - samples));
    for (auto& v : counts) {
      v = run.next_count();
      offline.add(static_cast<double>(v));
    }
    for (WindowAnalysis& w : offline.take_completed()) analysed.push_back(std::move(w));
    source.script_counts(scripted_ns, tau0_ns, counts.data(), counts.size());
    scripted_ns += counts.size() * tau0_ns;
    samples += counts.size();
    timer.update();
    board.run_once(0);
    while (auto f = host->receive()) session.feed(*f, static_cast<double>(clock.now_ns() - start_ns) * 1e-9);
  }
  session.finish();
  ASSERT_EQ(analysed.size(), windows);
  ASSERT_EQ(board.window().latest().window, windows - 1);

  const NodeView& v = session.decoder().nodes().at(0x21);
  EXPECT_EQ(v.window_taus, 11u);
  EXPECT_EQ(v.window_length, window);
  EXPECT_EQ(v.health.window_frames_unplaced, 0u);
  EXPECT_EQ(v.health.reports_lost, 0u);
  EXPECT_LE(v.health.reports_incomplete, 1u) << "only the last report, cut by the end of the run";
  ASSERT_EQ(v.windows.size(), windows) << "every window reached the decoder";
  for (const WindowAnalysis& w : analysed) {
    const WindowView& d = v.windows.at(static_cast<std::uint32_t>(w.index));
    ASSERT_TRUE(d.complete()) << w.index;
    EXPECT_EQ(d.gaps, 0u);
    for (const AnalysisRow& row : w.analysis.rows) {
      if (row.stat != DevStat::oadev && row.stat != DevStat::mdev) continue;
      const auto i = static_cast<std::size_t>(std::countr_zero(row.m));
      const double decoded = row.stat == DevStat::oadev ? d.adev[i] : d.mdev[i];
      EXPECT_NEAR(decoded / row.dev, 1.0, 2.2e-5) << "window " << w.index << " " << name(row.stat) << " m " << row.m;
    }
  }
  // The doubling, in the decoded windows: at the taus N dominates, each half near its closed form.
  for (const std::uint64_t m : {16u, 32u, 64u, 128u}) {
    const auto i = static_cast<std::size_t>(std::countr_zero(m));
    const double tau_s = static_cast<double>(m) * tau0_s;
    double mean[2] = {0, 0}, edf = 0;
    for (const WindowAnalysis& w : analysed) {
      const std::size_t half = w.index < windows / 2 ? 0 : 1;
      mean[half] += v.windows.at(static_cast<std::uint32_t>(w.index)).adev[i] / (windows / 2);
      for (const AnalysisRow& row : w.analysis.rows)
        if (row.stat == DevStat::oadev && row.m == m) edf = row.edf;
    }
    ASSERT_GT(edf, 10.0);
    EXPECT_NEAR(mean[0] / closed_form_adev(0.2, tau_s), 1.0, 4 / std::sqrt(2 * edf * windows / 2)) << tau_s;
    EXPECT_NEAR(mean[1] / closed_form_adev(0.4, tau_s), 1.0, 4 / std::sqrt(2 * edf * windows / 2)) << tau_s;
  }
  // CSV and JSON lines: one window row per window and window tau (and the CSV header names them).
  const std::string csv_text = contents(csv.get()), jsonl_text = contents(jsonl.get());
  EXPECT_EQ(count(csv_text, ",window,"), 1 + windows * 11);
  EXPECT_EQ(count(jsonl_text, "\"type\":\"window\""), windows * 11);
}

}  // namespace
}  // namespace gyrochar
