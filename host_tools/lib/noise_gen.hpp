#pragma once
// Power-law phase noise for tests: x = (1 - B)^(-d) w with w white and d = (2 - alpha) / 2, so that
// S_y(f) ~ f^alpha for alpha = +2 (white PM, d = 0), +1 (flicker PM), 0 (white FM, random walk
// phase), -1 (flicker FM), -2 (random walk FM). The fractional integration uses the impulse
// response of Kasdin & Walter (1992): h_0 = 1, h_k = h_{k-1} (k - 1 + d) / k. O(n^2): for test
// series of a few thousand points.
#include <cstdint>
#include <vector>

namespace gyrochar {

std::vector<double> power_law_phase(int alpha, std::size_t n, std::uint64_t seed);

}  // namespace gyrochar
