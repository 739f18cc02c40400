#pragma once
// CAN bus interface of the HAL: non-blocking send and receive of classic (and FD) frames with a
// pollable file descriptor, and counters for everything that can go wrong. Backends:
// hal/linux/socketcan.hpp (raw SocketCAN) and hal/fake/fake_can_bus.hpp (in-process bus).
#include <cstdint>
#include <optional>
#include <span>

#include "gyrochar/wire/can_frame.hpp"

namespace gyrochar::hal {

enum class BusState : std::uint8_t { active, warning, passive, bus_off, down };

struct CanCounters {
  std::uint64_t sent = 0;
  std::uint64_t received = 0;
  std::uint64_t tx_dropped = 0;  // could not be queued (TX queue full: ENOBUFS / EAGAIN)
  std::uint64_t rx_dropped = 0;  // lost in the socket's receive queue (SO_RXQ_OVFL)
  std::uint64_t error_frames = 0;
  std::uint64_t bus_off_events = 0;
  std::uint8_t tx_error_counter = 0;  // the controller's TEC and REC, as its last error frame said
  std::uint8_t rx_error_counter = 0;
};

/// A receive filter on 29-bit identifiers: a frame passes when (frame.id & mask) == (id & mask).
struct CanFilter {
  std::uint32_t id = 0;
  std::uint32_t mask = 0;
};

enum class SendResult : std::uint8_t { sent, queue_full, bus_down };

class CanBus {
 public:
  virtual ~CanBus() = default;
  /// Queues one frame without blocking. queue_full and bus_down are counted, never retried.
  virtual SendResult send(const CanFrame& frame) = 0;
  /// The next received frame, if any, without blocking; error frames come through with
  /// frame.error set and update the state and counters.
  virtual std::optional<CanFrame> receive() = 0;
  /// A file descriptor that becomes readable when a frame is waiting (for epoll).
  virtual int fd() const = 0;
  /// Receives only extended data frames that pass one of `filters` (none: no data frames at all);
  /// error frames always come through. Returns false when the backend refused the filters.
  virtual bool set_filters(std::span<const CanFilter> filters) = 0;
  virtual BusState state() const = 0;
  virtual const CanCounters& counters() const = 0;
};

}  // namespace gyrochar::hal
