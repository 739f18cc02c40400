// Exactness over a long run: 2^30 counts (a 12-day run at 1 ms) must give variance sums equal, to
// the last bit, to the exact computation, as after 10^3 counts.
// Oracle: counts with a period p make every term a function of (e mod p) only, so the exact sum is
// sum over residues of (number of terms with that residue) * (term value)^2, with each term value
// computed by brute force in 128-bit integers on a short series. The large mean count (10^6 per
// sample) drives P past 2^64, exercising the 128-bit prefix sums.
#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <vector>

#include "gyrochar/characterizer.hpp"

namespace gyrochar {
namespace {

using i128 = __int128;
using u128 = unsigned __int128;

constexpr std::uint64_t period = 1024;
constexpr unsigned octaves = 21;  // m up to 2^20
constexpr std::uint32_t stride_factor = 8;

struct Periodic {
  std::vector<std::int64_t> pattern;
  std::int64_t base = 1000000;
  std::int64_t count(std::uint64_t i) const { return base + pattern[i % period]; }
};

void check_run(std::uint64_t n_counts) {
  Periodic source;
  std::mt19937_64 rng(2026);
  for (std::uint64_t i = 0; i < period; ++i) source.pattern.push_back(static_cast<std::int64_t>(rng() % 20001) - 10000);

  auto c = std::make_unique<StaticCharacterizer<CountArith, octaves, stride_factor>>();
  std::vector<std::uint64_t> m_list;
  for (unsigned k = 0; k < octaves; ++k) m_list.push_back(std::uint64_t{1} << k);
  ASSERT_EQ(c->configure({stride_factor, 0}, m_list), ConfigureStatus::ok);
  for (std::uint64_t i = 0; i < n_counts; ++i) c->add_increment(source.count(i));
  const std::uint64_t points = n_counts + 1;  // phase points x_0 .. x_N
  ASSERT_EQ(c->phase_points(), points);

  // A short explicit series long enough for the largest tau, with its prefix sums.
  const std::uint64_t m_max = m_list.back();
  const std::uint64_t len = 3 * m_max + 2 * period + 2;
  std::vector<i128> x(len, 0), p(len + 1, 0);
  for (std::uint64_t e = 1; e < len; ++e) x[e] = x[e - 1] + source.count(e - 1);
  for (std::uint64_t e = 0; e < len; ++e) p[e + 1] = p[e] + x[e];

  for (std::size_t i = 0; i < m_list.size(); ++i) {
    const std::uint64_t m = m_list[i];
    const std::uint64_t stride = c->result(i).stride;
    std::array<u128, 3> want_sum{};
    std::array<std::uint64_t, 3> want_n{};
    const std::uint64_t first[3] = {2 * m, 3 * m - 1, 3 * m};  // smallest newest index e per stat
    const std::uint64_t classes = std::max(period, stride);
    for (std::uint64_t r = 0; r < classes; r += stride) {
      // Representative e in the short series with e = r (mod classes) and full history.
      std::uint64_t e = 3 * m + ((r + classes - (3 * m) % classes) % classes);
      const i128 a = x[e] - 2 * x[e - m] + x[e - 2 * m];
      const i128 t = p[e + 1] - 3 * p[e + 1 - m] + 3 * p[e + 1 - 2 * m] - p[e + 1 - 3 * m];
      const i128 h = x[e] - 3 * x[e - m] + 3 * x[e - 2 * m] - x[e - 3 * m];
      const i128 term[3] = {a, t, h};
      for (int s = 0; s < 3; ++s) {
        // Number of e in [first, points-1] with e = r (mod classes).
        const std::uint64_t lo = first[s], hi = points - 1;
        if (hi < lo) continue;
        const std::uint64_t start = lo + (r + classes - lo % classes) % classes;
        if (start > hi) continue;
        const std::uint64_t count = (hi - start) / classes + 1;
        want_sum[s] += static_cast<u128>(term[s] * term[s]) * count;
        want_n[s] += count;
      }
    }
    const auto& got = c->result(i);
    for (int s = 0; s < 3; ++s) {
      const u128 got_sum = (u128{got.sum[s].hi} << 64) | got.sum[s].lo;
      EXPECT_EQ(got.n[s], want_n[s]) << "m=" << m << " stat " << s;
      EXPECT_TRUE(got_sum == want_sum[s]) << "m=" << m << " stat " << s;
    }
    EXPECT_EQ(got.out_of_range, 0u);
    EXPECT_FALSE(got.sum_overflow);
  }
}

TEST(CharacterizerLongRun, ExactAfterOneThousandCounts) { check_run(1000); }
TEST(CharacterizerLongRun, ExactAfterTwoToTheThirtyCounts) { check_run(std::uint64_t{1} << 30); }

}  // namespace
}  // namespace gyrochar
