#pragma once
// An in-process CAN bus for host simulation and tests: any number of nodes attach to one bus and
// each sees the others' frames (not its own, like a CAN controller without loopback). Loss and
// bus-down are injected deterministically (seeded), and per node a full TX queue or bus-off (the
// controller's own state, as after too many errors); each node has a bounded receive queue whose
// overflows are counted, and an eventfd that is readable while frames wait, so the same epoll
// loop runs on it as on SocketCAN. A delay on a (virtual) clock can be injected too.
#include <cstdint>
#include <deque>
#include <memory>
#include <random>
#include <vector>

#include "hal/can_bus.hpp"
#include "hal/clock.hpp"

namespace gyrochar::hal {

class FakeCanNode;

class FakeCanBus {
 public:
  explicit FakeCanBus(std::uint64_t seed = 1) : rng_(seed) {}
  /// A new node on this bus; the bus must outlive it.
  std::unique_ptr<FakeCanNode> attach(std::size_t rx_capacity = 4096);
  /// Drops each frame with this probability (0..1).
  void set_loss(double probability) { loss_ = probability; }
  /// Delays every frame by `delay_ns` on `clock` (0: none): it reaches the other nodes once the
  /// clock has passed its send time + delay, when any node next sends, receives or pump() runs.
  void set_delay(const Clock& clock, std::uint64_t delay_ns) {
    clock_ = &clock;
    delay_ns_ = delay_ns;
  }
  /// Delivers the delayed frames that are due.
  void pump();
  /// Takes the bus down (sends fail with bus_down) or brings it back.
  void set_down(bool down) { down_ = down; }
  bool down() const { return down_; }
  std::uint64_t frames_on_bus() const { return frames_; }

 private:
  friend class FakeCanNode;
  void deliver(const FakeCanNode* from, const CanFrame& frame);
  void distribute(const FakeCanNode* from, const CanFrame& frame);
  void detach(FakeCanNode* node);
  struct Delayed {
    std::uint64_t due_ns;
    const FakeCanNode* from;
    CanFrame frame;
  };
  std::deque<Delayed> delayed_;
  const Clock* clock_ = nullptr;
  std::uint64_t delay_ns_ = 0;
  std::vector<FakeCanNode*> nodes_;
  std::mt19937_64 rng_;
  double loss_ = 0.0;
  bool down_ = false;
  std::uint64_t frames_ = 0;
};

class FakeCanNode final : public CanBus {
 public:
  ~FakeCanNode() override;
  SendResult send(const CanFrame& frame) override;
  std::optional<CanFrame> receive() override;
  int fd() const override { return event_fd_; }
  bool set_filters(std::span<const CanFilter> filters) override;
  BusState state() const override;
  /// This node's TX queue refuses frames (queue_full, counted) while `full`.
  void set_tx_full(bool full) { tx_full_ = full; }
  /// This node's controller goes bus-off (sends fail, one bus-off event counted) or recovers.
  void set_bus_off(bool off);
  const CanCounters& counters() const override { return counters_; }

 private:
  friend class FakeCanBus;
  FakeCanNode(FakeCanBus& bus, std::size_t rx_capacity);
  void push(const CanFrame& frame);
  FakeCanBus& bus_;
  std::size_t capacity_;
  std::deque<CanFrame> rx_;
  CanCounters counters_;
  int event_fd_ = -1;
  bool tx_full_ = false, bus_off_ = false;
  bool filtered_ = false;
  std::vector<CanFilter> filters_;
};

}  // namespace gyrochar::hal
