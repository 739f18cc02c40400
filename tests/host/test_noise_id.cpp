// Noise identification on generated power-law noise of each type (oracle: the generating process)
// and the gap rule: no difference spans a segment break.
#include <gtest/gtest.h>

#include <cmath>

#include "analysis.hpp"
#include "gyrochar/noise_id.hpp"
#include "support/power_law_noise.hpp"

namespace gyrochar {
namespace {

using test_support::power_law_phase;

TEST(NoiseId, IdentifiesEachPowerLawNoise) {
  for (int alpha : {2, 1, 0, -1, -2}) {
    int right = 0, total = 0;
    for (std::uint64_t seed = 1; seed <= 3; ++seed) {
      const auto x = power_law_phase(alpha, 6000, seed * 100 + static_cast<std::uint64_t>(alpha + 10));
      AnalysisOptions o;
      o.type = DataType::phase;
      o.m_list = {1, 4, 16, 64};
      o.stats = {DevStat::oadev};
      Analyzer a(o);
      for (double v : x) a.add(v);
      for (const auto& row : a.result().rows) {
        ++total;
        if (row.alpha && *row.alpha == alpha) ++right;
      }
    }
    // The lag-1 estimator is statistical. Measured with this generator (stationary increments,
    // 200 seeds of 6000 points per type), identified right at m = 1, 4, 16, 64: white PM 100, 100,
    // 98, 82 %; flicker PM 100, 92, 54, 45 % (taken for white PM where the decimated flicker
    // phase has 94..375 points: the known weak spot of the lag-1 method, which is why
    // R(n) = MVAR/AVAR exists); white FM 100, 100, 100, 96 %; flicker FM 100, 95, 70, 56 % (taken
    // for random walk FM); random walk FM 100 % throughout. These three seeds: 11, 8, 12, 9, 12
    // of 12. (The earlier generator started the flicker filter from an empty past, without
    // burn-in, and gave 11 of 12 for flicker FM.)
    EXPECT_GE(right, alpha == 1 || alpha == -1 ? 8 : 11) << "alpha " << alpha << ": " << right << " of " << total;
  }
}

TEST(NoiseId, DifferencesDoNotSpanAGap) {
  // White phase noise in two segments with a huge offset between them: identified as white PM
  // only if the jump is not differenced across (oracle: the gap rule).
  const auto x = power_law_phase(2, 200, 5);
  NoiseIdAccumulator with_gap, without;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double jump = i >= 100 ? 1e6 : 0.0;
    if (i == 100) with_gap.reset_segment();
    with_gap.add(x[i] + jump);
    without.add(x[i] + jump);
  }
  EXPECT_EQ(2 - std::lround(lag1_estimate(summarize(with_gap), 0, 2).p), 2);
  EXPECT_NE(2 - std::lround(lag1_estimate(summarize(without), 0, 2).p), 2);
}

}  // namespace
}  // namespace gyrochar
