#pragma once
// candump log lines (`candump -l`, replayable by canplayer):
//   (1436509052.249713) can0 18FF4101#0102030405060708     classic, 29-bit id (8 hex digits)
//   (1436509052.249713) can0 123#R                          remote request (11-bit id: 3 digits)
//   (1436509052.249713) can0 18FF4101##1<up to 64 bytes>    CAN FD, first nibble = flags
//   (1436509052.249713) can0 20000004#0004000000000000      error frame (CAN_ERR_FLAG in the id)
// One parser for the decoder and the tests; malformed lines are rejected with a reason.
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "gyrochar/wire/can_frame.hpp"

namespace gyrochar {

/// The longest candump log line accepted, in bytes (without its newline): far above the longest
/// line candump writes (a CAN FD frame of 64 bytes with a 15-character interface, about 180).
inline constexpr std::size_t max_candump_line_bytes = 1024;

struct CandumpLine {
  double time_s = 0.0;  // timestamp in seconds (as printed)
  std::string interface;
  CanFrame frame;
  bool remote = false;
};

/// Parses one line (no trailing newline needed). Returns false and sets `why` for a malformed line,
/// a line longer than max_candump_line_bytes among them. A remote request (`123#R`, `#R8`) sets
/// `remote` and the frame's length to its DLC, with no data. O(line length); allocates only the
/// interface name.
bool parse_candump_line(std::string_view line, CandumpLine& out, std::string& why);

/// Formats a frame as a candump log line.
std::string format_candump_line(double time_s, std::string_view interface, const CanFrame& frame);

}  // namespace gyrochar
