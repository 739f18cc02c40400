#pragma once
// A CAN frame as the protocol codec produces and the HAL carries it: classic (up to 8 data bytes)
// or CAN FD (up to 64). Plain value type, no allocation; shared by core/, hal/ and host_tools/.
#include <array>
#include <cstdint>

namespace gyrochar {

struct CanFrame {
  static constexpr std::uint8_t max_classic_len = 8;
  static constexpr std::uint8_t max_fd_len = 64;

  std::uint32_t id = 0;   // 11-bit or 29-bit identifier, without flag bits
  bool extended = false;  // 29-bit identifier
  bool fd = false;        // CAN FD frame (len may exceed 8)
  bool error = false;     // error frame reported by the controller (id holds error class bits)
  std::uint8_t len = 0;   // data length in bytes
  std::array<std::uint8_t, max_fd_len> data{};
};

}  // namespace gyrochar
