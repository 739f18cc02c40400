#pragma once
// Count source interface of the HAL: integer counts per sample interval (tau0), with the interval's
// end time and quality flags. Backends: hal/linux/gpio_quadrature.hpp (A/B edges through libgpiod),
// hal/linux/gpio_strobe.hpp (a strobe line plus a hardware counter), hal/fake/fake_count_source.hpp
// (scripted, for host tests). CounterInput frames from the gyro electronics arrive on the CAN bus
// instead and are turned into samples by hal/can_counter.hpp.
#include <cstdint>

namespace gyrochar::hal {

struct CountSample {
  std::int64_t count = 0;        // pulses in the interval (signed: the sense of rotation)
  std::uint64_t end_ns = 0;      // end of the interval, monotonic clock
  std::uint32_t lost_edges = 0;  // edges known to be missing in this interval
  /// The interval (or `gap_intervals` of them) could not be measured: a stall, a clock jump, lost
  /// input. `count` is meaningless; the consumer starts a new segment (no term spans a gap).
  bool gap = false;
  std::uint64_t gap_intervals = 0;
};

/// Where a source delivers its samples (the board's estimator, a test's recorder).
class CountSink {
 public:
  virtual void on_sample(const CountSample& sample) = 0;

 protected:
  ~CountSink() = default;
};

struct CountSourceCounters {
  std::uint64_t samples = 0;     // intervals delivered (gaps included)
  std::uint64_t edges = 0;       // input events read
  std::uint64_t lost_edges = 0;  // illegal transitions, missed strobes' counts, overruns
  std::uint64_t late_edges = 0;  // events that arrived after their interval was closed
  std::uint64_t gaps = 0;        // gap samples delivered
  std::uint64_t gap_intervals = 0;
};

class CountSource {
 public:
  virtual ~CountSource() = default;
  /// Readable when input waits (for epoll).
  virtual int fd() const = 0;
  /// Reads waiting input (at most a bounded batch: an edge storm cannot starve the loop) and
  /// delivers every interval that is complete at `now_ns`. Never blocks.
  virtual void poll(std::uint64_t now_ns, CountSink& sink) = 0;
  virtual const CountSourceCounters& counters() const = 0;
};

}  // namespace gyrochar::hal
