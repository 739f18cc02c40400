#pragma once
// A clock that tests advance by hand, and timers on it whose eventfd becomes readable when an
// advance passes their deadline, so the same epoll loop runs on virtual time.
#include <cstdint>

#include "hal/clock.hpp"

namespace gyrochar::hal {

class FakeClock final : public Clock {
 public:
  explicit FakeClock(std::uint64_t start_ns = 1000000000u) : now_(start_ns) {}
  std::uint64_t now_ns() const override { return now_; }
  void advance(std::uint64_t ns) { now_ += ns; }

 private:
  std::uint64_t now_;
};

class FakeTimer final : public PeriodicTimer {
 public:
  explicit FakeTimer(const FakeClock& clock);
  ~FakeTimer() override;
  FakeTimer(const FakeTimer&) = delete;
  FakeTimer& operator=(const FakeTimer&) = delete;
  void start(std::uint64_t period_ns) override;
  /// Readable when the clock has passed the next deadline (call update() after advancing).
  int fd() const override { return fd_; }
  std::uint64_t take_expirations() override;
  /// Re-evaluates readiness after the clock moved.
  void update();

 private:
  const FakeClock& clock_;
  std::uint64_t period_ = 0, next_ = 0;
  int fd_ = -1;
};

}  // namespace gyrochar::hal
