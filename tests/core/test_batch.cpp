// The batch path: for random streams with gaps, every tau's sums, term counts, out-of-range
// counts, overflow flag and noise identification sums equal, bit for bit, those of the
// characterizer fed the same counts (which tests/core/test_block_kernel.cpp checks against brute
// force), and the overlapping sums equal the brute-force definitions (oracle: exact 128-bit
// integers, tests/oracle/brute_force.hpp); residuals held as int32 and as int64 alike.
#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <vector>

#include "gyrochar/batch.hpp"
#include "gyrochar/characterizer.hpp"
#include "core/heap_characterizer.hpp"
#include "oracle/brute_force.hpp"

namespace gyrochar {
namespace {

using oracle::brute_force;
using oracle::Exact;
using oracle::u128;

// The phase points of each segment as the characterizer forms them from counts (a segment starts
// at the phase reached so far), held as residuals from the line through its first point with
// the slope of its first count.
struct Held {
  std::vector<std::vector<std::int64_t>> x;  // the phase points themselves (for brute force)
  std::vector<std::vector<std::int64_t>> r64;
  std::vector<std::vector<std::int32_t>> r32;  // empty where a residual leaves int32
  std::vector<PhaseSegment<std::int64_t>> seg64;
  std::vector<PhaseSegment<std::int32_t>> seg32;
};

Held hold(const std::vector<std::vector<std::int32_t>>& counts) {
  Held h;
  std::int64_t x = 0;
  for (const auto& c : counts) {
    std::vector<std::int64_t> points;  // a segment without counts has no point
    if (!c.empty()) points.push_back(x);
    for (const std::int32_t v : c) points.push_back(x += v);
    const std::int64_t slope = c.empty() ? 0 : c[0];
    std::vector<std::int64_t> r;
    bool narrow = true;
    for (std::size_t j = 0; j < points.size(); ++j) {
      r.push_back(points[j] - points[0] - slope * static_cast<std::int64_t>(j));
      narrow = narrow && r.back() >= INT32_MIN && r.back() <= INT32_MAX;
    }
    h.x.push_back(points);
    h.r64.push_back(r);
    h.r32.emplace_back(narrow ? std::vector<std::int32_t>(r.begin(), r.end()) : std::vector<std::int32_t>{});
  }
  std::uint64_t e = 0;
  for (std::size_t k = 0; k < counts.size(); ++k) {
    const std::uint64_t spread = increment_spread<std::int64_t>(h.r64[k]);
    const std::int64_t slope = counts[k].empty() ? 0 : counts[k][0];
    const std::int64_t x0 = h.x[k].empty() ? 0 : h.x[k][0];
    h.seg64.push_back({h.r64[k], x0, slope, e, spread});
    h.seg32.push_back({h.r32[k], x0, slope, e, spread});
    e += h.x[k].size();
  }
  return h;
}

void feed(Characterizer<CountArith>& c, const std::vector<std::vector<std::int32_t>>& counts) {
  for (std::size_t k = 0; k < counts.size(); ++k) {
    if (k > 0) c.mark_gap();
    c.add_increments(std::span<const std::int32_t>(counts[k]));
  }
}

void expect_same(const Characterizer<CountArith>& c, std::size_t i, const BatchTau& b, const char* what) {
  const auto want = c.result(i), got = b.result();
  const std::uint64_t m = want.m;
  EXPECT_EQ(got.m, m);
  EXPECT_EQ(got.stride, want.stride) << what << " m=" << m;
  for (std::size_t k = 0; k < sum_kinds; ++k) {
    EXPECT_TRUE(got.sum[k] == want.sum[k]) << what << " m=" << m << " kind " << k;
    EXPECT_EQ(got.n[k], want.n[k]) << what << " m=" << m << " kind " << k;
  }
  EXPECT_EQ(got.out_of_range, want.out_of_range) << what << " m=" << m;
  EXPECT_EQ(got.sum_overflow, want.sum_overflow) << what << " m=" << m;
  for (int d = 0; d < 4; ++d) {
    const Lag1Sums p = c.noise(i).order(d), q = b.noise().order(d);
    EXPECT_TRUE(p.n == q.n && p.pairs == q.pairs && p.shift == q.shift && p.sum == q.sum && p.sum_sq == q.sum_sq &&
                p.sum_lag == q.sum_lag && p.sum_left == q.sum_left && p.sum_right == q.sum_right)
        << what << " m=" << m << " order " << d;
  }
}

// Every m the pyramid forms up to 3S/2 or 40 (level 0 and the first strided levels), then octaves.
std::vector<std::uint64_t> taus_for(std::uint32_t s, std::uint64_t longest) {
  std::vector<std::uint64_t> m;
  for (std::uint64_t v = 1; v <= longest; ++v)
    if (v % stride_of(v, s) == 0 && (v <= 40 || v <= 3 * std::uint64_t{s} / 2 || std::has_single_bit(v))) m.push_back(v);
  return m;
}

class BatchProperty : public ::testing::TestWithParam<std::uint32_t> {};

TEST_P(BatchProperty, EqualsTheCharacterizerBitForBitAndBruteForce) {
  const std::uint32_t s = GetParam();
  std::mt19937_64 rng(1234 + s);
  for (int trial = 0; trial < 4; ++trial) {
    // 0: a gyro's counts (large rate, small noise: 64-bit partial sums, int32 residuals);
    // 1: one segment of swings near the int32 limits (terms beyond 2^27: 128-bit squares);
    // 2: a rate ramp (residuals beyond int32 in the long segment); 3: negative rates, short segments.
    std::vector<std::vector<std::int32_t>> counts;
    const int segments = trial == 3 ? 6 : 3;
    for (int seg = 0; seg < segments; ++seg) {
      std::vector<std::int32_t> v(trial == 3 ? rng() % 40 : 300 + rng() % 1500);
      for (std::size_t j = 0; j < v.size(); ++j) {
        std::int64_t c = 3600 + static_cast<std::int64_t>(rng() % 9) - 4;
        if (trial == 1 && seg == 1) c = static_cast<std::int64_t>(rng() % 4294967295u) - 2147483647;
        if (trial == 2) c = 1000 + static_cast<std::int64_t>(j) * 40000 + static_cast<std::int64_t>(rng() % 100);
        if (trial == 3) c = -7 - static_cast<std::int64_t>(rng() % 20);
        v[j] = static_cast<std::int32_t>(c);
      }
      counts.push_back(v);
    }
    const auto m_list = taus_for(s, 700);
    Heap heap(s, m_list);
    feed(heap.c, counts);
    const Held held = hold(counts);
    for (std::size_t i = 0; i < m_list.size(); ++i) {
      const std::uint64_t m = m_list[i], stride = stride_of(m, s);
      BatchTau b64(m, stride), b32(m, stride);
      bool narrow = true;
      for (std::size_t k = 0; k < counts.size(); ++k) {
        b64.add_segment(held.seg64[k]);
        narrow = narrow && held.r32[k].size() == held.r64[k].size();
        if (narrow) b32.add_segment(held.seg32[k]);
      }
      expect_same(heap.c, i, b64, "int64");
      if (narrow) {
        expect_same(heap.c, i, b32, "int32");
      }
      EXPECT_TRUE(trial == 2 ? !narrow : trial == 0 ? narrow : true);
      if (i % 7 != 0) continue;  // brute force on some taus
      Exact want;
      for (std::size_t k = 0; k < counts.size(); ++k)
        want += brute_force(held.x[k], m, stride, false, held.seg64[k].first_e);
      for (std::size_t k = 0; k < 3; ++k) {
        EXPECT_TRUE(to_u128(b64.result().sum[k]) == want.sum[k]) << "m=" << m << " stat " << k;
        EXPECT_EQ(b64.result().n[k], want.n[k]) << "m=" << m << " stat " << k;
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(StrideFactors, BatchProperty, ::testing::Values(2u, 8u, 64u, 1024u));

TEST(Batch, LargeTermsOfInt32ResidualsAreSummedTermByTermAsTheCharacterizerDoes) {
  // Counts of +-2^29 in random runs keep the residuals within int32 but make terms of 2^30 and
  // more, beyond what a chunk's 64-bit partial sum holds exactly: those chunks are summed term by
  // term in 128 bits (the x86-64 host's AVX2 chunks as well as the portable ones), and the
  // sums equal the characterizer's. Segment lengths not multiples of 4 leave tails of every size.
  std::mt19937_64 rng(77);
  std::vector<std::vector<std::int32_t>> counts(4);
  for (std::size_t k = 0; k < counts.size(); ++k) {
    std::int64_t r = 0;
    for (std::size_t j = 0; j < 1001 + 2 * k; ++j) {
      const std::int32_t c = (rng() % 2 == 0 && r < (std::int64_t{1} << 30)) || r <= -(std::int64_t{1} << 30) ? (1 << 29)
                                                                                                              : -(1 << 29);
      r += c;
      counts[k].push_back(j == 0 ? 0 : c);
    }
  }
  const std::vector<std::uint64_t> m_list{1, 2, 3, 5, 8, 13, 64, 100, 128};
  Heap heap(128, m_list);
  feed(heap.c, counts);
  const Held held = hold(counts);
  for (std::size_t i = 0; i < m_list.size(); ++i) {
    BatchTau b(m_list[i], 1);
    for (std::size_t k = 0; k < counts.size(); ++k) {
      ASSERT_EQ(held.r32[k].size(), held.r64[k].size()) << "the residuals must stay within int32";
      b.add_segment(held.seg32[k]);
    }
    expect_same(heap.c, i, b, "int32");
    Exact want;
    for (std::size_t k = 0; k < counts.size(); ++k)
      want += brute_force(held.x[k], m_list[i], 1, false, held.seg64[k].first_e);
    for (std::size_t k = 0; k < 3; ++k)
      EXPECT_TRUE(to_u128(b.result().sum[k]) == want.sum[k]) << "m=" << m_list[i] << " stat " << k;
  }
}

TEST(Batch, TermsBeyondInt64AreCountedOutOfRangeAsTheCharacterizerDoes) {
  // Fully overlapped m = 2^17: swings of +-(2^31 - 1) make MVAR terms of about 2^66, which the
  // spread cannot prove to fit: the checked path counts them out of range, the AVAR and HVAR
  // terms (about 2^50) stay exact, as in the characterizer.
  const std::uint64_t m = std::uint64_t{1} << 17;
  std::vector<std::vector<std::int32_t>> counts(2);
  for (int block = 0; block < 4; ++block)
    for (std::uint64_t k = 0; k < m; ++k) counts[0].push_back(block % 2 == 0 ? 2147483647 : -2147483647);
  for (std::uint64_t k = 0; k < 3 * m; ++k) counts[1].push_back(static_cast<std::int32_t>(k % 1000));
  Heap heap(1u << 17, {1, 3, m});
  feed(heap.c, counts);
  const Held held = hold(counts);
  BatchTau b(m, 1);
  for (const auto& seg : held.seg64) b.add_segment(seg);
  expect_same(heap.c, 2, b, "int64");
  EXPECT_GT(b.result().out_of_range, 0u);
}

TEST(Batch, SumsReachingTwoToThe127AreFlagged) {
  // Counts of +-(2^31 - 1) in runs of 20000 make MVAR terms at m = 2^13 of up to m^2 2^32 = 2^58
  // (each fits in int64), whose 3 10^5 squares sum past 2^127 (oracle: that magnitude bound):
  // the sticky flag is set, as in the characterizer.
  std::vector<std::vector<std::int32_t>> counts;
  for (int k = 0; k < 8; ++k) {
    std::vector<std::int32_t> v;
    for (int j = 0; j < 40000; ++j) v.push_back((j / 20000) % 2 ? 2147483647 : -2147483647);
    counts.push_back(v);
  }
  Heap heap(1u << 13, {1, 1u << 13});
  feed(heap.c, counts);
  const Held held = hold(counts);
  BatchTau b(1u << 13, 1);
  for (const auto& seg : held.seg64) b.add_segment(seg);
  expect_same(heap.c, 1, b, "int64");
  EXPECT_TRUE(b.result().sum_overflow);
}

}  // namespace
}  // namespace gyrochar
