// The interpolated EDF of dense tau lists (host_tools/analyze/edf_table.hpp) against the exact
// EDF and skew degrees of freedom (oracle: estimate() and exact_skew_dof() of the core, computed
// here at every m): exact at the anchors, within the stated relative error between them, for every
// overlapping statistic and every noise it converges for; and the estimate it gives with gaps
// and plausible ranges equals estimate()'s up to that error.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "confidence.hpp"
#include "edf_table.hpp"

namespace gyrochar {
namespace {

constexpr double stated_error = 2e-3;           // the EDF (edf_table.hpp)
constexpr double stated_interval_error = 5e-3;  // the interval's bounds with the skewness

struct Case {
  DevStat stat;
  std::uint64_t n_phase;
};

class EdfTableError : public ::testing::TestWithParam<Case> {};

TEST_P(EdfTableError, EveryMWithinTheStatedErrorOfTheExactEdf) {
  const auto [stat, n_phase] = GetParam();
  std::vector<PairSumCache::Entry> entries(4096);
  PairSumCache cache(entries);
  const Stat s = stat_of(stat);
  std::uint64_t m_max = 64;
  while (unbroken_grid(s, m_max + 1, 1, n_phase).n > 0) ++m_max;
  const EdfTable table(stat, n_phase, 64, m_max, cache);
  EXPECT_LT(table.anchors(), (m_max - 63) / 4);  // it pays
  const EstimateOptions exact{1.0, 1.0, EdfModel::exact, false};
  double worst = 0, worst_skew = 0;
  for (std::uint64_t m = 64; m <= m_max; m += 1 + m / 97) {  // every m up to 97, then a spread
    const TermGrid grid = unbroken_grid(s, m, 1, n_phase);
    const TauSums t = unbroken_sums(stat, m, n_phase);
    for (int alpha = 2; alpha >= -4; --alpha) {
      const double want = estimate(t, n_phase, stat, {alpha, alpha, alpha, NoiseIdMethod::given}, exact, &cache).edf;
      const EdfTable::Value got = table.at(m, alpha);
      if (want == 0) {
        EXPECT_EQ(got.edf, 0.0) << "m=" << m << " alpha=" << alpha;
        continue;
      }
      worst = std::fmax(worst, std::fabs(got.edf / want - 1));
      EXPECT_NEAR(got.edf / want, 1.0, stated_error) << "m=" << m << " alpha=" << alpha;
      if (want < 100) {  // the skewness shapes the interval: its bounds
        const Interval exact_ci = confidence_interval(1.0, want, 0.683, exact_skew_dof(alpha, grid));
        const Interval got_ci = confidence_interval(1.0, got.edf, 0.683, got.skew_dof);
        const double err = std::fmax(std::fabs(got_ci.low / exact_ci.low - 1), std::fabs(got_ci.high / exact_ci.high - 1));
        worst_skew = std::fmax(worst_skew, err);
        EXPECT_LT(err, stated_interval_error) << "m=" << m << " alpha=" << alpha;
      }
    }
  }
  std::printf("%s N=%llu: %zu anchors for %llu taus, worst EDF error %.2e, interval bound %.2e\n", name(stat),
              static_cast<unsigned long long>(n_phase), table.anchors(), static_cast<unsigned long long>(m_max - 63), worst,
              worst_skew);
}

INSTANTIATE_TEST_SUITE_P(Stats, EdfTableError,
                         ::testing::Values(Case{DevStat::oadev, 4001}, Case{DevStat::mdev, 4001}, Case{DevStat::ohdev, 4001},
                                           Case{DevStat::oadev, 30001}));

TEST(EdfTable, EstimateWithGapsAndPlausibleRangesAsEstimate) {
  // A tau with a tenth of its terms lost to gaps and three plausible noises: the smallest EDF of
  // the three, scaled by the share formed, its skewness likewise (oracle: estimate()).
  const std::uint64_t n_phase = 4001, m = 777;
  std::vector<PairSumCache::Entry> entries(256);
  PairSumCache cache(entries);
  const EdfTable table(DevStat::mdev, n_phase, 64, 1000, cache);
  TauSums t = unbroken_sums(DevStat::mdev, m, n_phase);
  t.n[static_cast<std::size_t>(SumKind::mvar)] = t.n[static_cast<std::size_t>(SumKind::mvar)] * 9 / 10;
  t.variance[static_cast<std::size_t>(SumKind::mvar)] = 2.5;
  const NoiseId id{0, -1, 1, NoiseIdMethod::rn};
  const EstimateOptions o{0.01, 1.0, EdfModel::exact, true};
  const Estimate want = estimate(t, n_phase, DevStat::mdev, id, o, &cache);
  const Estimate got = table.estimate(t, n_phase, id, o);
  EXPECT_EQ(got.deviation, want.deviation);
  EXPECT_EQ(got.n, want.n);
  EXPECT_EQ(got.edf_alpha, want.edf_alpha);
  EXPECT_NEAR(got.edf / want.edf, 1.0, stated_error);
  ASSERT_GT(want.skew_dof, 0.0);
  const Interval a = confidence_interval(1.0, want.edf, 0.683, want.skew_dof);
  const Interval b = confidence_interval(1.0, got.edf, 0.683, got.skew_dof);
  EXPECT_NEAR(b.low / a.low, 1.0, stated_interval_error);
  EXPECT_NEAR(b.high / a.high, 1.0, stated_interval_error);
}

TEST(EdfTable, DenseNoiseSumsWithinTheStatedErrorOfTheExactOnes) {
  // The diagonal pair sums identify_noise() reads (R(n)'s variances) at every m of a dense list,
  // through a cache that asks DenseNoiseSums first, against pair_sums() computed here (oracle).
  const std::uint64_t n_phase = 6001;
  std::vector<std::uint64_t> m_list;
  for (std::uint64_t m = 1; m <= 2000; ++m) m_list.push_back(m);
  std::vector<PairSumCache::Entry> entries(4096);
  PairSumCache cache(entries);
  const DenseNoiseSums dense(m_list, n_phase, 64, cache);
  cache.attach(&dense);
  const std::size_t anchors = dense.anchors();
  EXPECT_LT(anchors, m_list.size() / 4);
  double worst = 0;
  for (std::uint64_t m = 64; m <= 2000; m += 1 + m / 61) {
    const TermGrid a = unbroken_grid(Stat::avar, m, 1, n_phase), b = unbroken_grid(Stat::mvar, m, 1, n_phase);
    for (const auto& [g, h] : {std::pair{a, a}, std::pair{b, b}, std::pair{a, b}, std::pair{b, a}}) {
      const PairSums got = cache.get(g, h), want = pair_sums(allan_noises(), g, h);
      for (std::size_t k = 0; k < 5; ++k) {
        worst = std::fmax(worst, std::fabs(got.cc[k][k] / want.cc[k][k] - 1));
        EXPECT_NEAR(got.cc[k][k] / want.cc[k][k], 1.0, stated_error) << "m=" << m << " noise " << k;
      }
    }
  }
  std::printf("noise sums N=%llu: %zu anchors for %zu taus, worst error %.2e\n", static_cast<unsigned long long>(n_phase),
              anchors, m_list.size() - 63, worst);
}

}  // namespace
}  // namespace gyrochar
