// The board's IEEE-952 fit beside the report loop (fit_worker.hpp). Oracle: the inline mode, which
// is fit_ieee952() called directly, and the worker's own rule (a busy worker takes no new points).
#include <gtest/gtest.h>

#include <chrono>
#include <thread>
#include <vector>

#include "fit_worker.hpp"
#include "gyrochar/noise_model.hpp"

namespace gyrochar::firmware {
namespace {

// Angle random walk's curves, fully overlapped, at octave taus (tau0 = 0.01 s): AVAR = N^2 / tau
// and MVAR = N^2 / (2 tau), with N^2 = 4.
std::vector<FitPoint> arw_points(std::uint64_t n_phase) {
  std::vector<FitPoint> p;
  for (std::uint64_t m = 1; m <= n_phase / 8; m *= 2) {
    const double tau = 0.01 * static_cast<double>(m);
    p.push_back({Stat::avar, m, 1, n_phase - 2 * m, 4.0 / tau, 0.0});
    if (m > 1) p.push_back({Stat::mvar, m, 1, n_phase - 3 * m + 1, 2.0 / tau, 0.0});
  }
  return p;
}

FitWorker::Result wait_for(const FitWorker& w, std::uint64_t samples) {
  for (int i = 0; i < 6000; ++i) {  // up to a minute (a sanitizer build, a busy machine)
    const FitWorker::Result r = w.latest();
    if (r.samples == samples) return r;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return {};
}

TEST(FitWorker, BackgroundFitEqualsTheInlineFit) {
  const std::vector<FitPoint> points = arw_points(4096);
  const FitSetup setup{0.01, 4096, 0.0};
  FitWorker inline_worker(12, FitMode::inline_fit), background(12, FitMode::background);
  EXPECT_EQ(inline_worker.latest().samples, 0u);  // nothing yet
  inline_worker.request(points, setup, 4095);
  EXPECT_EQ(inline_worker.latest().samples, 4095u);  // at once
  background.request(points, setup, 4095);
  EXPECT_EQ(background.requested_samples(), 4095u);
  const FitWorker::Result got = wait_for(background, 4095);
  ASSERT_EQ(got.samples, 4095u) << "the background fit did not finish within a minute";
  const Ieee952Fit& want = inline_worker.latest().fit;
  EXPECT_EQ(got.fit.status, want.status);
  EXPECT_EQ(got.fit.points, want.points);
  for (std::size_t k = 0; k < 5; ++k) {
    EXPECT_EQ(got.fit.p[k].value, want.p[k].value) << k;
    EXPECT_EQ(got.fit.p[k].uncertainty, want.p[k].uncertainty) << k;
  }
}

TEST(FitWorker, ABusyWorkerTakesNoNewPoints) {
  const std::vector<FitPoint> points = arw_points(4096);
  const FitSetup setup{0.01, 4096, 0.0};
  FitWorker w(12, FitMode::background);
  w.request(points, setup, 100);
  w.request(points, setup, 200);  // the first is taken: busy until its fit is done
  EXPECT_EQ(w.requested_samples(), 100u);
  EXPECT_EQ(wait_for(w, 100).samples, 100u);
  w.request(points, setup, 300);  // idle again: taken
  EXPECT_EQ(w.requested_samples(), 300u);
}

}  // namespace
}  // namespace gyrochar::firmware
