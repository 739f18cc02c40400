#include "hal/fake/fake_can_bus.hpp"

#include <sys/eventfd.h>
#include <unistd.h>

#include <algorithm>
#include <stdexcept>

namespace gyrochar::hal {

std::unique_ptr<FakeCanNode> FakeCanBus::attach(std::size_t rx_capacity) {
  auto node = std::unique_ptr<FakeCanNode>(new FakeCanNode(*this, rx_capacity));
  nodes_.push_back(node.get());
  return node;
}

void FakeCanBus::deliver(const FakeCanNode* from, const CanFrame& frame) {
  ++frames_;
  if (delay_ns_ != 0 && clock_ != nullptr) {
    delayed_.push_back({clock_->now_ns() + delay_ns_, from, frame});
    pump();
    return;
  }
  distribute(from, frame);
}

void FakeCanBus::pump() {
  while (!delayed_.empty() && clock_ != nullptr && delayed_.front().due_ns <= clock_->now_ns()) {
    const Delayed d = delayed_.front();
    delayed_.pop_front();
    distribute(d.from, d.frame);
  }
}

void FakeCanBus::distribute(const FakeCanNode* from, const CanFrame& frame) {
  for (FakeCanNode* n : nodes_) {
    if (n == from) continue;
    if (loss_ > 0 && std::uniform_real_distribution<double>(0, 1)(rng_) < loss_) continue;
    n->push(frame);
  }
}

void FakeCanBus::detach(FakeCanNode* node) {
  nodes_.erase(std::remove(nodes_.begin(), nodes_.end(), node), nodes_.end());
  for (Delayed& d : delayed_)
    if (d.from == node) d.from = nullptr;  // still delivered to everyone else
}

FakeCanNode::FakeCanNode(FakeCanBus& bus, std::size_t rx_capacity) : bus_(bus), capacity_(rx_capacity) {
  event_fd_ = eventfd(0, EFD_NONBLOCK | EFD_SEMAPHORE | EFD_CLOEXEC);
  if (event_fd_ < 0) throw std::runtime_error("eventfd failed");
}

FakeCanNode::~FakeCanNode() {
  bus_.detach(this);
  if (event_fd_ >= 0) close(event_fd_);
}

BusState FakeCanNode::state() const {
  return bus_.down() ? BusState::down : bus_off_ ? BusState::bus_off : BusState::active;
}

void FakeCanNode::set_bus_off(bool off) {
  if (off && !bus_off_) ++counters_.bus_off_events;
  bus_off_ = off;
}

SendResult FakeCanNode::send(const CanFrame& frame) {
  if (bus_.down() || bus_off_) {
    ++counters_.tx_dropped;
    return SendResult::bus_down;
  }
  if (tx_full_) {
    ++counters_.tx_dropped;
    return SendResult::queue_full;
  }
  ++counters_.sent;
  bus_.deliver(this, frame);
  return SendResult::sent;
}

bool FakeCanNode::set_filters(std::span<const CanFilter> filters) {
  filters_.assign(filters.begin(), filters.end());
  filtered_ = true;
  return true;
}

void FakeCanNode::push(const CanFrame& frame) {
  if (filtered_ && !frame.error) {
    bool pass = false;
    for (const CanFilter& f : filters_) pass = pass || (frame.extended && (frame.id & f.mask) == (f.id & f.mask));
    if (!pass) return;
  }
  if (rx_.size() >= capacity_) {
    ++counters_.rx_dropped;
    return;
  }
  rx_.push_back(frame);
  const std::uint64_t one = 1;
  [[maybe_unused]] const auto n = write(event_fd_, &one, sizeof one);
}

std::optional<CanFrame> FakeCanNode::receive() {
  bus_.pump();
  if (rx_.empty()) return std::nullopt;
  std::uint64_t value = 0;
  [[maybe_unused]] const auto n = read(event_fd_, &value, sizeof value);
  CanFrame f = rx_.front();
  rx_.pop_front();
  ++counters_.received;
  return f;
}

}  // namespace gyrochar::hal
