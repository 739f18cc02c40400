// The per-sample path alone, for instruction counting with valgrind --tool=callgrind:
//   per_sample N  -> N counts into a 40-octave, S = 8 characterizer (the board's configuration).
// Instructions per sample = (callgrind total - the same run with N = 0) / N. toolchain/benchmarks.sh
// also builds it for aarch64 and Cortex-M4 and counts them under QEMU.
#include <array>
#include <cstdint>
#include <cstdlib>

#include "gyrochar/characterizer.hpp"

int main(int argc, char** argv) {
  const long n = argc > 1 ? std::atol(argv[1]) : 1000000;
  static gyrochar::StaticCharacterizer<gyrochar::CountArith, 40, 8> characterizer;
  std::array<std::uint64_t, 40> m_list{};
  for (unsigned k = 0; k < 40; ++k) m_list[k] = std::uint64_t{1} << k;
  if (characterizer.configure({8, 0}, m_list) != gyrochar::ConfigureStatus::ok) return 1;
  std::uint32_t lfsr = 0xace1u;
  for (long i = 0; i < n; ++i) {
    lfsr = (lfsr >> 1) ^ (-(lfsr & 1u) & 0xb400u);
    characterizer.add_increment(static_cast<std::int32_t>(1000 + (lfsr & 63u)));
  }
  return characterizer.result(3).n[0] == 0 && n > 100 ? 2 : 0;  // reads the result (no stdio: runs bare on Cortex-M)
}
