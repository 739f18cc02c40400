#pragma once
// The board's capacities, fixed at compile time: what its characterizers and reports hold.
#include <cstdint>

namespace gyrochar::firmware {

inline constexpr unsigned max_octaves = 40;             // taus m = 1, 2, ..., 2^39
inline constexpr std::uint32_t max_stride_factor = 64;  // S
/// Window taus of the dynamic Allan deviation: 30 keep a 32-tau node's reports within 3 % of a
/// 500 kbit/s bus (docs/protocol.md section 7).
inline constexpr unsigned max_window_taus = 30;

}  // namespace gyrochar::firmware
