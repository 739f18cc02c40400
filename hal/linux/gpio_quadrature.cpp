#include "hal/linux/gpio_quadrature.hpp"

#include <fcntl.h>
#include <gpiod.h>
#include <sys/epoll.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace gyrochar::hal {
namespace {

constexpr const char* consumer = "gyrochard";

std::uint64_t to_ns(const timespec& ts) {
  return static_cast<std::uint64_t>(ts.tv_sec) * 1000000000u + static_cast<std::uint64_t>(ts.tv_nsec);
}

QuadratureSettings decoder_settings(const GpioQuadratureSettings& s, std::uint64_t start_ns) {
  QuadratureSettings q;
  q.start_ns = start_ns;
  q.tau0_ns = s.tau0_ns;
  q.close_margin_ns = s.close_margin_ns;
  q.max_silent_intervals = s.max_silent_intervals;
  return q;
}

}  // namespace

GpioQuadratureSource::GpioQuadratureSource(const GpioQuadratureSettings& s, std::uint64_t start_ns)
    : decoder_(decoder_settings(s, start_ns)) {
  chip_ = gpiod_chip_open_lookup(s.chip.c_str());
  if (chip_ == nullptr) throw std::runtime_error(s.chip + ": cannot open GPIO chip: " + std::strerror(errno));
  epoll_ = epoll_create1(EPOLL_CLOEXEC);
  const unsigned offsets[2] = {s.line_a, s.line_b};
  bool levels[2] = {false, false};
  for (int k = 0; k < 2; ++k) {
    gpiod_line* line = gpiod_chip_get_line(chip_, offsets[k]);
    const std::string what = s.chip + " line " + std::to_string(offsets[k]) + ": ";
    if (line == nullptr) {
      const int e = errno;
      release();
      throw std::runtime_error(what + "no such line: " + std::strerror(e));
    }
    if (gpiod_line_request_both_edges_events(line, consumer) != 0) {
      const int e = errno;
      release();
      throw std::runtime_error(what + "cannot request edge events: " + std::strerror(e));
    }
    queues_[k].line = line;
    levels[k] = gpiod_line_get_value(line) == 1;
    const int fd = gpiod_line_event_get_fd(line);
    fcntl(fd, F_SETFL, fcntl(fd, F_GETFL) | O_NONBLOCK);
    epoll_event ev{};
    ev.events = EPOLLIN;
    ev.data.u32 = static_cast<std::uint32_t>(k);
    epoll_ctl(epoll_, EPOLL_CTL_ADD, fd, &ev);
  }
  QuadratureSettings q = decoder_settings(s, start_ns);
  q.initial_a = levels[0];
  q.initial_b = levels[1];
  decoder_ = QuadratureDecoder(q);
}

GpioQuadratureSource::~GpioQuadratureSource() { release(); }

void GpioQuadratureSource::release() {
  for (Queue& q : queues_)
    if (q.line != nullptr) gpiod_line_release(q.line);
  if (chip_ != nullptr) gpiod_chip_close(chip_);
  if (epoll_ >= 0) close(epoll_);
  chip_ = nullptr;
  epoll_ = -1;
  for (Queue& q : queues_) q.line = nullptr;
}

void GpioQuadratureSource::fill(Queue& q) {
  if (q.head == q.size) q.head = q.size = 0;
  if (q.size == batch) return;
  gpiod_line_event raw[batch];
  const int n = gpiod_line_event_read_multiple(q.line, raw, static_cast<unsigned>(batch - q.size));
  for (int k = 0; k < n; ++k) q.events[q.size++] = {to_ns(raw[k].ts), raw[k].event_type == GPIOD_LINE_EVENT_RISING_EDGE};
}

void GpioQuadratureSource::poll(std::uint64_t now_ns, CountSink& sink) {
  // Compact, then read both queues; merge what is older than now_ns in timestamp order.
  for (Queue& q : queues_) {
    if (q.head > 0) {
      for (std::size_t k = q.head; k < q.size; ++k) q.events[k - q.head] = q.events[k];
      q.size -= q.head;
      q.head = 0;
    }
    fill(q);
  }
  for (;;) {
    Queue* next = nullptr;
    int line = 0;
    for (int k = 0; k < 2; ++k) {
      Queue& q = queues_[k];
      if (q.head < q.size && q.events[q.head].t_ns <= now_ns &&
          (next == nullptr || q.events[q.head].t_ns < next->events[next->head].t_ns)) {
        next = &q;
        line = k;
      }
    }
    if (next == nullptr) break;
    const Event e = next->events[next->head++];
    decoder_.on_edge(e.t_ns, line == 0 ? QuadratureLine::a : QuadratureLine::b, e.level, sink);
  }
  // With a backlog left in the kernel (an edge storm), time must not close intervals its edges
  // belong to: the edges themselves move the intervals on.
  bool backlog = false;
  for (const Queue& q : queues_) backlog = backlog || q.size == batch;
  if (!backlog) decoder_.close_until(now_ns, sink);
}

}  // namespace gyrochar::hal
