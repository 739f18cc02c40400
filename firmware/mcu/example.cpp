// The freestanding core on a microcontroller: feeds simulated pulse counts into a 40-octave,
// stride-8 pyramid and takes a snapshot. Built for Cortex-M4F and Cortex-M7 to show the core carries
// to an MCU-based gyro board unchanged (sizes in docs/benchmarks.md). No heap, no exceptions.
#include <array>
#include <cstdint>

#include "gyrochar/pyramid.hpp"

namespace {
gyrochar::StaticPyramid<gyrochar::CountArith, 40, 8> pyramid;
std::array<gyrochar::Pyramid<gyrochar::CountArith>::Result, 40> snapshot;
}  // namespace

int main() {
  std::array<std::uint64_t, 40> m_list{};
  for (unsigned k = 0; k < m_list.size(); ++k) m_list[k] = std::uint64_t{1} << k;
  if (pyramid.configure({8, false}, m_list) != gyrochar::PyramidStatus::ok) return 1;
  std::uint32_t lfsr = 0xace1u;  // a counter stand-in: rate plus a pseudo-random dither residue
  for (int i = 0; i < 100000; ++i) {
    lfsr = (lfsr >> 1) ^ (-(lfsr & 1u) & 0xb400u);
    pyramid.add_increment(static_cast<std::int32_t>(1000 + (lfsr & 7u)));
  }
  pyramid.snapshot(snapshot);
  return snapshot[4].n[0] > 0 ? 0 : 2;
}
