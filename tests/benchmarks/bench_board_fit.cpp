// What the board's IEEE-952 fit costs its background worker (firmware/fit_worker.hpp): one fit of
// both curves at the board's octave taus, the five terms alone (protocol versions 2 and 3) and with
// the model selection (version 4), without a covariance cache (the worker's first fit, every pair
// summed: its worst case) and with the cache the worker keeps, warmed by one fit of the same points
// (its later fits: the run grown, the pairs' sums linear in n). The points are the exact expectations of a
// gyro with angle random walk 0.02 deg/sqrt(h) and a Markov term of 0.5 deg/h, Tc 300 s (arcsec
// and s, as on the board), tau0 10 ms, a run of 2^20 samples (2.9 h) and 20 octave taus.
//   bench_board_fit [Google Benchmark options]
#include <benchmark/benchmark.h>

#include <cstdint>
#include <vector>

#include "gyrochar/ieee952.hpp"

namespace gyrochar {
namespace {

constexpr double tau0_s = 0.01;
constexpr std::uint64_t samples = std::uint64_t{1} << 20;
constexpr unsigned octaves = 20;

std::vector<FitPoint> points() {
  Ieee952Fit truth;
  truth.p[1].value = 0.02 * 60.0;  // N: deg/sqrt(h) -> arcsec/sqrt(s)
  truth.n_markov = 1;
  truth.markov[0].sigma.value = 0.5;  // deg/h = arcsec/s
  truth.markov[0].tc_s = 300.0;
  std::vector<FitPoint> p;
  for (unsigned k = 0; k < octaves; ++k) {
    const std::uint64_t m = std::uint64_t{1} << k;
    if (4 * m > samples) break;
    for (const Stat s : {Stat::avar, Stat::mvar}) {
      const std::uint64_t n = s == Stat::avar ? samples + 1 - 2 * m : samples + 2 - 3 * m;
      p.push_back({s, m, 1, n, fitted_variance(truth, s, m, tau0_s), 0.0});
    }
  }
  return p;
}

// range(0): 1 with the model selection, 0 the five terms alone; range(1): 1 with a warm cache.
void BoardFit(benchmark::State& state) {
  const std::vector<FitPoint> p = points();
  FitSetup setup{tau0_s, samples + 1, 0.01 / 3.4641016151377544};  // 0.01 arcsec pulses: Q_w = w / sqrt(12)
  setup.select_model = state.range(0) != 0;
  std::vector<double> workspace(ieee952_workspace_doubles(p.size()));
  std::vector<PairSumCache::Entry> entries(std::size_t{octaves} * octaves * 4 * 2 + 64);  // as the worker's
  PairSumCache cache(entries);
  PairSumCache* use = state.range(1) != 0 ? &cache : nullptr;
  Ieee952Fit fit = fit_ieee952(p, setup, FitCurve::both, workspace, use);
  for (auto _ : state) {
    fit = fit_ieee952(p, setup, FitCurve::both, workspace, use);
    benchmark::DoNotOptimize(fit);
  }
  state.counters["points"] = static_cast<double>(p.size());
  state.counters["markov"] = static_cast<double>(fit.n_markov);
  state.counters["ok"] = fit.ok() ? 1 : 0;
}
BENCHMARK(BoardFit)->Args({0, 0})->Args({1, 0})->Args({0, 1})->Args({1, 1})->Unit(benchmark::kMillisecond)->MinTime(2.0);

}  // namespace
}  // namespace gyrochar

BENCHMARK_MAIN();
