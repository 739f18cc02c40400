// GYROCHAR_ASSERT's hook: this test program overrides gyrochar::assert_failed() (the core's own is
// weak) with one that names the broken invariant and aborts, then breaks invariants the core
// states as preconditions (oracle: each call's documented contract) and expects the override to
// fire with that invariant's expression; calls within the contract must not fire it.
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <cstdio>
#include <cstdlib>

#include "gyrochar/assert.hpp"
#include "gyrochar/batch.hpp"
#include "gyrochar/characterizer.hpp"

namespace gyrochar {
void assert_failed(const char* expression, const char* file, int line) {
  std::fprintf(stderr, "overridden hook: %s (%s:%d)\n", expression, file, line);
  std::abort();
}
}  // namespace gyrochar

namespace {

using namespace gyrochar;

// Death tests need the handler mode and a native run: under qemu-user (the aarch64 preset's
// tests) the forked child hangs or dies without its stderr, so there they skip, saying so; they
// run natively in the host and sanitizer builds.
#define REQUIRE_DEATH_TESTS()                                                                             \
  do {                                                                                                    \
    if (GYROCHAR_ASSERT_MODE != 2) GTEST_SKIP() << "GYROCHAR_ASSERT_MODE is not 'handler' in this build"; \
    if (emulated) GTEST_SKIP() << "death tests do not work under qemu-user; they run natively";           \
  } while (false)
#ifdef GYROCHAR_EMULATED
constexpr bool emulated = true;
#else
constexpr bool emulated = false;
#endif

TEST(AssertHookDeathTest, FiresOnATauIndexOutOfRange) {
  REQUIRE_DEATH_TESTS();
  static StaticCharacterizer<CountArith, 4, 8> c;
  const std::array<std::uint64_t, 4> m_list{1, 2, 4, 8};
  ASSERT_EQ(c.configure({8, 0}, m_list), ConfigureStatus::ok);
  for (int i = 0; i < 100; ++i) c.add_increment(1000 + i % 7);
  EXPECT_EQ(c.result(3).m, 8u);  // within the contract (0 <= i < tau_count()): no assertion
  EXPECT_DEATH(c.result(4), "overridden hook: i < ntaus_ \\(.*characterizer\\.hpp:[0-9]+\\)");
  EXPECT_DEATH(c.noise(4), "overridden hook: i < ntaus_");
}

TEST(AssertHookDeathTest, FiresOnABatchTauThatBreaksItsStrideContract) {
  REQUIRE_DEATH_TESTS();
  // BatchTau: m >= 1, stride a power of two that divides m when it is above 1.
  EXPECT_EQ(BatchTau(12, 4).result().stride, 4u);  // within the contract
  EXPECT_DEATH(BatchTau(0, 1), "overridden hook: m >= 1");
  EXPECT_DEATH(BatchTau(12, 8), "overridden hook: stride == 1 \\|\\| m % stride == 0");
  EXPECT_DEATH(BatchTau(12, 3), "overridden hook: std::has_single_bit\\(stride\\)");
}

TEST(AssertHook, IsAnExpressionInEveryMode) {
  // The macro is usable where an expression is (a comma operand), and a true condition passes.
  int evaluated = 0;
  const int value = (GYROCHAR_ASSERT(++evaluated == 1), 7);
  EXPECT_EQ(value, 7);
  EXPECT_EQ(evaluated, GYROCHAR_ASSERT_MODE == 0 ? 0 : 1);  // mode 0 does not evaluate the condition
}

}  // namespace
