// Accumulator throughput (per-sample and block API, stride factors 4, 8, 16 and full) beside the
// textbook batch estimators on the same counts. Run: toolchain/benchmarks.sh (writes BENCHMARKS.md).
#include <benchmark/benchmark.h>

#include <memory>
#include <random>
#include <vector>

#include "batch_estimators.hpp"
#include "gyrochar/characterizer.hpp"

namespace gyrochar {
namespace {

const std::vector<std::int32_t>& counts(std::size_t n) {
  static std::vector<std::int32_t> data;
  if (data.size() < n) {
    std::mt19937_64 rng(1);
    data.resize(n);
    for (auto& c : data) c = 1000 + static_cast<std::int32_t>(rng() % 64);  // rate + quantization noise
  }
  return data;
}

std::vector<std::uint64_t> octave_taus(std::size_t n_points) {
  std::vector<std::uint64_t> m;
  for (std::uint64_t v = 1; 3 * v < n_points && m.size() < 40; v *= 2) m.push_back(v);
  return m;
}

// A characterizer on heap storage sized for the stride factor (0 = full: S >= largest m).
struct HeapCharacterizer {
  std::vector<CountArith::Entry> history;
  std::vector<Characterizer<CountArith>::TauState> taus;
  std::unique_ptr<Characterizer<CountArith>> pyramid;
  HeapCharacterizer(std::uint32_t stride_factor, const std::vector<std::uint64_t>& m_list) {
    std::uint32_t s = stride_factor;
    if (s == 0) s = static_cast<std::uint32_t>(std::bit_ceil(m_list.back()));
    history.resize(history_entries(s, m_list.back()));
    taus.resize(m_list.size());
    pyramid = std::make_unique<Characterizer<CountArith>>(history, taus);
    if (pyramid->configure({s, 0}, m_list) != ConfigureStatus::ok) std::abort();
  }
};

void PerSample(benchmark::State& state) {
  const auto n = static_cast<std::size_t>(state.range(1));
  const auto& data = counts(n);
  const auto m_list = octave_taus(1ull << 40);
  for (auto _ : state) {
    HeapCharacterizer p(static_cast<std::uint32_t>(state.range(0)), octave_taus(std::size_t{1} << 41));
    for (std::size_t i = 0; i < n; ++i) p.pyramid->add_increment(data[i]);
    benchmark::DoNotOptimize(p.pyramid->result(3));
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * n));
  (void)m_list;
}

void Block(benchmark::State& state) {
  const auto n = static_cast<std::size_t>(state.range(1));
  const auto& data = counts(n);
  for (auto _ : state) {
    HeapCharacterizer p(static_cast<std::uint32_t>(state.range(0)), octave_taus(std::size_t{1} << 41));
    p.pyramid->add_increments(std::span<const std::int32_t>(data.data(), n));
    benchmark::DoNotOptimize(p.pyramid->result(3));
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * n));
}

void FullStride(benchmark::State& state) {
  const auto n = static_cast<std::size_t>(state.range(0));
  const auto& data = counts(n);
  for (auto _ : state) {
    HeapCharacterizer p(0, octave_taus(n + 1));
    p.pyramid->add_increments(std::span<const std::int32_t>(data.data(), n));
    benchmark::DoNotOptimize(p.pyramid->result(0));
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * n));
}

void Batch(benchmark::State& state) {
  const auto n = static_cast<std::size_t>(state.range(0));
  std::vector<std::int32_t> data(counts(n).begin(), counts(n).begin() + static_cast<std::ptrdiff_t>(n));
  for (auto _ : state) benchmark::DoNotOptimize(bench::batch_estimators(data, octave_taus(n + 1)));
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * n));
}

BENCHMARK(PerSample)->ArgsProduct({{4, 8, 16}, {10'000'000}})->Unit(benchmark::kMillisecond);
BENCHMARK(Block)->ArgsProduct({{4, 8, 16}, {10'000'000}})->Unit(benchmark::kMillisecond);
BENCHMARK(FullStride)->Arg(1'000'000)->Arg(10'000'000)->Unit(benchmark::kMillisecond);
BENCHMARK(Batch)->Arg(1'000'000)->Arg(10'000'000)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace gyrochar

BENCHMARK_MAIN();
