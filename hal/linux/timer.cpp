#include "hal/linux/timer.hpp"

#include <sys/timerfd.h>
#include <unistd.h>

#include <cerrno>
#include <ctime>
#include <system_error>

namespace gyrochar::hal {

std::uint64_t MonotonicClock::now_ns() const {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::uint64_t>(ts.tv_sec) * 1000000000u + static_cast<std::uint64_t>(ts.tv_nsec);
}

TimerFd::TimerFd() : fd_(timerfd_create(CLOCK_MONOTONIC, TFD_NONBLOCK | TFD_CLOEXEC)) {
  if (fd_ < 0) throw std::system_error(errno, std::generic_category(), "timerfd_create");
}

TimerFd::~TimerFd() { close(fd_); }

void TimerFd::start(std::uint64_t period_ns) {
  itimerspec spec{};
  spec.it_interval.tv_sec = static_cast<time_t>(period_ns / 1000000000u);
  spec.it_interval.tv_nsec = static_cast<long>(period_ns % 1000000000u);
  spec.it_value = spec.it_interval;
  if (timerfd_settime(fd_, 0, &spec, nullptr) != 0)
    throw std::system_error(errno, std::generic_category(), "timerfd_settime");
}

std::uint64_t TimerFd::take_expirations() {
  std::uint64_t n = 0;
  return read(fd_, &n, sizeof n) == static_cast<ssize_t>(sizeof n) ? n : 0;
}

}  // namespace gyrochar::hal
