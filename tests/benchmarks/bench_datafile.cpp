// The analyzer's reader alone (host_tools/analyze/datafile.*): bytes of text per second, from the
// page cache, for counts (integers of four digits, the integer fast path), the same file gzip'd
// (zlib's inflate in the loop) and phase values in exponent notation (std::from_chars). Run:
// toolchain/benchmarks.sh (writes BENCHMARKS.md); the files are made once in the build folder.
#include <benchmark/benchmark.h>
#include <sys/stat.h>

#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include "datafile.hpp"

namespace {

constexpr std::size_t values = 4'000'000;

// A file of `values` lines made by `line`, plain and gzip'd; returns its path.
template <class Line>
std::string made(const std::string& name, Line line) {
  const std::string path = "bench_datafile_" + name + ".txt";
  struct stat st {};
  if (stat(path.c_str(), &st) == 0) return path;
  std::FILE* f = std::fopen(path.c_str(), "w");
  std::mt19937_64 rng(1);
  for (std::size_t i = 0; i < values; ++i) std::fputs(line(rng).c_str(), f);
  std::fclose(f);
  if (std::system(("gzip -kf " + path).c_str()) != 0) std::abort();
  return path;
}

std::string counts_file() {
  return made("counts", [](std::mt19937_64& rng) { return std::to_string(3600 + static_cast<int>(rng() % 64)) + "\n"; });
}

std::string phase_file() {
  return made("phase", [](std::mt19937_64& rng) {
    char text[32];
    std::snprintf(text, sizeof text, "%.9e\n", std::uniform_real_distribution<double>(-1e-6, 1e-6)(rng));
    return std::string(text);
  });
}

// Reads `text` (or its gzip'd copy); bytes_per_second counts the text's bytes either way.
void Read(benchmark::State& state, const std::string& text, bool gzip) {
  std::vector<double> block(1 << 14);
  for (auto _ : state) {
    gyrochar::DataFile file(gzip ? text + ".gz" : text);
    std::size_t n = 0;
    while (const std::size_t k = file.read(block)) n += k;
    if (n != values) state.SkipWithError("wrong number of values");
  }
  struct stat st {};
  stat(text.c_str(), &st);
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations()) * st.st_size);
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * values));
}

void ReadCounts(benchmark::State& state) { Read(state, counts_file(), false); }
void ReadCountsGzip(benchmark::State& state) { Read(state, counts_file(), true); }
void ReadPhase(benchmark::State& state) { Read(state, phase_file(), false); }

}  // namespace

BENCHMARK(ReadCounts)->Unit(benchmark::kMillisecond);
BENCHMARK(ReadCountsGzip)->Unit(benchmark::kMillisecond);
BENCHMARK(ReadPhase)->Unit(benchmark::kMillisecond);
BENCHMARK_MAIN();
