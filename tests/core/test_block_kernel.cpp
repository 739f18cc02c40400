// The block kernel: whatever the blocks the points arrive in, the sums are bit-identical to the
// definitions evaluated by brute force (oracle: exact 128-bit integers, tests/oracle/brute_force.hpp)
// and to feeding the points one at a time with a read-out after each (which processes every point
// alone); the noise identification sums, in floating point, are bit-identical between the two.
// The 64-bit partial sums are checked against exact 128-bit sums around the bound that proves them.
#include <gtest/gtest.h>

#include <algorithm>
#include <climits>
#include <cstdint>
#include <random>
#include <vector>

#include "gyrochar/block_kernel.hpp"
#include "gyrochar/characterizer.hpp"
#include "core/heap_characterizer.hpp"
#include "oracle/brute_force.hpp"

namespace gyrochar {
namespace {

using oracle::brute_force;
using oracle::Exact;
using oracle::u128;

std::vector<std::uint64_t> taus_for(std::uint32_t s) {
  // Every m <= S (level 0: the kernel) up to 8, then octaves and one sub-octave tau per level.
  std::vector<std::uint64_t> m;
  for (std::uint64_t v = 1; v <= 8 && v <= s; ++v) m.push_back(v);
  for (std::uint64_t v = 16; v <= 4 * std::uint64_t{s} && v <= 1024; v *= 2) {
    if (v > s && 3 * v / 4 > m.back() && (3 * v / 4) % (v / s) == 0) m.push_back(3 * v / 4);
    if (v > m.back()) m.push_back(v);
  }
  return m;
}

// Feeds `counts` as segments separated by gaps, in blocks of random length (0: one point at a
// time with a read-out after each).
void feed(Characterizer<CountArith>& c, const std::vector<std::vector<std::int32_t>>& segments, std::mt19937_64* blocks) {
  for (std::size_t seg = 0; seg < segments.size(); ++seg) {
    if (seg > 0) c.mark_gap();
    const auto& v = segments[seg];
    for (std::size_t k = 0; k < v.size();) {
      if (blocks == nullptr) {
        c.add_increment(v[k++]);
        (void)c.result(0);
        continue;
      }
      const std::size_t len = std::min<std::size_t>(v.size() - k, (*blocks)() % 300);
      c.add_increments(std::span<const std::int32_t>(v.data() + k, len));
      k += len;
    }
  }
}

class BlockKernelProperty : public ::testing::TestWithParam<std::uint32_t> {};

TEST_P(BlockKernelProperty, AnyBlocksEqualOnePointAtATimeAndBruteForce) {
  const std::uint32_t s = GetParam();
  const auto m_list = taus_for(s);
  std::mt19937_64 rng(77 + s);
  for (int trial = 0; trial < 3; ++trial) {
    // Small noise on a large rate (64-bit partial sums), then swings near the int32 limits (terms
    // beyond 2^31: the 128-bit path), in three segments.
    std::vector<std::vector<std::int32_t>> segments;
    for (int seg = 0; seg < 3; ++seg) {
      std::vector<std::int32_t> v(500 + rng() % 2500);
      for (auto& c : v) {
        const bool wide = trial == 2 || (trial == 1 && seg == 1);
        c = wide ? static_cast<std::int32_t>(rng() % 4294967295u - 2147483647u)
                 : 1000000 + static_cast<std::int32_t>(rng() % 64);
      }
      segments.push_back(v);
    }
    Heap blocks(s, m_list), single(s, m_list);
    feed(blocks.c, segments, &rng);
    feed(single.c, segments, nullptr);
    for (std::size_t i = 0; i < m_list.size(); ++i) {
      const std::uint64_t m = m_list[i];
      Exact want, decimated;
      std::uint64_t start = 0;
      for (const auto& v : segments) {
        std::vector<std::int64_t> x{0};
        for (const std::int32_t c : v) x.push_back(x.back() + c);
        want += brute_force(x, m, blocks.c.result(i).stride, false, start);
        decimated += brute_force(x, m, 1, true, start);
        start += x.size();
      }
      const auto got = blocks.c.result(i), one = single.c.result(i);
      for (std::size_t k = 0; k < 3; ++k) {
        EXPECT_EQ(got.n[k], want.n[k]) << "S=" << s << " m=" << m << " stat " << k;
        EXPECT_TRUE(to_u128(got.sum[k]) == want.sum[k]) << "S=" << s << " m=" << m << " stat " << k;
      }
      const auto avar = static_cast<std::size_t>(SumKind::avar_nonoverlapped);
      const auto hvar = static_cast<std::size_t>(SumKind::hvar_nonoverlapped);
      EXPECT_TRUE(to_u128(got.sum[avar]) == decimated.sum[0] && got.n[avar] == decimated.n[0]) << "m=" << m;
      EXPECT_TRUE(to_u128(got.sum[hvar]) == decimated.sum[2] && got.n[hvar] == decimated.n[2]) << "m=" << m;
      for (std::size_t k = 0; k < sum_kinds; ++k) {
        EXPECT_TRUE(got.sum[k] == one.sum[k] && got.n[k] == one.n[k]) << "m=" << m << " kind " << k;
      }
      EXPECT_EQ(got.out_of_range, 0u);
      EXPECT_FALSE(got.sum_overflow);
      for (int d = 0; d < 4; ++d) {
        const Lag1Sums a = blocks.c.noise(i).order(d), b = single.c.noise(i).order(d);
        EXPECT_TRUE(a.n == b.n && a.pairs == b.pairs && a.sum == b.sum && a.sum_sq == b.sum_sq && a.sum_lag == b.sum_lag &&
                    a.sum_left == b.sum_left && a.sum_right == b.sum_right)
            << "m=" << m << " order " << d;
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(StrideFactors, BlockKernelProperty, ::testing::Values(2u, 4u, 8u, 16u, 64u, 256u));

// Taus of levels 4 to 12 at S = 4: the kernel leaves them, and the blocks enter the history in
// runs between the points at which they run. Sums equal one point at a time and brute force.
TEST(BlockKernel, HistoryEnteredInRunsEqualsOnePointAtATime) {
  const std::vector<std::uint64_t> m_list = {1, 2, 3, 4, 8, 64, 96, 128, 256, 1024, 4096, 12288, 16384};
  std::mt19937_64 rng(5);
  std::vector<std::vector<std::int32_t>> segments;
  for (const std::size_t n : {70000u, 1000u, 90000u}) {
    std::vector<std::int32_t> v(n);
    for (auto& c : v) c = 3600 + static_cast<std::int32_t>(rng() % 100);
    segments.push_back(v);
  }
  Heap blocks(4, m_list), single(4, m_list);
  feed(blocks.c, segments, &rng);
  feed(single.c, segments, nullptr);
  for (std::size_t i = 0; i < m_list.size(); ++i) {
    Exact want;
    std::uint64_t start = 0;
    for (const auto& v : segments) {
      std::vector<std::int64_t> x{0};
      for (const std::int32_t c : v) x.push_back(x.back() + c);
      want += brute_force(x, m_list[i], blocks.c.result(i).stride, false, start);
      start += x.size();
    }
    const auto got = blocks.c.result(i), one = single.c.result(i);
    for (std::size_t k = 0; k < 3; ++k) {
      EXPECT_EQ(got.n[k], want.n[k]) << "m=" << m_list[i] << " stat " << k;
      EXPECT_TRUE(to_u128(got.sum[k]) == want.sum[k]) << "m=" << m_list[i] << " stat " << k;
    }
    for (std::size_t k = 0; k < sum_kinds; ++k) {
      EXPECT_TRUE(got.sum[k] == one.sum[k] && got.n[k] == one.n[k]) << "m=" << m_list[i] << " kind " << k;
    }
  }
}

TEST(BlockKernel, PartialSumsAreExactOnlyWhenTheBoundProvesIt) {
  // n = 64 terms of magnitude v: the 64-bit partial sum of squares equals the exact sum (oracle:
  // 128-bit products) whenever squares_exact() says so; at 2^29 = v the bound (2*30 + 7 > 64)
  // refuses, and at 2^29 + 1 the partial sum has indeed wrapped.
  for (const std::int64_t v : {std::int64_t{1}, std::int64_t{12345}, (std::int64_t{1} << 28) - 1, std::int64_t{1} << 29,
                               (std::int64_t{1} << 29) + 1, std::int64_t{1} << 40}) {
    constexpr std::size_t n = 64;
    std::vector<std::int64_t> x0(n), x1(n, 0), x2(n, 0), x3(n, 0), a(n), h(n), t(n);
    std::vector<std::uint64_t> p(n, 0);
    for (std::size_t j = 0; j < n; ++j) x0[j] = j % 2 ? v : -v;  // AVAR term x0 - 2 x1 + x2 = +-v
    const BlockTerms terms = block_terms(n, x0.data(), x1.data(), x2.data(), x3.data(), p.data(), p.data(), p.data(),
                                         p.data(), a.data(), h.data(), t.data());
    u128 exact = 0;
    for (std::size_t j = 0; j < n; ++j) {
      EXPECT_EQ(a[j], x0[j]);
      exact += static_cast<u128>(static_cast<__int128>(a[j]) * a[j]);
    }
    const bool proved = squares_exact(terms.avar, n);
    EXPECT_EQ(proved, v < (std::int64_t{1} << 29)) << v;
    if (proved) {
      EXPECT_TRUE(u128{terms.avar.sum} == exact) << v;
    }
    if (v == (std::int64_t{1} << 29) + 1) {
      EXPECT_FALSE(u128{terms.avar.sum} == exact);
    }
  }
}

TEST(BlockKernel, ProvedKernelsEqualTheTermsThemselves) {
  // Phase points of a steady rate with increments spread over D = 2^12: every lag-m term is within
  // the proved bounds (|t| <= m^2 D < 2^27 for m <= 8). The kernels without bounds (SIMD where the
  // target has it, every block length 0..300 so the scalar tail runs too) give the terms and the
  // sums of their squares computed here one by one from the definitions (x and P; oracle: 128-bit
  // sums of squares), the running-sum one from the first MVAR term alone.
  std::mt19937_64 rng(5);
  for (std::size_t m : {std::size_t{1}, std::size_t{3}, std::size_t{8}}) {
    for (std::size_t n = 0; n <= 300; ++n) {
      const std::size_t back = 3 * m;
      std::vector<std::int64_t> x{std::int64_t{1} << 50};
      std::vector<std::uint64_t> p{static_cast<std::uint64_t>(x[0])};
      for (std::size_t k = 1; k < back + n; ++k) {
        x.push_back(x.back() + 1000000 + static_cast<std::int64_t>(rng() % 4096));
        p.push_back(p.back() + static_cast<std::uint64_t>(x.back()));
      }
      std::vector<std::int64_t> a(n + 1), h(n + 1), a2(n + 1), h2(n + 1);
      u128 want_a = 0, want_h = 0, want_t = 0;
      std::uint64_t t_first = 0;
      for (std::size_t j = 0; j < n; ++j) {
        const std::size_t e = back + j;
        const __int128 av = static_cast<__int128>(x[e]) - 2 * static_cast<__int128>(x[e - m]) + x[e - 2 * m];
        const __int128 hv = av - (static_cast<__int128>(x[e - m]) - 2 * static_cast<__int128>(x[e - 2 * m]) + x[e - 3 * m]);
        const auto tv = static_cast<std::int64_t>(p[e] - 3 * p[e - m] + 3 * p[e - 2 * m] - p[e - 3 * m]);
        if (j == 0) t_first = static_cast<std::uint64_t>(tv);
        want_a += static_cast<u128>(av * av);
        want_h += static_cast<u128>(hv * hv);
        want_t += static_cast<u128>(static_cast<__int128>(tv) * tv);
      }
      const auto at = [&](std::size_t age) { return x.data() + back - age; };
      const auto pt = [&](std::size_t age) { return p.data() + back - age; };
      const ProvedSums direct = proved_terms(n, at(0), at(m), at(2 * m), at(3 * m), pt(0), pt(m), pt(2 * m), pt(3 * m),
                                             a.data(), h.data());
      const ProvedSums running = proved_running_terms(n, at(0), at(m), at(2 * m), at(3 * m), t_first, a2.data(), h2.data());
      for (const ProvedSums& s : {direct, running}) {
        EXPECT_TRUE(u128{s.avar} == want_a && u128{s.hvar} == want_h && u128{s.mvar} == want_t) << "m=" << m << " n=" << n;
      }
      for (std::size_t j = 0; j < n; ++j) {
        EXPECT_EQ(a[j], x[back + j] - 2 * x[back + j - m] + x[back + j - 2 * m]);
        EXPECT_EQ(h[j], a[j] - (x[back + j - m] - 2 * x[back + j - 2 * m] + x[back + j - 3 * m]));
        EXPECT_EQ(a2[j], a[j]);
        EXPECT_EQ(h2[j], h[j]);
      }
    }
  }
}

TEST(BlockKernel, DifferenceRangeIsTheIncrementRangeFromTheLowWords) {
  // Phase points far from zero (near 2^62) whose increments span the whole int32 range: the range
  // taken from the low 32-bit words equals the smallest and largest increment (oracle: the
  // increments themselves), and folds into the range already held.
  std::mt19937_64 rng(11);
  for (const std::size_t n : {std::size_t{1}, std::size_t{2}, std::size_t{7}, std::size_t{256}}) {
    std::vector<std::int64_t> x{std::int64_t{1} << 62};
    std::int32_t want_lo = 5, want_hi = 5;  // the range held before
    for (std::size_t k = 1; k < n; ++k) {
      const auto c = k == 1 ? INT32_MIN : k == 2 ? INT32_MAX : static_cast<std::int32_t>(rng());
      x.push_back(x.back() + c);
      want_lo = std::min(want_lo, c);
      want_hi = std::max(want_hi, c);
    }
    std::int32_t lo = 5, hi = 5;
    difference_range(x.data(), n, lo, hi);
    EXPECT_EQ(lo, want_lo) << n;
    EXPECT_EQ(hi, want_hi) << n;
  }
}

TEST(BlockKernel, LevelZeroTausBeyondTwoToTheFifteenAreCheckedByTheIncrementRange) {
  // Fully overlapped (S = m = 2^17, level 0). Counts within a narrow range keep every term
  // provably in int64: the kernel forms them all, equal to brute force. Swings of +-(2^31-1) over
  // m counts make MVAR terms of about 2 m^2 2^31 = 2^66: the checked path counts them out of range
  // instead (oracle: that magnitude bound), while AVAR terms (2^50) stay exact.
  const std::uint64_t m = std::uint64_t{1} << 17;
  const std::vector<std::uint64_t> m_list{1, m};
  {
    Heap h(1u << 17, m_list);
    std::vector<std::int64_t> x{0};
    std::mt19937_64 rng(3);
    for (std::uint64_t k = 0; k < 4 * m; ++k) {
      const auto c = static_cast<std::int32_t>(rng() % 1000);
      h.c.add_increment(c);
      x.push_back(x.back() + c);
    }
    const Exact want = brute_force(x, m, 1);
    for (std::size_t k = 0; k < 3; ++k)
      EXPECT_TRUE(to_u128(h.c.result(1).sum[k]) == want.sum[k] && h.c.result(1).n[k] == want.n[k]);
  }
  Heap h(1u << 17, m_list);
  const std::int32_t v = 2147483647;
  for (int block = 0; block < 4; ++block)
    for (std::uint64_t k = 0; k < m; ++k) h.c.add_increment(block % 2 == 0 ? v : -v);
  EXPECT_GT(h.c.result(1).out_of_range, 0u);
  EXPECT_EQ(h.c.result(1).n[1] + h.c.result(1).out_of_range, 4 * m + 1 - 3 * m + 1);
  EXPECT_EQ(h.c.result(1).n[0], 4 * m + 1 - 2 * m);
}

}  // namespace
}  // namespace gyrochar
