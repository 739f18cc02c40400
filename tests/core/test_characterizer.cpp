// The characterizer against the estimator definitions evaluated by brute force.
// Oracle: the definitions in the header (and in tests/data/README.md) computed directly
// over the whole series with exact 128-bit integers; the sums must equal them bit for bit. The
// noise identification sums against the lag-1 autocorrelation computed directly.
#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <vector>

#include "gyrochar/characterizer.hpp"
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

void expect_exact(const Characterizer<CountArith>& c, std::size_t i, const Exact& want) {
  const auto& got = c.result(i);
  for (std::size_t s = 0; s < 3; ++s) {
    EXPECT_EQ(got.n[s], want.n[s]) << "m=" << got.m << " stat=" << s;
    EXPECT_TRUE(to_u128(got.sum[s]) == want.sum[s]) << "m=" << got.m << " stat=" << s;
  }
  EXPECT_EQ(got.out_of_range, 0u);
  EXPECT_FALSE(got.sum_overflow);
}

class CharacterizerProperty : public ::testing::TestWithParam<std::uint32_t> {};

TEST_P(CharacterizerProperty, RandomCountsEqualBruteForce) {
  const std::uint32_t stride_factor = GetParam();
  std::mt19937_64 rng(1234 + stride_factor);
  for (int trial = 0; trial < 6; ++trial) {
    const std::size_t n_counts = 200 + rng() % 3000;
    std::uniform_int_distribution<std::int64_t> count(-1000 - trial * 100000, 5000);
    std::vector<std::int64_t> x{0};
    StaticCharacterizer<CountArith, 12, 64> c;
    const auto m_list = octaves(12);
    ASSERT_EQ(c.configure({stride_factor, 0}, m_list), ConfigureStatus::ok);
    for (std::size_t k = 0; k < n_counts; ++k) {
      const std::int64_t v = count(rng);
      c.add_increment(static_cast<std::int32_t>(v));
      x.push_back(x.back() + v);
    }
    ASSERT_EQ(c.phase_points(), x.size());
    for (std::size_t i = 0; i < m_list.size(); ++i) {
      const std::uint64_t m = m_list[i];
      const std::uint64_t stride = m <= stride_factor ? 1 : m / stride_factor;
      EXPECT_EQ(c.result(i).stride, stride);
      expect_exact(c, i, brute_force(x, m, stride));
    }
  }
}

INSTANTIATE_TEST_SUITE_P(StrideFactors, CharacterizerProperty, ::testing::Values(2u, 4u, 8u, 16u, 64u));

TEST(Characterizer, SubOctaveTausEqualBruteForce) {
  std::mt19937_64 rng(99);
  const std::vector<std::uint64_t> m_list{1, 2, 3, 4, 5, 6, 7, 8, 10, 12, 14, 16, 20, 24, 28, 32, 40, 48, 56, 64};
  StaticCharacterizer<CountArith, 8, 8, 24> c;
  ASSERT_EQ(c.configure({8, 0}, m_list), ConfigureStatus::ok);
  std::vector<std::int64_t> x{0};
  for (int k = 0; k < 5000; ++k) {
    const std::int64_t v = static_cast<std::int64_t>(rng() % 2001) - 1000;
    c.add_increment(static_cast<std::int32_t>(v));
    x.push_back(x.back() + v);
  }
  for (std::size_t i = 0; i < m_list.size(); ++i) {
    const std::uint64_t m = m_list[i];
    expect_exact(c, i, brute_force(x, m, m <= 8 ? 1 : c.result(i).stride));
  }
}

void expect_nonoverlapped(const Characterizer<CountArith>& c, std::size_t i, const Exact& want) {
  const auto got = c.result(i);
  const auto avar = static_cast<std::size_t>(SumKind::avar_nonoverlapped);
  const auto hvar = static_cast<std::size_t>(SumKind::hvar_nonoverlapped);
  EXPECT_EQ(got.n[avar], want.n[0]) << "m=" << got.m;
  EXPECT_TRUE(to_u128(got.sum[avar]) == want.sum[0]) << "m=" << got.m;
  EXPECT_EQ(got.n[hvar], want.n[2]) << "m=" << got.m;
  EXPECT_TRUE(to_u128(got.sum[hvar]) == want.sum[2]) << "m=" << got.m;
}

TEST(Characterizer, NonOverlappedSumsEqualDecimatedDefinition) {
  // Every tau, below and above the stride factor and off the octaves (the decimation rides on the
  // tau's level): Stable32's non-overlapped terms x[e] - 2x[e-m] + x[e-2m] at e = 0, m, 2m, ...
  std::mt19937_64 rng(7);
  const std::vector<std::uint64_t> m_list{1, 2, 3, 5, 8, 12, 16, 24, 40, 64, 96};
  StaticCharacterizer<CountArith, 8, 8, 16> c;
  ASSERT_EQ(c.configure({8, 0}, m_list), ConfigureStatus::ok);
  std::vector<std::int64_t> x{0};
  for (int k = 0; k < 3001; ++k) {
    const std::int64_t v = static_cast<std::int64_t>(rng() % 100);
    c.add_increment(static_cast<std::int32_t>(v));
    x.push_back(x.back() + v);
  }
  for (std::size_t i = 0; i < m_list.size(); ++i) {
    expect_nonoverlapped(c, i, brute_force(x, m_list[i], 1, true));
    // Stable32's non-overlapped term count: floor((N-1)/m) - 1 for N phase points.
    EXPECT_EQ(c.result(i).n[static_cast<std::size_t>(SumKind::avar_nonoverlapped)], (x.size() - 1) / m_list[i] - 1);
  }
}

TEST(Characterizer, NoiseSumsSeeTheDecimatedSeries) {
  // The lag-1 autocorrelation of x[0], x[m], x[2m], ... and of its first difference, computed
  // directly (oracle: the definition r1 = sum (z_i - mean)(z_i+1 - mean) / sum (z_i - mean)^2).
  std::mt19937_64 rng(17);
  const std::vector<std::uint64_t> m_list{1, 3, 16, 48};
  StaticCharacterizer<CountArith, 8, 8, 8> c;
  ASSERT_EQ(c.configure({8, 0}, m_list), ConfigureStatus::ok);
  std::vector<std::int64_t> x{0};
  for (int k = 0; k < 5000; ++k) {
    const std::int64_t v = static_cast<std::int64_t>(rng() % 21) - 10;
    c.add_increment(static_cast<std::int32_t>(v));
    x.push_back(x.back() + v);
  }
  auto r1 = [](const std::vector<double>& z) {
    double mean = 0;
    for (double v : z) mean += v;
    mean /= static_cast<double>(z.size());
    double num = 0, den = 0;
    for (std::size_t i = 0; i < z.size(); ++i) {
      den += (z[i] - mean) * (z[i] - mean);
      if (i + 1 < z.size()) num += (z[i] - mean) * (z[i + 1] - mean);
    }
    return num / den;
  };
  for (std::size_t i = 0; i < m_list.size(); ++i) {
    std::vector<double> z, dz;
    for (std::size_t e = 0; e < x.size(); e += m_list[i]) z.push_back(static_cast<double>(x[e]));
    for (std::size_t k = 1; k < z.size(); ++k) dz.push_back(z[k] - z[k - 1]);
    ASSERT_EQ(c.noise(i).points(), z.size());
    EXPECT_NEAR(c.noise(i).order(0).r1(), r1(z), 1e-9) << "m=" << m_list[i];
    EXPECT_NEAR(c.noise(i).order(1).r1(), r1(dz), 1e-9) << "m=" << m_list[i];
  }
}

TEST(Characterizer, GapsFormNoSpanningTerms) {
  // Segments fed with gaps between them must give the sums of the segments computed separately
  // (oracle: brute force per segment, overlapping and non-overlapped), whatever phase jump happens
  // across a gap.
  std::mt19937_64 rng(5);
  const auto m_list = octaves(8);
  StaticCharacterizer<CountArith, 8, 8> c;
  ASSERT_EQ(c.configure({8, 0}, m_list), ConfigureStatus::ok);
  std::vector<std::vector<std::int64_t>> segments;
  std::vector<std::uint64_t> starts;
  for (int seg = 0; seg < 3; ++seg) {
    if (seg > 0) c.mark_gap();
    starts.push_back(c.phase_points());
    std::vector<std::int64_t> x{0};
    const int len = 700 + seg * 333;
    for (int k = 0; k < len; ++k) {
      const std::int64_t v = static_cast<std::int64_t>(rng() % 50) + (seg == 1 ? 1000000 : 0);
      c.add_increment(static_cast<std::int32_t>(v));
      x.push_back(x.back() + v);
    }
    segments.push_back(x);
  }
  for (std::size_t i = 0; i < m_list.size(); ++i) {
    const std::uint64_t m = m_list[i];
    Exact want, nonoverlapped;
    for (std::size_t seg = 0; seg < segments.size(); ++seg) {
      // Strided terms sit on the global grid of phase indices: the segment's offset.
      want += brute_force(segments[seg], m, c.result(i).stride, false, starts[seg]);
      nonoverlapped += brute_force(segments[seg], m, 1, true, starts[seg]);
    }
    expect_exact(c, i, want);
    expect_nonoverlapped(c, i, nonoverlapped);
  }
}

TEST(Characterizer, OutOfRangeTermsAreSkippedAndCounted) {
  // Blocks of m = 2^17 counts of +(2^31-1) and -(2^31-1) make MVAR terms of about 2 m^2 2^31 =
  // 2^66, beyond int64: they cannot be exact and must be counted, not accumulated (oracle: that
  // magnitude bound). AVAR terms (about 2 m 2^31 = 2^49) stay exact and are formed.
  StaticCharacterizer<CountArith, 18, 2> c;
  const std::vector<std::uint64_t> m_list{std::uint64_t{1} << 17};
  ASSERT_EQ(c.configure({2, 0}, m_list), ConfigureStatus::ok);
  const std::int32_t v = 2147483647;
  for (int block = 0; block < 4; ++block)
    for (int k = 0; k < (1 << 17); ++k) c.add_increment(block % 2 == 0 ? v : -v);
  // MVAR positions: e in [3m-1, 4m] on the stride grid (m/S = 2^16) -> 393216, 458752, 524288.
  EXPECT_GT(c.result(0).out_of_range, 0u);
  EXPECT_EQ(c.result(0).n[1] + c.result(0).out_of_range, 3u);
  EXPECT_GT(c.result(0).n[0], 0u);
}

TEST(Characterizer, FloatPhaseMatchesLongDoubleDefinition) {
  // Floating phase with a large offset and drift (as clock phase files have): the characterizer
  // takes the line through the first two points off and keeps double-double prefix sums, so every
  // sum must match the definition evaluated in long double with phase taken relative to the first
  // point (oracle; the line changes no difference of order two or more) to 1e-9 relative.
  std::mt19937_64 rng(11);
  std::normal_distribution<double> noise(0.0, 1e-9);
  std::vector<double> x;
  double walk = 0.0;
  for (int k = 0; k < 4000; ++k) {
    walk += noise(rng);
    x.push_back(1e-3 + 2.5e-7 * k + walk + noise(rng));
  }
  const auto m_list = octaves(9);
  StaticCharacterizer<FloatArith, 9, 512> c;
  ASSERT_EQ(c.configure({512, 0}, m_list), ConfigureStatus::ok);
  for (double v : x) c.add_phase_point(v);
  for (std::size_t i = 0; i < m_list.size(); ++i) {
    const std::uint64_t m = m_list[i];
    long double sum[3] = {0, 0, 0};
    std::uint64_t n[3] = {0, 0, 0};
    std::vector<long double> p(x.size() + 1, 0);
    for (std::size_t k = 0; k < x.size(); ++k) p[k + 1] = p[k] + (static_cast<long double>(x[k]) - x[0]);
    for (std::uint64_t e = 0; e < x.size(); ++e) {
      auto xr = [&](std::uint64_t k) { return static_cast<long double>(x[k]) - x[0]; };
      if (e >= 2 * m) {
        const long double a = xr(e) - 2 * xr(e - m) + xr(e - 2 * m);
        sum[0] += a * a;
        ++n[0];
      }
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
      EXPECT_EQ(c.result(i).n[s], n[s]);
      EXPECT_NEAR(c.result(i).sum[s] / static_cast<double>(sum[s]), 1.0, 1e-9) << "m=" << m << " stat " << s;
    }
  }
}

TEST(Characterizer, RejectsBadConfiguration) {
  StaticCharacterizer<CountArith, 10, 8> c;
  const std::vector<std::uint64_t> unrepresentable{1, 2, 17};  // 17 > S and odd
  EXPECT_EQ(c.configure({8, 0}, unrepresentable), ConfigureStatus::tau_not_representable);
  const std::vector<std::uint64_t> unsorted{2, 1};
  EXPECT_EQ(c.configure({8, 0}, unsorted), ConfigureStatus::tau_not_representable);
  EXPECT_EQ(c.configure({6, 0}, octaves(3)), ConfigureStatus::bad_stride_factor);
  EXPECT_EQ(c.configure({16, 0}, octaves(3)), ConfigureStatus::ok);
  EXPECT_EQ(c.configure({8, 0}, octaves(11)), ConfigureStatus::too_many_taus);
}

}  // namespace
}  // namespace gyrochar
