// The per-sample path alone, for instruction counting with valgrind --tool=callgrind:
//   per_sample N        -> N counts into a 40-octave, S = 8 characterizer (the board's
//                          configuration), add_increment() one count at a time
//   per_sample N block  -> the same counts through add_increments(), 4096 at a time
// Instructions per sample = (callgrind total - the same run with N = 0) / N. toolchain/benchmarks.sh
// also builds it for aarch64 and Cortex-M4 and counts them under QEMU.
#include <array>
#include <cstdint>
#include <cstdlib>
#include <span>

#include "gyrochar/characterizer.hpp"

int main(int argc, char** argv) {
  const long n = argc > 1 ? std::atol(argv[1]) : 1000000;
  const bool block = argc > 2;
  static gyrochar::StaticCharacterizer<gyrochar::CountArith, 40, 8> characterizer;
  std::array<std::uint64_t, 40> m_list{};
  for (unsigned k = 0; k < 40; ++k) m_list[k] = std::uint64_t{1} << k;
  if (characterizer.configure({8, 0}, m_list) != gyrochar::ConfigureStatus::ok) return 1;
  std::uint32_t lfsr = 0xace1u;
  const auto next = [&lfsr] {
    lfsr = (lfsr >> 1) ^ (-(lfsr & 1u) & 0xb400u);
    return static_cast<std::int32_t>(1000 + (lfsr & 63u));
  };
  if (!block) {
    for (long i = 0; i < n; ++i) characterizer.add_increment(next());
  } else {
    static std::array<std::int32_t, 4096> counts;
    for (long i = 0; i < n;) {
      std::size_t held = 0;
      for (; held < counts.size() && i < n; ++held, ++i) counts[held] = next();
      characterizer.add_increments(std::span<const std::int32_t>(counts.data(), held));
    }
  }
  return characterizer.result(3).n[0] == 0 && n > 100 ? 2 : 0;  // reads the result (no stdio: runs bare on Cortex-M)
}
