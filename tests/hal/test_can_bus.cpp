// The CAN HAL: the in-process bus (delivery, loss injection, bus down, bounded receive queue) and
// the SocketCAN backend's error path on this machine, whose kernel has no CAN (the QEMU bench runs
// it on a real one). Oracles: counts of what the test sent, dropped and queued.
#include <gtest/gtest.h>
#include <poll.h>

#include <stdexcept>

#include "hal/fake/fake_can_bus.hpp"
#include "hal/fake/fake_clock.hpp"
#include "hal/linux/socketcan.hpp"

namespace gyrochar::hal {
namespace {

CanFrame frame(std::uint32_t id) {
  CanFrame f;
  f.id = id;
  f.extended = true;
  f.len = 8;
  f.data[0] = static_cast<std::uint8_t>(id);
  return f;
}

bool readable(int fd) {
  pollfd p{fd, POLLIN, 0};
  return poll(&p, 1, 0) == 1;
}

TEST(FakeCanBus, EveryOtherNodeReceivesInOrder) {
  FakeCanBus bus;
  auto a = bus.attach(), b = bus.attach(), c = bus.attach();
  EXPECT_FALSE(readable(b->fd()));
  for (std::uint32_t i = 0; i < 5; ++i) EXPECT_EQ(a->send(frame(0x100 + i)), SendResult::sent);
  EXPECT_TRUE(readable(b->fd()));
  for (auto* n : {b.get(), c.get()}) {
    for (std::uint32_t i = 0; i < 5; ++i) {
      const auto f = n->receive();
      ASSERT_TRUE(f.has_value());
      EXPECT_EQ(f->id, 0x100 + i);
    }
    EXPECT_FALSE(n->receive().has_value());
    EXPECT_FALSE(readable(n->fd()));
  }
  EXPECT_FALSE(a->receive().has_value());  // no loopback to the sender
  EXPECT_EQ(a->counters().sent, 5u);
  EXPECT_EQ(b->counters().received, 5u);
}

TEST(FakeCanBus, LossDownAndOverflowAreCounted) {
  FakeCanBus bus(42);
  auto a = bus.attach(), b = bus.attach(16);
  bus.set_loss(0.25);
  for (int i = 0; i < 10000; ++i) a->send(frame(1));
  std::uint64_t got = 0;
  while (b->receive()) ++got;
  // 16 fit in the queue; the rest of what was not lost overflowed and was counted.
  EXPECT_EQ(got, 16u);
  EXPECT_NEAR(static_cast<double>(b->counters().rx_dropped + got), 7500.0, 200.0);  // binomial(10000, 0.75)
  bus.set_loss(0);
  bus.set_down(true);
  EXPECT_EQ(a->send(frame(2)), SendResult::bus_down);
  EXPECT_EQ(a->state(), BusState::down);
  EXPECT_EQ(a->counters().tx_dropped, 1u);
  bus.set_down(false);
  EXPECT_EQ(a->send(frame(3)), SendResult::sent);
  EXPECT_EQ(b->receive()->id, 3u);
}

TEST(SocketCan, MissingInterfaceGivesAClearError) {
  try {
    SocketCan can("nosuchcan0");
    FAIL() << "opened a nonexistent interface";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    // Without CAN in the kernel the socket itself fails; with it, the interface lookup does.
    EXPECT_TRUE(what.find("nosuchcan0") != std::string::npos || what.find("CAN socket") != std::string::npos) << what;
  }
  EXPECT_THROW(SocketCan(""), std::runtime_error);
}

}  // namespace
}  // namespace gyrochar::hal

namespace gyrochar::hal {
namespace {

TEST(FakeCanBus, FiltersPassMatchingExtendedFramesAndErrorFrames) {
  // Oracle: the filter rule (frame.id & mask) == (id & mask), extended data frames only.
  FakeCanBus bus;
  auto a = bus.attach(), b = bus.attach();
  const CanFilter only_0x80[] = {{0x0CFF5080, 0x1FFFFFFF}};
  ASSERT_TRUE(b->set_filters(only_0x80));
  CanFrame pass;
  pass.id = 0x0CFF5080;
  pass.extended = true;
  CanFrame other = pass;
  other.id = 0x0CFF5081;
  CanFrame standard = pass;
  standard.extended = false;
  standard.id = 0x80;
  CanFrame error;
  error.error = true;
  error.id = 0x40;
  for (const CanFrame& f : {pass, other, standard, error}) a->send(f);
  auto first = b->receive(), second = b->receive();
  ASSERT_TRUE(first && second);
  EXPECT_EQ(first->id, 0x0CFF5080u);
  EXPECT_TRUE(second->error);
  EXPECT_FALSE(b->receive());
  ASSERT_TRUE(b->set_filters({}));  // nothing but error frames
  a->send(pass);
  EXPECT_FALSE(b->receive());
}

}  // namespace
}  // namespace gyrochar::hal

namespace gyrochar::hal {
namespace {

TEST(FakeCanBus, DelayedFramesArriveInOrderOnceTheirTimeHasCome) {
  // Oracle: the injected delay on the virtual clock (5 ms).
  FakeClock clock;
  FakeCanBus bus;
  bus.set_delay(clock, 5000000);
  auto a = bus.attach(), b = bus.attach();
  CanFrame f;
  f.extended = true;
  for (std::uint32_t id : {1u, 2u}) {
    f.id = id;
    a->send(f);
    clock.advance(1000000);
  }
  clock.advance(2999999);  // 4.999999 ms after the first
  EXPECT_FALSE(b->receive().has_value());
  clock.advance(1);
  auto first = b->receive();
  ASSERT_TRUE(first.has_value());
  EXPECT_EQ(first->id, 1u);
  EXPECT_FALSE(b->receive().has_value()) << "the second is due 1 ms later";
  clock.advance(1000000);
  bus.pump();
  EXPECT_TRUE(readable(b->fd()));
  EXPECT_EQ(b->receive()->id, 2u);
}

}  // namespace
}  // namespace gyrochar::hal
