#include "hal/linux/gpio_strobe.hpp"

#include <fcntl.h>
#include <gpiod.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <stdexcept>

namespace gyrochar::hal {

GpioStrobeSource::GpioStrobeSource(const GpioStrobeSettings& s) : decoder_(StrobeDecoder({s.tau0_ns, s.counter_bits})) {
  chip_ = gpiod_chip_open_lookup(s.chip.c_str());
  if (chip_ == nullptr) throw std::runtime_error(s.chip + ": cannot open GPIO chip: " + std::strerror(errno));
  const std::string what = s.chip + " line " + std::to_string(s.line) + ": ";
  line_ = gpiod_chip_get_line(chip_, s.line);
  if (line_ == nullptr || gpiod_line_request_rising_edge_events(line_, "gyrochard") != 0) {
    const int e = errno;
    line_ = nullptr;
    release();
    throw std::runtime_error(what + "cannot request edge events: " + std::strerror(e));
  }
  fcntl(fd(), F_SETFL, fcntl(fd(), F_GETFL) | O_NONBLOCK);
  counter_fd_ = open(s.counter_path.c_str(), O_RDONLY | O_CLOEXEC);
  std::uint64_t value = 0;
  if (counter_fd_ < 0 || !read_counter(value)) {
    const int e = errno;
    release();
    throw std::runtime_error(s.counter_path + ": cannot read the counter: " + std::strerror(e));
  }
}

GpioStrobeSource::~GpioStrobeSource() { release(); }

void GpioStrobeSource::release() {
  if (line_ != nullptr) gpiod_line_release(line_);
  if (chip_ != nullptr) gpiod_chip_close(chip_);
  if (counter_fd_ >= 0) close(counter_fd_);
  line_ = nullptr;
  chip_ = nullptr;
  counter_fd_ = -1;
}

int GpioStrobeSource::fd() const { return gpiod_line_event_get_fd(line_); }

bool GpioStrobeSource::read_counter(std::uint64_t& value) const {
  char text[32];
  const ssize_t n = pread(counter_fd_, text, sizeof text - 1, 0);
  if (n <= 0) return false;
  text[n] = '\0';
  char* end = nullptr;
  errno = 0;
  value = std::strtoull(text, &end, 10);
  return errno == 0 && end != text;
}

void GpioStrobeSource::poll(std::uint64_t, CountSink& sink) {
  gpiod_line_event events[batch];
  const int n = gpiod_line_event_read_multiple(line_, events, batch);
  for (int k = 0; k < n; ++k) {
    std::uint64_t value = 0;
    const std::uint64_t t = static_cast<std::uint64_t>(events[k].ts.tv_sec) * 1000000000u +
                            static_cast<std::uint64_t>(events[k].ts.tv_nsec);
    // An unreadable counter loses this strobe: the next one then spans two intervals, which the
    // decoder's missed-strobe rule delivers as a gap.
    if (read_counter(value)) decoder_.on_strobe(t, value, sink);
  }
}

}  // namespace gyrochar::hal
