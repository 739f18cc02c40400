// What the dynamic Allan deviation costs the board (docs/dynamic.md): its sample path with the
// cumulative characterizer alone and with the window beside it (firmware/window.hpp), configured
// as gyrochard configures them (32 octave taus, S = 8; windows of 2^21 samples: 20 window taus,
// and of 2^31: the 30 the capacity allows), and the memory both take.
//   bench_window [Google Benchmark options]
//   bench_window --samples N LOG2  N samples with windows of 2^LOG2 (0: none), for instruction
//                                  counting: valgrind --tool=callgrind, minus the same with N = 0
#include <benchmark/benchmark.h>

#include <cstdio>
#include <cstdlib>
#include <memory>
#include <random>
#include <string_view>
#include <vector>

#include "report.hpp"
#include "window.hpp"

namespace gyrochar::firmware {
namespace {

const std::vector<std::int32_t>& counts() {
  static std::vector<std::int32_t> data;
  if (data.empty()) {
    std::mt19937_64 rng(1);
    data.resize(std::size_t{1} << 22);
    for (auto& c : data) c = 1000 + static_cast<std::int32_t>(rng() % 64);  // rate + quantization noise
  }
  return data;
}

// The board's two characterizers, configured as gyrochard configures them.
struct BoardPath {
  std::unique_ptr<BoardCharacterizer> cumulative = std::make_unique<BoardCharacterizer>();
  std::unique_ptr<DynamicWindow> window = std::make_unique<DynamicWindow>();
  std::uint64_t length = 0;
  unsigned window_taus = 0;
  explicit BoardPath(unsigned length_log2) {
    ReportSettings s;
    s.tau0_s = 0.001;
    s.stride_factor = 8;
    s.octaves = 32;
    if (!configure(*cumulative, s)) std::abort();
    length = length_log2 ? std::uint64_t{1} << length_log2 : 0;
    window_taus = firmware::window_taus(s.octaves, length);
    if (length != 0 && !window->configure(s.stride_factor, 0, window_taus, length)) std::abort();
  }
  void add(std::int32_t c) {
    cumulative->add_increment(c);
    if (length != 0) window->add(c);
  }
};

// range(0): window length log2 (0: no window).
void BoardSamplePath(benchmark::State& state) {
  const auto& data = counts();
  BoardPath board(static_cast<unsigned>(state.range(0)));
  std::size_t i = 0;
  for (auto _ : state) board.add(data[i++ & (data.size() - 1)]);
  benchmark::DoNotOptimize(board.cumulative->result(3));
  benchmark::DoNotOptimize(board.window->latest());
  state.SetItemsProcessed(state.iterations());
  state.counters["window_taus"] = board.window_taus;
  state.counters["state_bytes"] = static_cast<double>(sizeof(BoardCharacterizer) +
                                                      (board.length ? sizeof(DynamicWindow) : 0));
}
BENCHMARK(BoardSamplePath)->Arg(0)->Arg(21)->Arg(31)->MinTime(1.0);

}  // namespace
}  // namespace gyrochar::firmware

int main(int argc, char** argv) {
  if (argc == 4 && std::string_view(argv[1]) == "--samples") {
    const auto& data = gyrochar::firmware::counts();
    gyrochar::firmware::BoardPath board(static_cast<unsigned>(std::atoi(argv[3])));
    const long n = std::atol(argv[2]);
    for (long i = 0; i < n; ++i) board.add(data[static_cast<std::size_t>(i) & (data.size() - 1)]);
    std::printf("%llu\n", static_cast<unsigned long long>(board.cumulative->result(3).n[0] + board.window->latest().window));
    return 0;
  }
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  return 0;
}
