#pragma once
// Clock and timer interface of the HAL: monotonic time and a periodic wake-up with a pollable file
// descriptor. Backends: hal/linux/timer.hpp (CLOCK_MONOTONIC, timerfd) and hal/fake/fake_clock.hpp
// (time that a test advances by hand).
#include <cstdint>

namespace gyrochar::hal {

class Clock {
 public:
  virtual ~Clock() = default;
  virtual std::uint64_t now_ns() const = 0;
};

class PeriodicTimer {
 public:
  virtual ~PeriodicTimer() = default;
  /// First expiry one period from now, then every period.
  virtual void start(std::uint64_t period_ns) = 0;
  /// Readable while expirations are pending.
  virtual int fd() const = 0;
  /// Expirations since the last call (0 if none); clears them.
  virtual std::uint64_t take_expirations() = 0;
};

}  // namespace gyrochar::hal
