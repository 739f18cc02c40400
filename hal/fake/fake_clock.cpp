#include "hal/fake/fake_clock.hpp"

#include <sys/eventfd.h>
#include <unistd.h>

#include <cerrno>
#include <system_error>

namespace gyrochar::hal {

FakeTimer::FakeTimer(const FakeClock& clock) : clock_(clock), fd_(eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC)) {
  if (fd_ < 0) throw std::system_error(errno, std::generic_category(), "eventfd");
}

FakeTimer::~FakeTimer() { close(fd_); }

void FakeTimer::start(std::uint64_t period_ns) {
  period_ = period_ns;
  next_ = clock_.now_ns() + period_ns;
  update();
}

void FakeTimer::update() {
  std::uint64_t drained = 0;
  [[maybe_unused]] const auto r = read(fd_, &drained, sizeof drained);  // level reflects the clock
  if (period_ != 0 && clock_.now_ns() >= next_) {
    const std::uint64_t one = 1;
    [[maybe_unused]] const auto w = write(fd_, &one, sizeof one);
  }
}

std::uint64_t FakeTimer::take_expirations() {
  std::uint64_t n = 0;
  if (period_ != 0 && clock_.now_ns() >= next_) {
    n = (clock_.now_ns() - next_) / period_ + 1;
    next_ += n * period_;
  }
  update();
  return n;
}

}  // namespace gyrochar::hal
