// The pyramid against the estimator definitions evaluated by brute force.
// Oracle: the definitions in the header (and in ../shared/refdata/README.md) computed directly
// over the whole series with exact 128-bit integers; the pyramid must equal them bit for bit.
#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <vector>

#include "gyrochar/pyramid.hpp"
#include "oracle/brute_force.hpp"

namespace gyrochar {
namespace {

using oracle::brute_force;
using oracle::Exact;
using oracle::i128;
using oracle::u128;

u128 to_u128(UInt128 v) { return (u128{v.hi} << 64) | v.lo; }

std::vector<std::uint64_t> octaves(unsigned count) {
  std::vector<std::uint64_t> m;
  for (unsigned k = 0; k < count; ++k) m.push_back(std::uint64_t{1} << k);
  return m;
}

void expect_exact(const Pyramid<CountArith>& pyramid, std::size_t i, const Exact& want) {
  const auto& got = pyramid.result(i);
  for (std::size_t s = 0; s < 3; ++s) {
    EXPECT_EQ(got.n[s], want.n[s]) << "m=" << got.m << " stat=" << s;
    EXPECT_TRUE(to_u128(got.sum[s]) == want.sum[s]) << "m=" << got.m << " stat=" << s;
  }
  EXPECT_EQ(got.out_of_range, 0u);
  EXPECT_FALSE(got.sum_overflow);
}

class PyramidProperty : public ::testing::TestWithParam<std::uint32_t> {};

TEST_P(PyramidProperty, RandomCountsEqualBruteForce) {
  const std::uint32_t stride_factor = GetParam();
  std::mt19937_64 rng(1234 + stride_factor);
  for (int trial = 0; trial < 6; ++trial) {
    const std::size_t n_counts = 200 + rng() % 3000;
    std::uniform_int_distribution<std::int64_t> count(-1000 - trial * 100000, 5000);
    std::vector<std::int64_t> x{0};
    StaticPyramid<CountArith, 12, 64> pyramid;
    const auto m_list = octaves(12);
    ASSERT_EQ(pyramid.configure({stride_factor, false}, m_list), PyramidStatus::ok);
    for (std::size_t k = 0; k < n_counts; ++k) {
      const std::int64_t c = count(rng);
      pyramid.add_increment(c);
      x.push_back(x.back() + c);
    }
    ASSERT_EQ(pyramid.phase_points(), x.size());
    for (std::size_t i = 0; i < m_list.size(); ++i) {
      const std::uint64_t m = m_list[i];
      const std::uint64_t stride = m <= stride_factor ? 1 : m / stride_factor;
      EXPECT_EQ(pyramid.stride(i), stride);
      expect_exact(pyramid, i, brute_force(x, m, stride));
    }
  }
}

INSTANTIATE_TEST_SUITE_P(StrideFactors, PyramidProperty, ::testing::Values(2u, 4u, 8u, 16u, 64u));

TEST(Pyramid, SubOctaveTausEqualBruteForce) {
  std::mt19937_64 rng(99);
  const std::vector<std::uint64_t> m_list{1, 2, 3, 4, 5, 6, 7, 8, 10, 12, 14, 16, 20, 24, 28, 32, 40, 48, 56, 64};
  StaticPyramid<CountArith, 8, 8, 24> pyramid;
  ASSERT_EQ(pyramid.configure({8, false}, m_list), PyramidStatus::ok);
  std::vector<std::int64_t> x{0};
  for (int k = 0; k < 5000; ++k) {
    const std::int64_t c = static_cast<std::int64_t>(rng() % 2001) - 1000;
    pyramid.add_increment(c);
    x.push_back(x.back() + c);
  }
  for (std::size_t i = 0; i < m_list.size(); ++i) {
    const std::uint64_t m = m_list[i];
    expect_exact(pyramid, i, brute_force(x, m, m <= 8 ? 1 : pyramid.stride(i)));
  }
}

TEST(Pyramid, NonOverlappingModeEqualsDecimatedDefinition) {
  std::mt19937_64 rng(7);
  const auto m_list = octaves(7);
  StaticPyramid<CountArith, 7, 64> pyramid;
  ASSERT_EQ(pyramid.configure({64, true}, m_list), PyramidStatus::ok);
  std::vector<std::int64_t> x{0};
  for (int k = 0; k < 3001; ++k) {
    const std::int64_t c = static_cast<std::int64_t>(rng() % 100);
    pyramid.add_increment(c);
    x.push_back(x.back() + c);
  }
  for (std::size_t i = 0; i < m_list.size(); ++i) {
    const Exact want = brute_force(x, m_list[i], 1, true);
    const auto& got = pyramid.result(i);
    EXPECT_EQ(got.n[0], want.n[0]);
    EXPECT_TRUE(to_u128(got.sum[0]) == want.sum[0]);
    EXPECT_EQ(got.n[2], want.n[2]);
    EXPECT_TRUE(to_u128(got.sum[2]) == want.sum[2]);
    // Stable32's non-overlapped term count: floor((N-1)/m) - 1 for N phase points.
    EXPECT_EQ(got.n[0], (x.size() - 1) / m_list[i] - 1);
  }
}

TEST(Pyramid, GapsFormNoSpanningTerms) {
  // Two segments fed with a gap between them must give the sums of the two segments computed
  // separately (oracle: brute force per segment), whatever phase jump happens across the gap.
  std::mt19937_64 rng(5);
  const auto m_list = octaves(8);
  StaticPyramid<CountArith, 8, 8> pyramid;
  ASSERT_EQ(pyramid.configure({8, false}, m_list), PyramidStatus::ok);
  std::vector<std::vector<std::int64_t>> segments;
  std::vector<std::uint64_t> starts;
  for (int seg = 0; seg < 3; ++seg) {
    if (seg > 0) pyramid.mark_gap();
    starts.push_back(pyramid.phase_points());
    std::vector<std::int64_t> x{0};
    const int len = 700 + seg * 333;
    for (int k = 0; k < len; ++k) {
      const std::int64_t c = static_cast<std::int64_t>(rng() % 50) + (seg == 1 ? 1000000 : 0);
      pyramid.add_increment(c);
      x.push_back(x.back() + c);
    }
    segments.push_back(x);
  }
  for (std::size_t i = 0; i < m_list.size(); ++i) {
    const std::uint64_t m = m_list[i];
    Exact want;
    for (std::size_t seg = 0; seg < segments.size(); ++seg) {
      // Strided terms sit on the global grid of phase indices: the segment's offset.
      want += brute_force(segments[seg], m, pyramid.stride(i), false, starts[seg]);
    }
    expect_exact(pyramid, i, want);
  }
}

TEST(Pyramid, OutOfRangeTermsAreSkippedAndCounted) {
  // Blocks of m = 2^17 counts of +(2^31-1) and -(2^31-1) make MVAR terms of about 2 m^2 2^31 =
  // 2^66, beyond int64: they cannot be exact and must be counted, not accumulated (oracle: that
  // magnitude bound). AVAR terms (about 2 m 2^31 = 2^49) stay exact and are formed.
  StaticPyramid<CountArith, 18, 2> pyramid;
  const std::vector<std::uint64_t> m_list{std::uint64_t{1} << 17};
  ASSERT_EQ(pyramid.configure({2, false}, m_list), PyramidStatus::ok);
  const std::int32_t c = 2147483647;
  for (int block = 0; block < 4; ++block)
    for (int k = 0; k < (1 << 17); ++k) pyramid.add_increment(block % 2 == 0 ? c : -c);
  // MVAR positions: e in [3m-1, 4m] on the stride grid (m/S = 2^16) -> 393216, 458752, 524288.
  EXPECT_GT(pyramid.result(0).out_of_range, 0u);
  EXPECT_EQ(pyramid.result(0).n[1] + pyramid.result(0).out_of_range, 3u);
  EXPECT_GT(pyramid.result(0).n[0], 0u);
}

TEST(Pyramid, FloatPhaseMatchesLongDoubleDefinition) {
  // Floating phase with a large offset and drift (as clock phase files have): the pyramid keeps
  // double-double prefix sums, so MVAR must match the definition evaluated in long double with
  // phase taken relative to the first point (oracle) to 1e-9 relative.
  std::mt19937_64 rng(11);
  std::normal_distribution<double> noise(0.0, 1e-9);
  std::vector<double> x;
  double walk = 0.0;
  for (int k = 0; k < 4000; ++k) {
    walk += noise(rng);
    x.push_back(1e-3 + 2.5e-7 * k + walk + noise(rng));
  }
  const auto m_list = octaves(9);
  StaticPyramid<FloatArith, 9, 512> pyramid;
  ASSERT_EQ(pyramid.configure({512, false}, m_list), PyramidStatus::ok);
  for (double v : x) pyramid.add_phase_point(v - x[0]);
  for (std::size_t i = 0; i < m_list.size(); ++i) {
    const std::uint64_t m = m_list[i];
    long double sum[3] = {0, 0, 0};
    std::uint64_t n[3] = {0, 0, 0};
    std::vector<long double> p(x.size() + 1, 0);
    for (std::size_t k = 0; k < x.size(); ++k) p[k + 1] = p[k] + (static_cast<long double>(x[k]) - x[0]);
    for (std::uint64_t e = 0; e < x.size(); ++e) {
      auto xr = [&](std::uint64_t k) { return static_cast<long double>(x[k]) - x[0]; };
      if (e >= 2 * m) { const long double a = xr(e) - 2 * xr(e - m) + xr(e - 2 * m); sum[0] += a * a; ++n[0]; }
      if (e + 1 >= 3 * m) {
        const long double t = p[e + 1] - 3 * p[e + 1 - m] + 3 * p[e + 1 - 2 * m] - p[e + 1 - 3 * m];
        sum[1] += t * t;
        ++n[1];
      }
      if (e >= 3 * m) {
        const long double h = xr(e) - 3 * xr(e - m) + 3 * xr(e - 2 * m) - xr(e - 3 * m);
        sum[2] += h * h;
        ++n[2];
      }
    }
    for (int s = 0; s < 3; ++s) {
      EXPECT_EQ(pyramid.result(i).n[s], n[s]);
      EXPECT_NEAR(pyramid.result(i).sum[s] / static_cast<double>(sum[s]), 1.0, 1e-9) << "m=" << m << " stat " << s;
    }
  }
}

TEST(Pyramid, RejectsBadConfiguration) {
  StaticPyramid<CountArith, 10, 8> pyramid;
  const std::vector<std::uint64_t> unrepresentable{1, 2, 17};  // 17 > S and odd
  EXPECT_EQ(pyramid.configure({8, false}, unrepresentable), PyramidStatus::tau_not_representable);
  const std::vector<std::uint64_t> unsorted{2, 1};
  EXPECT_EQ(pyramid.configure({8, false}, unsorted), PyramidStatus::tau_not_representable);
  EXPECT_EQ(pyramid.configure({6, false}, octaves(3)), PyramidStatus::bad_stride_factor);
  EXPECT_EQ(pyramid.configure({16, false}, octaves(3)), PyramidStatus::ok);
  EXPECT_EQ(pyramid.configure({8, false}, octaves(11)), PyramidStatus::too_many_taus);
  EXPECT_EQ(pyramid.configure({8, true}, octaves(5)), PyramidStatus::nonoverlapping_needs_m_le_s);
}

}  // namespace
}  // namespace gyrochar
