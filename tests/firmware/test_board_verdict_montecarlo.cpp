// The acceptance verdict by Monte Carlo on the board's path: the gyros and the limit of
// tests/host/test_verdict_montecarlo.cpp (support/verdict_study.hpp: white quantization, true N 10 %
// inside N <= 0.003 deg/sqrt(h), at it and 10 % beyond it, runs of 15 minutes and 1 hour, the same
// seeds, so run r of a cell is the same record on both paths), but each record goes through the
// board program's own loop (firmware/board.hpp on the HAL fakes, as gyrochar-demo runs it: its
// octave taus at its stride, its fit at the slow cycles, protocol version 5 with the unconstrained
// estimates), its frames over the in-process CAN bus into the host decoder, and the verdict is the
// decoder's (node_decisions, as gyrochar-decode --limits gives it at the end of a log).
//
// Oracles: the stated risk of the rule, a wrong verdict ("fail" for a gyro within the limit, "pass"
// for one beyond it or at it) in at most 2.5 % of the runs; with 3 runs a cell (the board's loop,
// the bus and its fits cost 2 to 3 s of one core for an hour of gyro time, so the suite's version
// is small; the larger study's figures are in docs/metrology.md), 2 or more wrong ones would happen
// with a chance of 0.18 % at a true rate of 2.5 % (binomial tail, computed exactly:
// 1 - 0.975^3 - 3 x 0.025 x 0.975^2 = 0.0018; the test recomputes it), the bound tested. The
// link's own accounting: every report of every run arrives whole (a lossless bus), and the node's N
// is judged by its unconstrained estimate.
// GYROCHAR_DECODER_VERDICT_RUNS=N runs N a cell and GYROCHAR_DECODER_VERDICT_DURATIONS=900,3600
// other run lengths (s); GYROCHAR_DECODER_VERDICT_FIRST_RUN=F makes them runs F to F + N - 1 of each
// cell (their seeds), to share a study between processes. The table is printed (docs/metrology.md,
// "Acceptance limits and verdicts", has the larger study's figures).
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <vector>

#include "board.hpp"
#include "decoder.hpp"
#include "gyro_sim.hpp"
#include "hal/fake/fake_can_bus.hpp"
#include "hal/fake/fake_clock.hpp"
#include "hal/fake/fake_count_source.hpp"
#include "limits.hpp"
#include "node_report.hpp"
#include "sim_truth.hpp"
#include "support/verdict_study.hpp"
#include "units.hpp"

namespace gyrochar::test_support {
namespace {

constexpr std::uint64_t ms = 1000000;

// What one run left besides its verdict: the link's health and which estimate was judged.
struct RunRecord {
  Decision decision;
  std::uint64_t frames_missing = 0, reports_incomplete = 0;
  bool unconstrained = false;  // judged by the unconstrained estimate (version 5)
};

// The simulated gyro `o` through a board on the HAL fakes (the board's default estimation settings
// at the gyro's tau0 and pulse weight, the fit inline as in gyrochar-demo), its frames through the
// in-process bus to a decoder; the decoder's verdict of `limit` once the run's last report is in.
RunRecord board_run(const SimOptions& o, const Limit& limit) {
  firmware::Config c;
  c.node = 0x10;
  c.source = firmware::SourceKind::quadrature;  // any GPIO kind: the fake source stands in for it
  c.tau0_s = o.tau0_s;
  c.pulse_weight_arcsec = o.pulse_arcsec;
  hal::FakeCanBus bus;
  auto board_node = bus.attach();
  auto host = bus.attach(1 << 16);
  hal::FakeClock clock;
  hal::FakeTimer timer{clock};
  hal::FakeCountSource source;
  firmware::Board board(c, firmware::BoardIo{*board_node, &source, clock, timer}, firmware::FitMode::inline_fit);
  GyroSimulator gyro(gyro_parameters(o));
  std::vector<std::int64_t> counts(static_cast<std::size_t>(std::llround(o.duration_s / o.tau0_s)));
  for (auto& v : counts) v = gyro.next_count();
  const auto tau0_ns = static_cast<std::uint64_t>(std::llround(o.tau0_s * 1e9));
  const std::uint64_t start_ns = clock.now_ns(), end_ns = start_ns + counts.size() * tau0_ns;
  source.script_counts(start_ns, tau0_ns, counts.data(), counts.size());
  Decoder decoder;
  const auto advance = [&](std::uint64_t ns) {
    clock.advance(ns);
    timer.update();
    board.run_once(0);
    while (auto f = host->receive()) decoder.feed(*f, static_cast<double>(clock.now_ns() - start_ns) * 1e-9);
  };
  // Steps of a quarter second, as gyrochar-demo's clock; then the report being sent goes out whole.
  while (clock.now_ns() < end_ns) advance(250 * ms);
  for (int k = 0; k < 2000 && !board.between_reports(); ++k) advance(ms);
  decoder.flush();
  RunRecord out;
  const auto node = decoder.nodes().find(c.node);
  if (node == decoder.nodes().end()) {
    out.decision = decide(limit, no_estimate("no report heard"));
    return out;
  }
  const NodeView& v = node->second;
  out.decision = decoding::node_decisions(v, {limit}).front();
  out.frames_missing = v.health.frames_missing;
  out.reports_incomplete = v.health.reports_incomplete;
  out.unconstrained = out.decision.estimate.kind == estimate_unconstrained;
  return out;
}

TEST(BoardVerdictMonteCarlo, DecodedWrongVerdictsStayWithinTheStatedRisk) {
  const std::size_t runs = env_count("GYROCHAR_DECODER_VERDICT_RUNS", 3);
  const std::size_t first_run = env_count("GYROCHAR_DECODER_VERDICT_FIRST_RUN", 0);
  const Limit limit = parse_limits(verdict_limit_text).front();
  const std::vector<double> durations = env_durations("GYROCHAR_DECODER_VERDICT_DURATIONS", {900, 3600});
  ASSERT_GE(durations.size(), 1u);
  std::vector<std::array<VerdictTally, 3>> tally(durations.size());
  // Per cell: the judged estimate's distance from the truth in its stated standard uncertainties
  // (mean and root mean square): how far the decoded interval is honest.
  std::vector<std::array<double, 3>> sum_z(durations.size()), sum_z2(durations.size());
  std::uint64_t missing = 0, incomplete = 0, judged = 0, unconstrained = 0;
  for (std::size_t d = 0; d < durations.size(); ++d)
    for (std::size_t c = 0; c < verdict_truth_ratio.size(); ++c)
      for (std::size_t r = 0; r < runs; ++r) {
        const SimOptions o = verdict_gyro(durations[d], d, c, first_run + r);
        const RunRecord run = board_run(o, limit);
        tally[d][c].add(run.decision, o.duration_s);
        missing += run.frames_missing;
        incomplete += run.reports_incomplete;
        const LimitEstimate& e = run.decision.estimate;
        if (!e.usable) {  // said, so that a larger study names the run (its seed) and the cause
          std::printf("%s, %.0f s, run %zu (seed %llu): no verdict on N: %s\n", verdict_where[c], durations[d],
                      first_run + r, static_cast<unsigned long long>(o.seed), e.why.c_str());
          continue;
        }
        ++judged;
        unconstrained += run.unconstrained;
        const double u = (e.high - e.value) / decision_z;
        const double z = (e.value - o.arw_deg_per_sqrt_h * units::deg_per_sqrt_h) / u;
        sum_z[d][c] += z;
        sum_z2[d][c] += z * z;
      }
  print_verdict_table(durations, tally);
  std::printf("judged estimate - truth, in stated u: mean (rms) per cell\n");
  for (std::size_t d = 0; d < durations.size(); ++d)
    for (std::size_t c = 0; c < verdict_truth_ratio.size(); ++c) {
      const auto n = static_cast<double>(tally[d][c].resolved);
      if (n > 0)
        std::printf("%-13s %5.0f s  %+.3f (%.3f)\n", verdict_where[c], durations[d], sum_z[d][c] / n,
                    std::sqrt(sum_z2[d][c] / n));
    }
  EXPECT_EQ(missing, 0u) << "frames missing on a lossless bus";
  EXPECT_EQ(incomplete, 0u) << "reports closed incomplete on a lossless bus";
  EXPECT_EQ(unconstrained, judged) << "a version 5 node's N is judged by its unconstrained estimate";
  // The header's bound: 2 or more wrong verdicts in 3 runs have a chance of 0.18 % at 2.5 %; other run
  // counts allow the largest number whose excess has a chance below 1 %.
  EXPECT_NEAR(binomial_tail(3, 2, 0.025), 0.0018, 0.00005);
  std::size_t wrong_allowed = 0;
  while (binomial_tail(runs, wrong_allowed + 1, 0.025) > 0.01) ++wrong_allowed;
  for (std::size_t d = 0; d < durations.size(); ++d) {
    EXPECT_LE(tally[d][0].fail, wrong_allowed) << "fail for a gyro inside, run " << durations[d] << " s";
    EXPECT_LE(tally[d][2].pass, wrong_allowed) << "pass for a gyro beyond, run " << durations[d] << " s";
    EXPECT_LE(tally[d][1].pass, wrong_allowed) << "pass at the limit, run " << durations[d] << " s";
    EXPECT_LE(tally[d][1].fail, wrong_allowed) << "fail at the limit, run " << durations[d] << " s";
    // N resolved in every run: true of the suite's runs; the larger study's 15-minute cell at the
    // limit had one run whose board fit took the quantization for periodic (docs/metrology.md).
    for (const VerdictTally& t : tally[d]) EXPECT_EQ(t.resolved, t.runs) << "N is resolved in every run of this gyro";
  }
}

}  // namespace
}  // namespace gyrochar::test_support
