#pragma once
// CRC-32 (IEEE 802.3, reflected polynomial 0xEDB88320, as zlib's crc32), for checkpoints.
// Nibble-table implementation: 64 bytes of table, O(n), no allocation.
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

namespace gyrochar {

/// Continues a CRC over `data` (start with crc = 0). crc32("123456789") = 0xCBF43926.
constexpr std::uint32_t crc32(std::span<const std::byte> data, std::uint32_t crc = 0) {
  constexpr std::array<std::uint32_t, 16> table = [] {
    std::array<std::uint32_t, 16> t{};
    for (std::uint32_t i = 0; i < 16; ++i) {
      std::uint32_t c = i;
      for (int k = 0; k < 4; ++k) c = (c & 1u) ? (c >> 1) ^ 0xEDB88320u : c >> 1;
      t[i] = c;
    }
    return t;
  }();
  crc = ~crc;
  for (const std::byte b : data) {
    crc ^= static_cast<std::uint32_t>(b);
    crc = (crc >> 4) ^ table[crc & 15u];
    crc = (crc >> 4) ^ table[crc & 15u];
  }
  return ~crc;
}

}  // namespace gyrochar
