#pragma once
// Linux clock and timer: CLOCK_MONOTONIC (the clock of kernel GPIO event timestamps) and timerfd.
#include "hal/clock.hpp"

namespace gyrochar::hal {

class MonotonicClock final : public Clock {
 public:
  std::uint64_t now_ns() const override;
};

class TimerFd final : public PeriodicTimer {
 public:
  TimerFd();  // throws std::system_error
  ~TimerFd() override;
  TimerFd(const TimerFd&) = delete;
  TimerFd& operator=(const TimerFd&) = delete;
  void start(std::uint64_t period_ns) override;
  int fd() const override { return fd_; }
  std::uint64_t take_expirations() override;

 private:
  int fd_ = -1;
};

}  // namespace gyrochar::hal
