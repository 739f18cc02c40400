// The freestanding core on a microcontroller: feeds simulated pulse counts into a 40-octave,
// stride-8 characterizer and reads out the MDEV curve with its exact EDF. Built for Cortex-M4F and Cortex-M7 to show the core carries
// to an MCU-based gyro board unchanged (sizes in docs/benchmarks.md). No heap, no exceptions.
#include <array>
#include <cstdint>

#include "gyrochar/characterizer.hpp"
#include "gyrochar/estimates.hpp"

namespace {
gyrochar::StaticCharacterizer<gyrochar::CountArith, 40, 8> characterizer;
std::array<gyrochar::TauSums, 40> sums;
std::array<gyrochar::NoiseId, 40> noise;
}  // namespace

int main() {
  std::array<std::uint64_t, 40> m_list{};
  for (unsigned k = 0; k < m_list.size(); ++k) m_list[k] = std::uint64_t{1} << k;
  if (characterizer.configure({8, 0}, m_list) != gyrochar::ConfigureStatus::ok) return 1;
  std::uint32_t lfsr = 0xace1u;  // a counter stand-in: rate plus a pseudo-random dither residue
  for (int i = 0; i < 100000; ++i) {
    lfsr = (lfsr >> 1) ^ (-(lfsr & 1u) & 0xb400u);
    characterizer.add_increment(static_cast<std::int32_t>(1000 + (lfsr & 7u)));
  }
  gyrochar::take_sums(characterizer, sums);
  gyrochar::identify_noise(sums, characterizer.phase_points(), 2, false, noise);
  const auto e = gyrochar::estimate(sums[4], characterizer.phase_points(), gyrochar::DevStat::mdev, noise[4], {});
  return e.n > 0 && e.edf > 0 ? 0 : 2;
}
