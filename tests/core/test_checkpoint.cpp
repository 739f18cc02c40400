// Checkpoints of the characterizer: save, restore into a fresh one, go on; the result must equal,
// bit for bit, one uninterrupted run with a gap marked at the restart (oracle: the gap semantics,
// whose own exactness test_characterizer checks against brute force), noise sums included.
// Damaged or foreign checkpoints are detected; a state with a valid CRC but a field that breaks an
// invariant is refused, naming the field, and every state real accumulation writes is accepted.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "gyrochar/crc32.hpp"
#include "gyrochar/characterizer.hpp"

namespace gyrochar {

// Where each field of a CountArith checkpoint lies: save() writes the header, the m list, the run
// state, the history and the tau states, each as its bytes (offsets taken from the objects).
template <>
struct CheckpointLayout<CountArith> {
  using C = Characterizer<CountArith>;
  using Run = C::RunState;
  using Tau = C::TauState;
  using Header = CheckpointCodec<CountArith>::Header;
  template <class S, class F>
  static std::size_t offset(const S& s, const F& f) {
    return static_cast<std::size_t>(reinterpret_cast<const char*>(&f) - reinterpret_cast<const char*>(&s));
  }
  static std::size_t identity() {
    const Header h;
    return offset(h, h.identity);
  }
  static std::size_t run(const C& c) { return sizeof(Header) + c.tau_count() * sizeof(std::uint64_t); }
  static std::size_t history(const C& c) { return run(c) + sizeof(Run); }
  static std::size_t tau(const C& c, std::size_t i) {
    return history(c) + c.history_.used() * sizeof(C::Entry) + i * sizeof(Tau);
  }
  static std::size_t entry_bytes() { return sizeof(C::Entry); }
  static std::size_t ring_size(const C& c, unsigned l) { return c.history_.ring_size(l); }
  static unsigned ring_levels(const C& c) { return c.history_.levels(); }
};

namespace {

using Board = StaticCharacterizer<CountArith, 20, 8>;
using Layout = CheckpointLayout<CountArith>;

std::vector<std::uint64_t> octaves(unsigned n) {
  std::vector<std::uint64_t> m;
  for (unsigned k = 0; k < n; ++k) m.push_back(std::uint64_t{1} << k);
  return m;
}

TEST(Crc32, CheckValue) {
  // The CRC-32/ISO-HDLC check value of "123456789" (oracle: the CRC catalogue's check value).
  const char text[] = "123456789";
  EXPECT_EQ(crc32(std::as_bytes(std::span(text, 9))), 0xCBF43926u);
}

TEST(Checkpoint, RestoreThenContinueEqualsRunWithGap) {
  const auto m_list = octaves(20);
  std::mt19937_64 rng(3);
  std::vector<std::int32_t> counts(300000);
  for (auto& c : counts) c = 5000 + static_cast<std::int32_t>(rng() % 101);

  auto reference = std::make_unique<Board>();
  ASSERT_EQ(reference->configure({8, 0}, m_list), ConfigureStatus::ok);
  auto first = std::make_unique<Board>();
  ASSERT_EQ(first->configure({8, 0}, m_list), ConfigureStatus::ok);
  const std::size_t cut = 123457;
  for (std::size_t i = 0; i < cut; ++i) {
    reference->add_increment(counts[i]);
    first->add_increment(counts[i]);
  }
  std::vector<std::byte> bytes(first->checkpoint_size());
  ASSERT_EQ(first->save(bytes), bytes.size());

  auto second = std::make_unique<Board>();
  ASSERT_EQ(second->configure({8, 0}, m_list), ConfigureStatus::ok);
  ASSERT_EQ(second->restore(bytes), RestoreStatus::ok);
  reference->mark_gap();
  for (std::size_t i = cut; i < counts.size(); ++i) {
    reference->add_increment(counts[i]);
    second->add_increment(counts[i]);
  }
  ASSERT_EQ(second->phase_points(), reference->phase_points());
  for (std::size_t i = 0; i < m_list.size(); ++i) {
    const auto a = reference->result(i), b = second->result(i);
    EXPECT_EQ(a.n, b.n) << "m=" << a.m;
    for (std::size_t s = 0; s < sum_kinds; ++s) EXPECT_TRUE(a.sum[s] == b.sum[s]) << "m=" << a.m;
    EXPECT_EQ(reference->noise(i).order(1).r1(), second->noise(i).order(1).r1()) << "m=" << a.m;
    EXPECT_EQ(reference->noise(i).points(), second->noise(i).points()) << "m=" << a.m;
  }
  EXPECT_GT(second->result(15).n[0], 0u);  // m = 2^15: terms on both sides of the cut
}

TEST(Checkpoint, DamageIsDetectedAndNothingChanges) {
  const auto m_list = octaves(10);
  auto board = std::make_unique<Board>();
  ASSERT_EQ(board->configure({8, 0}, m_list), ConfigureStatus::ok);
  for (int i = 0; i < 10000; ++i) board->add_increment(100 + i % 7);
  std::vector<std::byte> bytes(board->checkpoint_size());
  ASSERT_EQ(board->save(bytes), bytes.size());

  auto target = std::make_unique<Board>();
  ASSERT_EQ(target->configure({8, 0}, m_list), ConfigureStatus::ok);
  auto flipped = bytes;
  flipped[flipped.size() / 2] ^= std::byte{0x10};
  EXPECT_EQ(target->restore(flipped), RestoreStatus::corrupted);
  EXPECT_EQ(target->restore(std::span(bytes).first(bytes.size() - 1)), RestoreStatus::truncated);
  EXPECT_EQ(target->restore(std::span(bytes).first(3)), RestoreStatus::truncated);
  auto garbage = bytes;
  garbage[0] = std::byte{'X'};
  EXPECT_EQ(target->restore(garbage), RestoreStatus::not_a_checkpoint);
  EXPECT_EQ(target->phase_points(), 0u);  // nothing restored

  auto other = std::make_unique<Board>();
  ASSERT_EQ(other->configure({16, 0}, m_list), ConfigureStatus::ok);
  EXPECT_EQ(other->restore(bytes), RestoreStatus::config_mismatch);
  ASSERT_EQ(other->configure({8, 1234}, m_list), ConfigureStatus::ok);  // another caller tag
  EXPECT_EQ(other->restore(bytes), RestoreStatus::config_mismatch);
  const auto fewer = octaves(9);
  ASSERT_EQ(other->configure({8, 0}, fewer), ConfigureStatus::ok);
  EXPECT_EQ(other->restore(bytes), RestoreStatus::config_mismatch);
  std::vector<std::byte> small(bytes.size() - 1);
  EXPECT_EQ(board->save(small), 0u);
}

// A real checkpoint: 10000 counts (with a gap) under S = 8 and 20 octave taus.
std::vector<std::byte> real_checkpoint(Board& board, std::uint32_t identity = 0) {
  EXPECT_EQ(board.configure({8, 0, identity}, octaves(20)), ConfigureStatus::ok);
  for (int i = 0; i < 10000; ++i) {
    if (i == 4000) board.mark_gap();
    board.add_increment(100 + i % 7);
  }
  std::vector<std::byte> bytes(board.checkpoint_size());
  EXPECT_EQ(board.save(bytes), bytes.size());
  return bytes;
}

// The CRC recomputed after an edit: the state is what the test made it, the CRC holds.
void reseal(std::vector<std::byte>& bytes) {
  const std::uint32_t crc = crc32(std::span(bytes).first(bytes.size() - 4));
  std::memcpy(bytes.data() + bytes.size() - 4, &crc, 4);
}

template <class T>
T read_at(const std::vector<std::byte>& bytes, std::size_t at) {
  T v{};
  std::memcpy(&v, bytes.data() + at, sizeof v);
  return v;
}
template <class T>
void write_at(std::vector<std::byte>& bytes, std::size_t at, T v) {
  std::memcpy(bytes.data() + at, &v, sizeof v);
}

// Restores `bytes` (resealed) into a fresh characterizer of the same configuration: the status, the
// field it names, and that nothing was taken on failure.
struct Outcome {
  RestoreStatus status;
  std::string field;
};
Outcome restore_into_fresh(std::vector<std::byte> bytes) {
  reseal(bytes);
  auto target = std::make_unique<Board>();
  EXPECT_EQ(target->configure({8, 0}, octaves(20)), ConfigureStatus::ok);
  const RestoreStatus s = target->restore(bytes);
  if (s != RestoreStatus::ok) {
    EXPECT_EQ(target->phase_points(), 0u);
  }
  return {s, target->restore_field()};
}

TEST(CheckpointFields, EachBrokenInvariantIsRefusedNamingTheField) {
  auto board = std::make_unique<Board>();
  const std::vector<std::byte> good = real_checkpoint(*board);
  ASSERT_EQ(restore_into_fresh(good).status, RestoreStatus::ok);  // the CRC helper changes nothing
  const Layout::Run r0{};
  const std::size_t run = Layout::run(*board);
  const std::uint64_t e = read_at<std::uint64_t>(good, run + Layout::offset(r0, r0.next_e));
  ASSERT_EQ(e, 10002u);  // oracle: 10000 counts in two segments, one extra point at each start
  struct Case {
    const char* what;
    std::size_t at;
    std::uint64_t value;
    unsigned bytes;     // 1, 4 or 8
    const char* field;  // the prefix restore_field() must start with
  };
  const auto run_at = [&](const auto& member) { return run + Layout::offset(r0, member); };
  const std::size_t tau3 = Layout::tau(*board, 3);    // m = 8 (S = 8: level 0, stride 1)
  const std::size_t tau19 = Layout::tau(*board, 19);  // m = 2^19: no terms yet in 10^4 points
  const Layout::Tau t0{};
  const auto tau_at = [&](std::size_t tau, const auto& member) { return tau + Layout::offset(t0, member); };
  const std::uint64_t ones = ~std::uint64_t{0};
  const std::size_t ring0 = Layout::ring_size(*board, 0);
  const Case cases[] = {
      // The reproducers: sample count 0xFF..., phase points 0xFF... (the spin), far beyond 2^62.
      {"increments all ones", run_at(r0.increments), ones, 8, "increments"},
      {"next_e all ones", run_at(r0.next_e), ones, 8, "next_e"},
      {"next_e 2^62 + 1", run_at(r0.next_e), (std::uint64_t{1} << 62) + 1, 8, "next_e"},
      {"next_e one more than the points", run_at(r0.next_e), e + 1, 8, "increments"},
      {"increments above the points", run_at(r0.increments), e + 1, 8, "increments"},
      // 10000 increments in two segments make 10002 points: 9999 would need 3 segments, 2 gaps.
      {"increments too few for the gaps", run_at(r0.increments), e - 3, 8, "increments"},
      {"segment_start beyond next_e", run_at(r0.segment_start), e + 1, 8, "segment_start"},
      {"steady_from off by one", run_at(r0.steady_from), read_at<std::uint64_t>(good, run_at(r0.steady_from)) + 1, 8,
       "steady_from"},
      {"x not the last point's", run_at(r0.x), read_at<std::uint64_t>(good, run_at(r0.x)) + 1, 8, "x"},
      {"p not the last point's", run_at(r0.p.lo), read_at<std::uint64_t>(good, run_at(r0.p.lo)) ^ 1, 8, "p"},
      {"line_points (floating only)", run_at(r0.line_points), 1, 8, "line"},
      {"first_increment (floating only)", run_at(r0.first_increment), 1, 4, "line"},
      {"phase_overflow not a bool", run_at(r0.phase_overflow), 2, 1, "phase_overflow"},
      {"head 0 outside ring 0", run_at(r0.head[0]), ring0, 4, "head"},
      {"head 0 off by one", run_at(r0.head[0]), (e % ring0), 4, "head"},
      {"head of an unused ring", run_at(r0.head[Layout::ring_levels(*board)]), 1, 4, "head"},
      {"tau m", tau_at(tau3, t0.result.m), 9, 8, "tau"},
      {"tau stride", tau_at(tau3, t0.result.stride), 2, 8, "tau"},
      {"tau level", tau_at(tau3, t0.level), 1, 1, "tau"},
      {"tau ring_of beyond the rings", tau_at(tau3, t0.ring_of[2]), 200, 1, "tau"},
      {"tau back beyond the ring", tau_at(tau3, t0.back[0]), 0xFFFFFFFF, 4, "tau"},
      {"countdown 0", tau_at(tau3, t0.countdown), 0, 8, "countdown"},
      {"countdown huge (no more decimation)", tau_at(tau3, t0.countdown), ones, 8, "countdown"},
      {"decimated_count 4", tau_at(tau3, t0.decimated_count), 4, 1, "decimated_count"},
      {"sum_overflow not a bool", tau_at(tau3, t0.result.sum_overflow), 0xFF, 1, "sum_overflow"},
      {"sum_overflow true (kept in sticky)", tau_at(tau3, t0.result.sum_overflow), 1, 1, "sum_overflow"},
      {"n above the points", tau_at(tau3, t0.result.n[0]), e + 1, 8, "n"},
      {"decimated n above points / m", tau_at(tau3, t0.result.n[3]), e / 8 + 1, 8, "n"},
      {"a sum without terms", tau_at(tau19, t0.result.sum[0].lo), 1, 8, "sum"},
      {"a sum's high word not in sticky", tau_at(tau3, t0.result.sum[1].hi), 1, 8, "sticky"},
      {"out_of_range above two per point", tau_at(tau3, t0.result.out_of_range), 2 * e + 1, 4, "out_of_range"},
  };
  // Points without samples: each segment is opened by a sample, however many gaps are counted
  // (fuzz_checkpoint found a state of points, no sample and about 2^64 gaps accepted).
  {
    auto bytes = good;
    write_at(bytes, run_at(r0.gaps), std::uint64_t{1} << 62);
    EXPECT_EQ(restore_into_fresh(bytes).status, RestoreStatus::ok);  // at the bound
    write_at(bytes, run_at(r0.increments), e / 2 - 1);
    EXPECT_EQ(restore_into_fresh(bytes).field, "increments (samples)");
    write_at(bytes, run_at(r0.gaps), ones);  // would wrap to 0 at the restart's gap
    EXPECT_EQ(restore_into_fresh(bytes).field, "gaps");
  }
  for (const Case& c : cases) {
    auto bytes = good;
    if (c.bytes == 1) write_at(bytes, c.at, static_cast<std::uint8_t>(c.value));
    if (c.bytes == 4) write_at(bytes, c.at, static_cast<std::uint32_t>(c.value));
    if (c.bytes == 8) write_at(bytes, c.at, c.value);
    ASSERT_NE(bytes, good) << c.what;  // the case changes something
    const Outcome o = restore_into_fresh(bytes);
    EXPECT_EQ(o.status, RestoreStatus::invalid_state) << c.what;
    EXPECT_EQ(o.field.rfind(c.field, 0), 0u) << c.what << ": " << o.field;
  }
}

TEST(CheckpointFields, NoiseSumsOutOfOrderAreRefused) {
  // IntegerNoiseIdAccumulator ends with n_ (5 counts) and have_ (one byte, padded to 8): x86-64
  // and aarch64 lay it out alike.
  static_assert(sizeof(IntegerNoiseIdAccumulator) == 368);
  auto board = std::make_unique<Board>();
  const std::vector<std::byte> good = real_checkpoint(*board);
  const Layout::Tau t0{};
  const std::size_t noise = Layout::tau(*board, 3) + Layout::offset(t0, t0.noise);
  const std::size_t have = noise + 360, n = noise + 320;
  ASSERT_EQ(read_at<std::uint64_t>(good, n), 10001u / 8 + 1);  // oracle: x[0], x[8], ... x[10000] of 10002 points
  auto bytes = good;
  write_at<std::uint8_t>(bytes, have, 6);  // at most 5 points of a segment are counted
  EXPECT_EQ(restore_into_fresh(bytes).field, "noise (lag-1 sums)");
  bytes = good;
  write_at<std::uint64_t>(bytes, n + 8, 10001u / 8 + 2);  // more first differences than values
  EXPECT_EQ(restore_into_fresh(bytes).field, "noise (lag-1 sums)");
  bytes = good;
  write_at<std::uint64_t>(bytes, n, ~std::uint64_t{0});  // more values than the points allow
  EXPECT_EQ(restore_into_fresh(bytes).field, "noise (lag-1 sums)");
}

TEST(CheckpointFields, AnotherIdentityIsRefusedAndReported) {
  auto board = std::make_unique<Board>();
  const std::vector<std::byte> bytes = real_checkpoint(*board, 0x18001);
  ASSERT_EQ(read_at<std::uint32_t>(bytes, Layout::identity()), 0x18001u);
  auto other = std::make_unique<Board>();
  ASSERT_EQ(other->configure({8, 0, 0x18101}, octaves(20)), ConfigureStatus::ok);
  EXPECT_EQ(other->restore(bytes), RestoreStatus::other_identity);
  EXPECT_EQ(other->checkpoint_identity(), 0x18001u);
  EXPECT_EQ(other->phase_points(), 0u);
  ASSERT_EQ(other->configure({8, 0, 0x18001}, octaves(20)), ConfigureStatus::ok);
  EXPECT_EQ(other->restore(bytes), RestoreStatus::ok);
}

TEST(CheckpointFields, VersionFourIsRefused) {
  auto board = std::make_unique<Board>();
  std::vector<std::byte> bytes = real_checkpoint(*board);
  write_at<std::uint16_t>(bytes, 4, 4);  // the format before the identity (oracle: Header.version at 4)
  auto other = std::make_unique<Board>();
  ASSERT_EQ(other->configure({8, 0}, octaves(20)), ConfigureStatus::ok);
  EXPECT_EQ(other->restore(bytes), RestoreStatus::wrong_version);
}

// Every state accumulation writes passes the checks: saved after each of many irregular steps
// (random counts, runs of extreme counts, gaps, single points and blocks, restarts, at S = 2, 8 and
// 64) restores.
TEST(CheckpointFields, EveryRealStateIsAccepted) {
  std::mt19937_64 rng(19);
  for (const std::uint32_t s : {2u, 8u, 64u}) {
    using Big = StaticCharacterizer<CountArith, 20, 64>;
    auto c = std::make_unique<Big>();
    auto copy = std::make_unique<Big>();
    ASSERT_EQ(c->configure({s, 7}, octaves(20)), ConfigureStatus::ok);
    ASSERT_EQ(copy->configure({s, 7}, octaves(20)), ConfigureStatus::ok);
    std::vector<std::byte> bytes(c->checkpoint_size());
    std::vector<std::int32_t> block;
    for (int step = 0; step < 400; ++step) {
      ASSERT_EQ(c->save(bytes), bytes.size());
      const RestoreStatus status = copy->restore(bytes);
      ASSERT_EQ(status, RestoreStatus::ok) << "S=" << s << " step " << step << ": " << copy->restore_field();
      const unsigned kind = static_cast<unsigned>(rng() % 8);
      const std::size_t n = kind < 4 ? rng() % 7 : rng() % 3000;
      block.resize(n);
      for (auto& v : block) {
        v = kind == 7 ? (rng() % 2 ? INT32_MAX : INT32_MIN)  // terms beyond the block kernel's proof
                      : static_cast<std::int32_t>(rng() % 2001) - 1000;
      }
      if (kind == 0) c->mark_gap();
      if (kind % 2) {
        c->add_increments(std::span<const std::int32_t>(block));
      } else {
        for (const auto v : block) c->add_increment(v);
      }
      if (kind == 6 && step % 50 == 0) c->restart();
    }
    EXPECT_GT(c->phase_points(), 100000u) << "S=" << s;
  }
}

// Floating phase data (the analyzer's arithmetic) checkpoints under the same checks: real states of
// phase points and of frequency increments restore; a state whose prefix sum is NaN does not.
TEST(CheckpointFields, FloatingStatesAreCheckedToo) {
  using Phase = StaticCharacterizer<FloatArith, 12, 8>;
  const auto m_list = octaves(12);
  for (const bool increments : {false, true}) {
    auto c = std::make_unique<Phase>();
    ASSERT_EQ(c->configure({8, 0}, m_list), ConfigureStatus::ok);
    for (int i = 0; i < 5000; ++i) {
      if (i == 3000) c->mark_gap();
      if (increments) {
        c->add_increment(1e-9 * (i % 13));
      } else {
        c->add_phase_point(1e-6 * i + 1e-9 * (i % 17));
      }
    }
    std::vector<std::byte> bytes(c->checkpoint_size());
    ASSERT_EQ(c->save(bytes), bytes.size());
    auto d = std::make_unique<Phase>();
    ASSERT_EQ(d->configure({8, 0}, m_list), ConfigureStatus::ok);
    EXPECT_EQ(d->restore(bytes), RestoreStatus::ok) << d->restore_field();
    // RunState::p.hi lies 40 bytes into the run state (five counters before it).
    const double nan = std::nan("");
    std::memcpy(bytes.data() + 40 + 12 * 8 + 40, &nan, sizeof nan);
    reseal(bytes);
    EXPECT_EQ(d->restore(bytes), RestoreStatus::invalid_state);
    EXPECT_EQ(std::string(d->restore_field()), "p (prefix sum)");
  }
}

}  // namespace
}  // namespace gyrochar
