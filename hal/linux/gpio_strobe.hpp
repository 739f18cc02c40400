#pragma once
// Sample strobe on a GPIO line (rising edges, kernel timestamps, through libgpiod 1.6) plus a
// hardware counter read from a file (a sysfs counter attribute such as
// /sys/bus/counter/devices/counter0/count0/count) that the strobe latches. Each strobe is fed to
// the StrobeDecoder with the counter value read right after it.
#include <cstdint>
#include <string>

#include "hal/count_source.hpp"
#include "hal/strobe.hpp"

struct gpiod_chip;
struct gpiod_line;

namespace gyrochar::hal {

struct GpioStrobeSettings {
  std::string chip = "gpiochip0";
  unsigned line = 0;
  std::string counter_path;  // file holding the latched count as decimal text
  unsigned counter_bits = 32;
  std::uint64_t tau0_ns = 1000000;
};

class GpioStrobeSource final : public CountSource {
 public:
  /// Throws std::runtime_error naming what failed (chip, line, counter file).
  explicit GpioStrobeSource(const GpioStrobeSettings& settings);
  ~GpioStrobeSource() override;
  GpioStrobeSource(const GpioStrobeSource&) = delete;
  GpioStrobeSource& operator=(const GpioStrobeSource&) = delete;
  int fd() const override;
  void poll(std::uint64_t now_ns, CountSink& sink) override;
  const CountSourceCounters& counters() const override { return decoder_.counters(); }

  static constexpr unsigned batch = 64;  // strobes per poll

 private:
  bool read_counter(std::uint64_t& value) const;
  void release();
  gpiod_chip* chip_ = nullptr;
  gpiod_line* line_ = nullptr;
  int counter_fd_ = -1;
  StrobeDecoder decoder_;
};

}  // namespace gyrochar::hal
