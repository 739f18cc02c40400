#pragma once
// A sample strobe plus a hardware counter: each strobe edge ends an interval, and the counter value
// latched at that strobe (a capture register) gives the count as the difference of successive
// readings, modulo 2^counter_bits, taken as signed. Pure logic (no OS).
//
// A strobe later than 1.5 tau0 after the previous one means strobes were missed: the count spans
// several intervals and cannot be split, so it is delivered as a gap and the reading becomes the
// new reference. A strobe earlier than 0.5 tau0 is a glitch: ignored and counted as a lost edge.
#include <cstdint>

#include "hal/count_source.hpp"

namespace gyrochar::hal {

struct StrobeSettings {
  std::uint64_t tau0_ns = 1000000;
  unsigned counter_bits = 32;  // 1..64
};

class StrobeDecoder {
 public:
  explicit StrobeDecoder(const StrobeSettings& settings) : s_(settings) {}
  void on_strobe(std::uint64_t t_ns, std::uint64_t counter_value, CountSink& sink);
  const CountSourceCounters& counters() const { return counters_; }

 private:
  StrobeSettings s_;
  bool have_reference_ = false;
  std::uint64_t last_t_ns_ = 0, last_value_ = 0;
  CountSourceCounters counters_;
};

}  // namespace gyrochar::hal
