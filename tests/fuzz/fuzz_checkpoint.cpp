// libFuzzer target: the board's checkpoint decoder, restore_checkpoint() (the cumulative
// characterizer, then the window), on any bytes. The first byte chooses whether the CRCs are
// recomputed where they lie (bit 0 clear: the fuzzer reaches the state's checks past them) or left
// as they are; the rest is the file. Either the file is refused (a reason given, both
// characterizers fresh) or the state it restores runs on: counts are added, every sum and noise
// statistic read, and a checkpoint of the result must restore again (accumulation keeps the
// invariants an accepted state has). Never a crash, a hang or a sanitizer report.
//
// The seed corpus (corpus/checkpoint) holds real checkpoints of this target's configuration:
//   GYROCHAR_FUZZ_WRITE_SEED=DIR build/fuzz/tests/fuzz/fuzz_checkpoint   writes them to DIR.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <span>
#include <string>
#include <vector>

#include "board.hpp"
#include "gyrochar/crc32.hpp"

namespace {

using namespace gyrochar;
using namespace gyrochar::firmware;

struct Target {
  ReportSettings settings;
  BoardCharacterizer cumulative, again;
  DynamicWindow window, window_again;
  std::vector<std::byte> buffer;

  Target() {
    settings.stride_factor = 8;
    settings.octaves = 16;
    settings.config_hash = 0x19191919;
    settings.identity = 0x18007;  // node 0x07, counter node 0x80
    settings.window_length = 64;
    settings.window_taus = window_taus(settings.octaves, settings.window_length);
    reset(cumulative, window);
    buffer.resize(cumulative.checkpoint_size() + window.checkpoint_size());
  }
  void reset(BoardCharacterizer& c, DynamicWindow& w) const {
    if (!configure(c, settings) || !w.configure(settings.stride_factor, settings.config_hash, settings.window_taus,
                                                settings.window_length, settings.identity))
      std::abort();
  }
  // The board's order: the cumulative part, then the window's.
  std::span<const std::byte> save() {
    const std::size_t n = cumulative.save(buffer);
    return std::span(buffer).first(n + window.save(std::span(buffer).subspan(n)));
  }
  void add(std::int32_t count) {
    cumulative.add_increment(count);
    window.add(count);
  }
};

Target& target() {
  static Target* t = new Target;
  return *t;
}

// The CRC-32 over [begin, end) stored at end, when the file reaches that far.
void reseal(std::vector<std::byte>& b, std::size_t begin, std::size_t end) {
  if (end + 4 > b.size() || begin > end) return;
  const std::uint32_t crc = crc32(std::span(b).subspan(begin, end - begin));
  std::memcpy(b.data() + end, &crc, 4);
}

// Counts from the input's bytes: small ones, and the int32 extremes (terms the block kernel's
// proofs do not cover).
std::int32_t count_from(std::uint64_t& z) {
  z = z * 6364136223846793005ull + 1442695040888963407ull;
  const auto r = static_cast<std::uint32_t>(z >> 32);
  if ((r & 15) == 0) return (r & 16) ? INT32_MAX : INT32_MIN;
  return static_cast<std::int32_t>(r % 2001) - 1000;
}

void write_seeds(const char* dir) {
  Target& t = target();
  std::uint64_t z = 19;
  for (const int samples : {0, 5, 300, 4000}) {
    t.reset(t.cumulative, t.window);
    for (int i = 0; i < samples; ++i) {
      if (i == samples / 3) {
        t.cumulative.mark_gap();
        t.window.mark_gap();
      }
      t.add(count_from(z));
    }
    const auto bytes = t.save();
    const std::string path = std::string(dir) + "/real_" + std::to_string(samples);
    std::FILE* f = std::fopen(path.c_str(), "wb");
    const std::uint8_t recompute = 0;
    if (f == nullptr || std::fwrite(&recompute, 1, 1, f) != 1 ||
        std::fwrite(bytes.data(), 1, bytes.size(), f) != bytes.size() || std::fclose(f) != 0)
      std::abort();
  }
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  if (const char* dir = std::getenv("GYROCHAR_FUZZ_WRITE_SEED")) {
    write_seeds(dir);
    std::exit(0);
  }
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  Target& t = target();
  t.reset(t.cumulative, t.window);
  std::vector<std::byte> file(size - 1);
  if (!file.empty()) std::memcpy(file.data(), data + 1, size - 1);
  if ((data[0] & 1) == 0) {
    const std::size_t cumulative = t.cumulative.checkpoint_size(), pyramid = t.window.pyramid().checkpoint_size();
    const std::size_t window_end = cumulative + t.window.checkpoint_size() - 4;
    reseal(file, 0, cumulative - 4);
    reseal(file, cumulative, cumulative + pyramid - 4);
    reseal(file, cumulative + pyramid, window_end);
  }
  const std::string why = restore_checkpoint(file, t.cumulative, t.window, t.settings);
  if (!why.empty()) {
    if (t.cumulative.increments() != 0 || t.window.samples() != 0) std::abort();  // refused: fresh
    return 0;
  }
  // Accepted: it runs on, reads out, and checkpoints again.
  std::uint64_t z = crc32(std::span(file));
  for (int i = 0; i < 300; ++i) {
    if (i == 150) {
      t.cumulative.mark_gap();
      t.window.mark_gap();
    }
    t.add(count_from(z));
  }
  double sink = 0;
  for (std::size_t i = 0; i < t.cumulative.tau_count(); ++i) {
    const auto r = t.cumulative.result(i);
    for (std::size_t k = 0; k < sum_kinds; ++k) sink += variance(r, static_cast<SumKind>(k), 0.001);
    for (int d = 0; d < 4; ++d) sink += t.cumulative.noise(i).order(d).r1() + t.cumulative.noise(i).order(d).variance();
  }
  for (std::size_t i = 0; i < t.window.taus(); ++i) sink += t.window.latest().avar[i];
  const auto saved = t.save();
  const std::vector<std::byte> copy(saved.begin(), saved.end());
  t.reset(t.again, t.window_again);
  const std::string again = restore_checkpoint(copy, t.again, t.window_again, t.settings);
  if (!again.empty()) {
    std::fprintf(stderr, "an accepted state, run on, was refused: %s\n", again.c_str());
    std::abort();
  }
  if (t.again.increments() != t.cumulative.increments()) std::abort();
  return sink == 1.25 ? 1 : 0;  // keeps the reads; libFuzzer ignores the value
}
