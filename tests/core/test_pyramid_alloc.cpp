// The accumulator never touches the heap: global operator new is replaced by a counting one and
// a million counts, snapshots included, must allocate nothing (oracle: the count, exactly 0).
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>

#include "gyrochar/pyramid.hpp"

namespace {
std::atomic<std::size_t> allocations{0};
}

// The replacement pairs malloc with free on purpose; GCC cannot see that both are replaced.
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"

void* operator new(std::size_t size) {
  ++allocations;
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

namespace gyrochar {
namespace {

TEST(PyramidAllocation, AccumulationAndSnapshotsAllocateNothing) {
  static StaticPyramid<CountArith, 40, 8> pyramid;
  std::array<std::uint64_t, 40> m_list{};
  for (unsigned k = 0; k < 40; ++k) m_list[k] = std::uint64_t{1} << k;
  ASSERT_EQ(pyramid.configure({8, false}, m_list), PyramidStatus::ok);
  static std::array<Pyramid<CountArith>::Result, 40> snapshot;
  const std::size_t before = allocations.load();
  for (std::int64_t i = 0; i < 1000000; ++i) {
    pyramid.add_increment(1000 + (i * 7919) % 13);
    if (i % 1000 == 0) pyramid.snapshot(snapshot);
    if (i == 500000) pyramid.mark_gap();
  }
  EXPECT_EQ(allocations.load() - before, 0u);
  EXPECT_GT(pyramid.result(10).n[0], 0u);  // it did accumulate
}

TEST(PyramidAllocation, StateSizeForFortyOctavesStrideEight) {
  // Budget from the issue: at most 16 KiB for 40 levels and S = 8 (oracle: sizeof).
  EXPECT_LE((sizeof(StaticPyramid<CountArith, 40, 8>)), 16u * 1024u);
  std::printf("sizeof(StaticPyramid<CountArith, 40, 8>) = %zu bytes\n", sizeof(StaticPyramid<CountArith, 40, 8>));
}

}  // namespace
}  // namespace gyrochar
