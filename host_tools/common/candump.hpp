#pragma once
// candump log lines (`candump -l`, replayable by canplayer):
//   (1436509052.249713) can0 18FF4101#0102030405060708     classic, 29-bit id (8 hex digits)
//   (1436509052.249713) can0 123#R                          remote request (11-bit id: 3 digits)
//   (1436509052.249713) can0 18FF4101##1<up to 64 bytes>    CAN FD, first nibble = flags
//   (1436509052.249713) can0 20000004#0004000000000000      error frame (CAN_ERR_FLAG in the id)
// One parser for the decoder and the tests; malformed lines are rejected with a reason.
#include <cstdint>
#include <string>
#include <string_view>

#include "gyrochar/can_frame.hpp"

namespace gyrochar {

struct CandumpLine {
  double time_s = 0.0;   // timestamp in seconds (as printed)
  std::string interface;
  CanFrame frame;
  bool remote = false;
};

/// Parses one line (no trailing newline needed). Returns false and sets `why` for a malformed line.
/// O(line length); allocates only the interface name.
bool parse_candump_line(std::string_view line, CandumpLine& out, std::string& why);

/// Formats a frame as a candump log line.
std::string format_candump_line(double time_s, std::string_view interface, const CanFrame& frame);

}  // namespace gyrochar
