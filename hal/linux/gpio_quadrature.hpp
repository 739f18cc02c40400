#pragma once
// Quadrature A/B lines through libgpiod (1.6): both edges of both lines with kernel timestamps
// (CLOCK_MONOTONIC), merged in timestamp order and fed to the QuadratureDecoder. Each line has its
// own event queue; an epoll descriptor over both is this source's pollable fd. Events newer than
// the start of a poll wait for the next one, so that the two queues merge in order.
#include <array>
#include <cstdint>
#include <string>

#include "hal/count_source.hpp"
#include "hal/quadrature.hpp"

struct gpiod_chip;
struct gpiod_line;

namespace gyrochar::hal {

struct GpioQuadratureSettings {
  std::string chip = "gpiochip0";  // name, path, label or number (gpiod_chip_open_lookup)
  unsigned line_a = 0, line_b = 1;
  std::uint64_t tau0_ns = 1000000;
  std::uint64_t close_margin_ns = 2000000;  // event latency allowed before an interval closes
  std::uint64_t max_silent_intervals = 1000;
};

class GpioQuadratureSource final : public CountSource {
 public:
  /// Opens the chip and requests both lines; throws std::runtime_error naming what failed.
  GpioQuadratureSource(const GpioQuadratureSettings& settings, std::uint64_t start_ns);
  ~GpioQuadratureSource() override;
  GpioQuadratureSource(const GpioQuadratureSource&) = delete;
  GpioQuadratureSource& operator=(const GpioQuadratureSource&) = delete;
  int fd() const override { return epoll_; }
  void poll(std::uint64_t now_ns, CountSink& sink) override;
  const CountSourceCounters& counters() const override { return decoder_.counters(); }

  static constexpr std::size_t batch = 256;  // events read per line per poll

 private:
  struct Event {
    std::uint64_t t_ns;
    bool level;
  };
  struct Queue {  // events read from one line, not yet merged
    gpiod_line* line = nullptr;
    std::array<Event, batch> events{};
    std::size_t head = 0, size = 0;
  };
  void fill(Queue& q);
  void release();
  gpiod_chip* chip_ = nullptr;
  std::array<Queue, 2> queues_;
  QuadratureDecoder decoder_;
  int epoll_ = -1;
};

}  // namespace gyrochar::hal
