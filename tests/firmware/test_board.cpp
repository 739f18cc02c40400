// The board program's loop on the HAL fakes (in-process CAN bus, scripted count source, virtual
// clock): no heap allocation after start-up, quadrature edges end up as the exact counts, a downed
// bus costs reports but no samples, and checkpoints resume or are refused with the reason.
// Oracles: a characterizer fed the same counts directly (same exact integer sums), the fake bus's own
// counters, and the checkpoint format's checks.
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <cstdlib>
#include <fstream>
#include <new>
#include <random>
#include <vector>

#include "board.hpp"
#include "hal/fake/fake_can_bus.hpp"
#include "hal/fake/fake_clock.hpp"
#include "hal/fake/fake_count_source.hpp"

// Counts every heap allocation of this test program while armed. The replacement pairs malloc
// with free on purpose; GCC cannot see that both are replaced.
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
namespace {
std::atomic<bool> armed{false};
std::atomic<std::uint64_t> allocations{0};
}  // namespace
void* operator new(std::size_t n) {
  if (armed) ++allocations;
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

namespace gyrochar::firmware {
namespace {

constexpr std::uint64_t ms = 1000000;

Config test_config() {
  Config c;
  c.node = 7;
  c.source = SourceKind::quadrature;  // any GPIO kind: the fake source stands in for it
  c.tau0_s = 0.001;
  c.stride_factor = 8;
  c.octaves = 20;
  c.report_period_s = 0.1;
  return c;
}

std::vector<std::int64_t> test_counts(std::size_t n, std::uint64_t seed = 3) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 3.0);
  std::vector<std::int64_t> c(n);
  for (auto& v : c) v = 5 + static_cast<std::int64_t>(std::lround(noise(rng)));
  return c;
}

// The board, its fakes, and a loop that advances the virtual clock one millisecond at a time.
struct Rig {
  hal::FakeCanBus bus;
  std::unique_ptr<hal::FakeCanNode> board_node = bus.attach();
  hal::FakeClock clock;
  hal::FakeTimer timer{clock};
  hal::FakeCountSource source;
  std::unique_ptr<Board> board;
  explicit Rig(const Config& c) { board = std::make_unique<Board>(c, BoardIo{*board_node, &source, clock, timer}); }
  void run_for(std::uint64_t ns) {
    for (std::uint64_t t = 0; t < ns; t += ms) {
      clock.advance(ms);
      timer.update();
      ASSERT_TRUE(board->run_once(0));
    }
  }
};

void expect_same_sums(const Characterizer<CountArith>& a, const Characterizer<CountArith>& b) {
  ASSERT_EQ(a.tau_count(), b.tau_count());
  for (std::size_t i = 0; i < a.tau_count(); ++i) {
    const auto ra = a.result(i), rb = b.result(i);
    for (std::size_t k = 0; k < sum_kinds; ++k) {
      EXPECT_EQ(ra.n[k], rb.n[k]) << "tau " << i << " stat " << k;
      EXPECT_TRUE(ra.sum[k] == rb.sum[k]) << "tau " << i << " stat " << k;
    }
  }
}

// A quadrature encoder's lines: each step is one edge, forwards (AB: 00 10 11 01 00) or back.
struct Encoder {
  int state = 0;
  void step(hal::FakeCountSource& source, std::uint64_t t_ns, bool forward) {
    static constexpr bool ab[4][2] = {{false, false}, {true, false}, {true, true}, {false, true}};
    const int next = (state + (forward ? 1 : 3)) % 4;
    const bool a_changes = ab[state][0] != ab[next][0];
    source.push_edge(t_ns, a_changes ? hal::QuadratureLine::a : hal::QuadratureLine::b, ab[next][a_changes ? 0 : 1]);
    state = next;
  }
};

// The oracle: a characterizer fed the counts directly.
std::unique_ptr<BoardCharacterizer> direct(const Config& c, const std::vector<std::int64_t>& counts) {
  ReportSettings s;
  s.tau0_s = c.tau0_s;
  s.stride_factor = c.stride_factor;
  s.octaves = c.octaves;
  auto e = std::make_unique<BoardCharacterizer>();
  EXPECT_TRUE(configure(*e, s));
  for (const auto v : counts) e->add_increment(static_cast<std::int32_t>(v));
  return e;
}

TEST(Board, NoHeapAllocationAfterStartUp) {
  Config c = test_config();
  c.checkpoint_path = ::testing::TempDir() + std::to_string(getpid()) + "_alloc.ckpt";
  c.checkpoint_period_s = 0.5;
  Rig rig(c);
  const auto counts = test_counts(5000);
  rig.source.script_counts(rig.clock.now_ns(), ms, counts.data(), counts.size());
  rig.board->resume();
  armed = true;
  rig.run_for(5000 * ms);  // 5000 samples, 50 reports, 10 checkpoints
  armed = false;
  EXPECT_EQ(allocations.load(), 0u);
  EXPECT_EQ(rig.board->characterizer().increments(), counts.size());
  EXPECT_GT(rig.bus.frames_on_bus(), 50u * 40u);
  std::remove(c.checkpoint_path.c_str());
}

TEST(Board, QuadratureEdgesBecomeTheExactCounts) {
  const Config c = test_config();
  Rig rig(c);
  hal::QuadratureSettings q;
  q.start_ns = rig.clock.now_ns();
  q.tau0_ns = ms;
  rig.source.use_quadrature(q);
  // |count| edges spread over each interval, in the count's sense.
  const auto counts = test_counts(3000);
  Encoder encoder;
  for (std::size_t k = 0; k < counts.size(); ++k) {
    const std::int64_t n = std::llabs(counts[k]);
    for (std::int64_t e = 0; e < n; ++e)
      encoder.step(rig.source, q.start_ns + k * ms + static_cast<std::uint64_t>((e + 1) * ms / (n + 1)), counts[k] > 0);
  }
  rig.run_for(3000 * ms);
  EXPECT_EQ(rig.board->characterizer().increments(), counts.size());
  expect_same_sums(rig.board->characterizer(), *direct(c, counts));
  EXPECT_EQ(rig.board->faults().lost_edges, 0u);
}

TEST(Board, ADownedBusCostsReportsButNoSamples) {
  const Config c = test_config();
  Rig rig(c);
  auto listener = rig.bus.attach();
  const auto counts = test_counts(3000);
  rig.source.script_counts(rig.clock.now_ns(), ms, counts.data(), counts.size());
  rig.run_for(1000 * ms);
  std::size_t received = 0;
  while (listener->receive()) ++received;
  EXPECT_GT(received, 0u);
  rig.bus.set_down(true);
  rig.run_for(1000 * ms);
  EXPECT_EQ(listener->receive(), std::nullopt) << "nothing crosses a downed bus";
  EXPECT_GT(rig.board_node->counters().tx_dropped, 0u);
  rig.bus.set_down(false);
  rig.run_for(1000 * ms);
  received = 0;
  while (listener->receive()) ++received;
  EXPECT_GT(received, 0u) << "reports resume";
  EXPECT_EQ(rig.board->characterizer().increments(), counts.size());
  expect_same_sums(rig.board->characterizer(), *direct(c, counts));
}

TEST(Board, MeasuredBusLoadOfOneNodeIsUnderThreePercentOf500kbits) {
  // 32 taus, one report per second, for 60 s of virtual time: every frame that crossed the bus is
  // counted at its worst-case length on the wire (maximum stuffing). Oracle: the 3 % budget of the
  // protocol specification (docs/protocol.md) and the codec's own worst-case figure.
  Config c = test_config();
  c.octaves = 32;
  c.report_period_s = 1.0;
  Rig rig(c);
  auto listener = rig.bus.attach(1 << 16);
  const auto counts = test_counts(60000);
  rig.source.script_counts(rig.clock.now_ns(), ms, counts.data(), counts.size());
  double bits = 0;
  for (int s = 0; s < 60; ++s) {
    rig.run_for(1000 * ms);
    while (auto f = listener->receive()) bits += protocol::worst_case_frame_bits(f->len);
  }
  const double load = bits / 60.0 / 500000.0;
  std::printf("measured bus load, 32 taus at 1 report/s: %.3f %% of 500 kbit/s\n", 100 * load);
  EXPECT_LE(load, 0.03);
  EXPECT_LE(load, protocol::worst_case_bus_load(32, 1.0, 500000.0) * (1 + 1e-9));
  EXPECT_GT(load, 0.5 * protocol::worst_case_bus_load(32, 1.0, 500000.0)) << "reports were sent";
}

TEST(Board, FullTxQueueAndBusOffAreCountedReportedAndSurvived) {
  // Oracles: the fake node's own counters, and the board's status frames as decoded by the codec.
  const Config c = test_config();
  Rig rig(c);
  auto listener = rig.bus.attach(1 << 16);
  const auto counts = test_counts(4000);
  rig.source.script_counts(rig.clock.now_ns(), ms, counts.data(), counts.size());
  rig.run_for(1000 * ms);
  rig.board_node->set_tx_full(true);
  rig.run_for(500 * ms);
  rig.board_node->set_tx_full(false);
  rig.board_node->set_bus_off(true);
  rig.run_for(500 * ms);
  rig.board_node->set_bus_off(false);
  while (listener->receive()) {
  }
  rig.run_for(2000 * ms);
  EXPECT_EQ(rig.board->characterizer().increments(), counts.size()) << "accumulation never stopped";
  expect_same_sums(rig.board->characterizer(), *direct(c, counts));
  std::optional<protocol::StatusFaultsMsg> faults;
  while (auto f = listener->receive()) {
    const protocol::Decoded d = protocol::decode(*f);
    if (const auto* m = std::get_if<protocol::StatusFaultsMsg>(&d.message)) faults = *m;
  }
  ASSERT_TRUE(faults.has_value()) << "reports resumed after the faults";
  EXPECT_EQ(faults->tx_dropped_frames, rig.board_node->counters().tx_dropped);
  EXPECT_GT(faults->tx_dropped_frames, 0u);
  EXPECT_EQ(faults->bus_off_events, 1u);
}

TEST(Board, EdgeStormsAreWorkedOffInBoundedPassesAndClockJumpsAreOneGap) {
  // Oracles: the fake source's batch bound (256 edges per pass) and the quadrature decoder's stall
  // rule (a silence over max_silent_intervals is one gap sample).
  const Config c = test_config();
  Rig rig(c);
  hal::QuadratureSettings q;
  q.start_ns = rig.clock.now_ns();
  q.tau0_ns = ms;
  q.max_silent_intervals = 1000;
  rig.source.use_quadrature(q);
  // 100000 edges inside the first millisecond: 25000 forward cycles.
  Encoder encoder;
  for (int e = 0; e < 100000; ++e) encoder.step(rig.source, q.start_ns + static_cast<std::uint64_t>(e) * 5, true);
  rig.clock.advance(2 * ms);
  rig.timer.update();
  ASSERT_TRUE(rig.board->run_once(0));
  EXPECT_EQ(rig.source.counters().edges, hal::FakeCountSource::batch) << "one pass, one batch";
  int passes = 1;
  while (rig.source.counters().edges < 100000 && passes < 10000) {
    ASSERT_TRUE(rig.board->run_once(0));
    ++passes;
  }
  EXPECT_EQ(passes, (100000 + 255) / 256);
  EXPECT_EQ(rig.board->characterizer().increments(), 1u) << "the storm's interval, closed once its backlog is read";
  EXPECT_EQ(rig.source.counters().late_edges, 0u);
  // The clock jumps a day ahead: one pass, one gap, nothing bridged.
  rig.clock.advance(86400ull * 1000 * ms);
  rig.timer.update();
  ASSERT_TRUE(rig.board->run_once(0));
  EXPECT_EQ(rig.board->faults().sample_gaps, 1u);
  EXPECT_EQ(rig.board->characterizer().increments(), 1u);
}

TEST(Board, CounterFramesFromItsElectronicsOnlyBecomeTheExactCounts) {
  // CounterInput frames from node 0x80 carry the accumulated count; another electronics (0x81)
  // shares the bus and must be filtered out. Oracle: an estimator fed the counts directly.
  Config c = test_config();
  c.source = SourceKind::can_counter;
  c.counter_node = 0x80;
  hal::FakeCanBus bus;
  auto board_node = bus.attach(), electronics = bus.attach();
  hal::FakeClock clock;
  hal::FakeTimer timer(clock);
  Board board(c, BoardIo{*board_node, nullptr, clock, timer});
  const auto counts = test_counts(2000);
  std::uint32_t accumulated = 0;
  for (std::size_t k = 0; k <= counts.size(); ++k) {
    if (k > 0) accumulated += static_cast<std::uint32_t>(counts[k - 1]);
    for (const std::uint8_t node : {std::uint8_t{0x80}, std::uint8_t{0x81}}) {
      protocol::CounterInputMsg m;
      m.count = node == 0x80 ? accumulated : 7 * static_cast<std::uint32_t>(k);
      m.seq = static_cast<std::uint8_t>(k);
      CanFrame f;
      ASSERT_EQ(protocol::encode(m, node, f), protocol::ProtocolError::none);
      electronics->send(f);
    }
    clock.advance(ms);
    timer.update();
    ASSERT_TRUE(board.run_once(0));
  }
  EXPECT_EQ(board.characterizer().increments(), counts.size());
  expect_same_sums(board.characterizer(), *direct(c, counts));
  EXPECT_EQ(board_node->counters().received, counts.size() + 1) << "the other node's frames never reached the board";
}

class BoardCheckpoint : public ::testing::Test {
 protected:
  Config c = test_config();
  std::vector<std::int64_t> counts = test_counts(2000);
  void SetUp() override {
    c.checkpoint_path = ::testing::TempDir() + std::to_string(getpid()) + "_board.ckpt";
    std::remove(c.checkpoint_path.c_str());
    std::remove((c.checkpoint_path + ".bad").c_str());
    Rig rig(c);
    rig.source.script_counts(rig.clock.now_ns(), ms, counts.data(), counts.size());
    rig.run_for(2000 * ms);
    ASSERT_EQ(rig.board->checkpoint(), 0);
  }
  void TearDown() override {
    std::remove(c.checkpoint_path.c_str());
    std::remove((c.checkpoint_path + ".bad").c_str());
  }
  std::string bytes() {
    std::ifstream f(c.checkpoint_path, std::ios::binary);
    return {std::istreambuf_iterator<char>(f), {}};
  }
  void rewrite(const std::string& b) { std::ofstream(c.checkpoint_path, std::ios::binary) << b; }
  bool exists(const std::string& p) { return access(p.c_str(), F_OK) == 0; }
};

TEST_F(BoardCheckpoint, ResumesWithTheSameSums) {
  Rig rig(c);
  const std::string said = rig.board->resume();
  EXPECT_NE(said.find("resumed"), std::string::npos) << said;
  EXPECT_EQ(rig.board->characterizer().increments(), counts.size());
  expect_same_sums(rig.board->characterizer(), *direct(c, counts));
}

TEST_F(BoardCheckpoint, ACorruptedFileIsReportedAndKeptAside) {
  std::string b = bytes();
  b[b.size() / 2] = static_cast<char>(b[b.size() / 2] ^ 0x10);
  rewrite(b);
  Rig rig(c);
  const std::string said = rig.board->resume();
  EXPECT_NE(said.find("CRC"), std::string::npos) << said;
  EXPECT_NE(said.find("starting fresh"), std::string::npos) << said;
  EXPECT_EQ(rig.board->characterizer().increments(), 0u);
  EXPECT_TRUE(exists(c.checkpoint_path + ".bad"));
  EXPECT_FALSE(exists(c.checkpoint_path));
}

TEST_F(BoardCheckpoint, ATruncatedFileIsReportedAndKeptAside) {
  for (const std::size_t keep : {std::size_t{3}, bytes().size() - 1}) {
    const std::string b = bytes();
    rewrite(b.substr(0, keep));
    Rig rig(c);
    const std::string said = rig.board->resume();
    EXPECT_NE(said.find("truncated"), std::string::npos) << keep << ": " << said;
    EXPECT_EQ(rig.board->characterizer().increments(), 0u);
    EXPECT_TRUE(exists(c.checkpoint_path + ".bad"));
    std::rename((c.checkpoint_path + ".bad").c_str(), c.checkpoint_path.c_str());
    rewrite(b);
  }
}

TEST_F(BoardCheckpoint, AnotherConfigurationIsNotResumed) {
  Config other = c;
  other.tau0_s = 0.002;
  Rig rig(other);
  const std::string said = rig.board->resume();
  EXPECT_NE(said.find("another configuration"), std::string::npos) << said;
  EXPECT_EQ(rig.board->characterizer().increments(), 0u);
  // Garbage is not a checkpoint.
  rewrite(std::string(4096, 'x'));
  Rig rig2(c);
  EXPECT_NE(rig2.board->resume().find("not a gyrochard checkpoint"), std::string::npos);
}

}  // namespace
}  // namespace gyrochar::firmware
