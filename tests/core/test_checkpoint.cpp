// Checkpoints of the characterizer: save, restore into a fresh one, go on; the result must equal,
// bit for bit, one uninterrupted run with a gap marked at the restart (oracle: the gap semantics,
// whose own exactness test_characterizer checks against brute force), noise sums included.
// Damaged or foreign checkpoints are detected.
#include <gtest/gtest.h>

#include <memory>
#include <random>
#include <vector>

#include "gyrochar/crc32.hpp"
#include "gyrochar/characterizer.hpp"

namespace gyrochar {
namespace {

using Board = StaticCharacterizer<CountArith, 20, 8>;

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

}  // namespace
}  // namespace gyrochar
