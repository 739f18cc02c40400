#pragma once
// CounterInput frames from the gyro electronics (docs/protocol.md) as a count source: the count is
// the difference of successive accumulated counts (modulo 2^32, signed). A frame after lost frames
// (sequence jump), or one that says the electronics lost counts or were not ready, ends the
// segment: it is delivered as a gap, never bridged. Pure logic: the board feeds it the frames it
// receives on its CAN bus.
#include <cstdint>

#include "gyrochar/wire/can_frame.hpp"
#include "hal/count_source.hpp"

namespace gyrochar::hal {

class CanCounterDecoder {
 public:
  explicit CanCounterDecoder(std::uint8_t counter_node) : node_(counter_node) {}
  /// Returns true when the frame was a CounterInput frame from the configured node.
  bool on_frame(const CanFrame& frame, std::uint64_t now_ns, CountSink& sink);
  const CountSourceCounters& counters() const { return counters_; }

 private:
  std::uint8_t node_;
  bool have_reference_ = false;
  std::uint32_t last_count_ = 0;
  std::uint8_t last_seq_ = 0;
  CountSourceCounters counters_;
};

}  // namespace gyrochar::hal
