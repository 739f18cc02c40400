#pragma once
// Raw SocketCAN backend of hal::CanBus: non-blocking socket bound to one interface, error frames
// enabled (bus state and bus-off events), SO_RXQ_OVFL for receive-queue drops, CAN FD frames
// accepted where the interface allows. A full TX queue (ENOBUFS/EAGAIN) and a downed interface
// (ENETDOWN) are counted, never waited for. An interface that vanishes is looked for again (once
// a second, by name) and used again when it is back, on the same descriptor.
#include <string>

#include "hal/can_bus.hpp"

namespace gyrochar::hal {

class SocketCan final : public CanBus {
 public:
  /// Opens `interface` (e.g. "can0", "vcan0"). Throws std::runtime_error with the system's reason
  /// when the interface does not exist or the socket cannot be made.
  explicit SocketCan(const std::string& interface);
  ~SocketCan() override;
  SocketCan(const SocketCan&) = delete;
  SocketCan& operator=(const SocketCan&) = delete;

  SendResult send(const CanFrame& frame) override;
  std::optional<CanFrame> receive() override;
  int fd() const override { return fd_; }
  bool set_filters(std::span<const CanFilter> filters) override;
  BusState state() const override { return state_; }
  const CanCounters& counters() const override { return counters_; }

 private:
  std::string name_;
  int fd_ = -1;
  int ifindex_ = 0;  // 0: the interface is gone
  std::uint64_t last_lookup_ms_ = 0;
  BusState state_ = BusState::active;
  CanCounters counters_;
};

}  // namespace gyrochar::hal
