// Two-word 128-bit arithmetic against the compiler's native __int128 (oracle) on random and
// boundary values, including the portable multiply used on 32-bit targets.
#include <gtest/gtest.h>

#include <cstdint>
#include <limits>
#include <random>

#include "gyrochar/wide.hpp"

namespace gyrochar {
namespace {

using i128 = __int128;
using u128 = unsigned __int128;
u128 as_u128(UInt128 v) { return (u128{v.hi} << 64) | v.lo; }
u128 as_u128(Int128 v) { return (u128{v.hi} << 64) | v.lo; }

TEST(Wide, MultiplyAndSquareMatchNative) {
  std::mt19937_64 rng(1);
  std::vector<std::uint64_t> values{0, 1, 2, 0xffffffffu, 0x100000000u, ~std::uint64_t{0}, std::uint64_t{1} << 63};
  for (int i = 0; i < 10000; ++i) values.push_back(rng() >> (rng() % 64));
  for (std::uint64_t a : values) {
    for (int j = 0; j < 8; ++j) {
      const std::uint64_t b = values[rng() % values.size()];
      EXPECT_TRUE(as_u128(mul_wide_portable(a, b)) == u128{a} * b);
      EXPECT_TRUE(as_u128(mul_wide(a, b)) == u128{a} * b);
    }
    const auto s = static_cast<std::int64_t>(a);
    EXPECT_TRUE(as_u128(square(s)) == static_cast<u128>(i128{s} * s));
  }
  const std::int64_t min = std::numeric_limits<std::int64_t>::min();
  EXPECT_TRUE(as_u128(square(min)) == u128{1} << 126);
}

TEST(Wide, SignedAddSubNarrowMatchNative) {
  std::mt19937_64 rng(2);
  for (int i = 0; i < 100000; ++i) {
    const auto a = static_cast<std::int64_t>(rng()), b = static_cast<std::int64_t>(rng());
    const Int128 x = widen(a) + widen(b) + widen(a);
    const Int128 y = widen(a) - widen(b) - widen(b);
    EXPECT_TRUE(as_u128(x) == static_cast<u128>(i128{a} + b + a));
    EXPECT_TRUE(as_u128(y) == static_cast<u128>(i128{a} - b - b));
    std::int64_t out = 0;
    const i128 exact = i128{a} + b;
    const bool fits = exact >= std::numeric_limits<std::int64_t>::min() && exact <= std::numeric_limits<std::int64_t>::max();
    EXPECT_EQ(narrow(widen(a) + widen(b), out), fits);
    if (fits) {
      EXPECT_EQ(out, static_cast<std::int64_t>(exact));
    }
  }
}

TEST(Wide, AdditionReportsWrapPast2To128) {
  UInt128 acc{~std::uint64_t{0}, ~std::uint64_t{0} - 1};
  EXPECT_FALSE(add_overflows(acc, UInt128{0, 1}));  // reaches exactly 2^128 - 1
  EXPECT_TRUE(acc == (UInt128{~std::uint64_t{0}, ~std::uint64_t{0}}));
  EXPECT_TRUE(add_overflows(acc, UInt128{1, 0}));  // 2^128 wraps to 0
  EXPECT_TRUE(acc == (UInt128{0, 0}));
  std::mt19937_64 rng(3);
  for (int i = 0; i < 100000; ++i) {
    UInt128 a{rng(), rng() >> (rng() % 64)}, b{rng(), rng() >> (rng() % 64)};
    const u128 exact = as_u128(a) + as_u128(b);
    const bool wraps = exact < as_u128(a);
    EXPECT_EQ(add_overflows(a, b), wraps);
    EXPECT_TRUE(as_u128(a) == exact);
  }
}

TEST(Wide, ToDoubleWithinOneUlp) {
  // Bound: two roundings, relative error <= 2^-52 (oracle: long double conversion of native u128).
  std::mt19937_64 rng(4);
  for (int i = 0; i < 100000; ++i) {
    const UInt128 v{rng(), rng() >> (rng() % 64)};
    const long double exact = static_cast<long double>(as_u128(v));
    const long double got = to_double(v);
    EXPECT_LE(std::fabs(got - exact), exact * 0x1p-52L);
  }
}

}  // namespace
}  // namespace gyrochar
