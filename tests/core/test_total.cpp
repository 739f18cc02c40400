// The total and Theo family (core/include/gyrochar/total.hpp) against brute-force oracles written
// from NIST SP 1065's definitions in this file: the reflected records built explicitly, every term
// summed directly in long double. The decimated variants against the same brute force restricted
// to the sub-sequences and terms they keep (the oracle of what they compute), and their distance to
// the exact estimator on power-law noise. Random records: white phase plus a random walk and a
// large offset and drift (which none of these statistics may see).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "gyrochar/total.hpp"

namespace gyrochar {
namespace {

using LD = long double;

std::vector<double> record(std::size_t n, std::uint64_t seed, double offset = 1e3, double drift = 2.5) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> z;
  std::vector<double> x(n);
  double walk = 0;
  for (std::size_t i = 0; i < n; ++i) {
    walk += 0.3 * z(rng);
    x[i] = offset + drift * static_cast<double>(i) + walk + z(rng);
  }
  return x;
}

// TOTVAR: the 3N - 4 point record x* of SP 1065 eq. 25, then the definition.
LD totvar_oracle(const std::vector<double>& x, std::uint64_t m, double tau0) {
  const std::size_t N = x.size();
  std::vector<LD> xs;  // x*[1-(N-2)] .. x*[N+(N-2)] in SP 1065's 1-based indices
  for (std::size_t j = N - 2; j >= 1; --j) xs.push_back(2.0L * x[0] - x[j]);
  for (std::size_t i = 0; i < N; ++i) xs.push_back(x[i]);
  for (std::size_t j = 1; j <= N - 2; ++j) xs.push_back(2.0L * x[N - 1] - x[N - 1 - j]);
  const std::size_t off = N - 2;  // xs[off] = x[0]
  LD sum = 0;
  for (std::size_t i = 1; i + 1 < N; ++i) {
    const LD t = xs[off + i - m] - 2 * xs[off + i] + xs[off + i + m];
    sum += t * t;
  }
  const LD tau = static_cast<LD>(m) * tau0;
  return sum / (2 * tau * tau * static_cast<LD>(N - 2));
}

// One sub-sequence of 3M values (M = m / b): linear trend from the half means removed, the 9M
// extension by mirror reflection, and the mean of squared terms sum_{j=k}^{k+M-1} (e[j+2M] -
// 2e[j+M] + e[j]) over the 6M start points k (every b-th of the full estimator's when the values
// are block sums). Written from SP 1065 section 5.2.12 without prefix sums.
LD subsequence_mean(const std::vector<LD>& w) {
  const std::size_t L = w.size(), M = L / 3, h = L / 2;
  LD a = 0, b = 0;
  for (std::size_t t = 0; t < h; ++t) a += w[t], b += w[L - h + t];
  const LD slope = (b / h - a / h) / static_cast<LD>(L - h);
  std::vector<LD> u(L), e;
  for (std::size_t t = 0; t < L; ++t) u[t] = w[t] - slope * static_cast<LD>(t);
  for (std::size_t t = 0; t < L; ++t) e.push_back(u[L - 1 - t]);
  for (std::size_t t = 0; t < L; ++t) e.push_back(u[t]);
  for (std::size_t t = 0; t < L; ++t) e.push_back(u[L - 1 - t]);
  LD acc = 0;
  for (std::size_t k = 0; k < 6 * M; ++k) {
    LD z = 0;
    for (std::size_t j = k; j < k + M; ++j) z += e[j + 2 * M] - 2 * e[j + M] + e[j];
    acc += z * z;
  }
  return acc / static_cast<LD>(6 * M);
}

// MTOTVAR with sub-sequences and terms every b samples (b = 1: SP 1065 eq. 27 itself).
LD mtotvar_oracle(const std::vector<double>& x, std::uint64_t m, double tau0, std::uint64_t b, std::uint64_t* runs) {
  std::vector<LD> blocks;
  for (std::size_t k = 0; (k + 1) * b <= x.size(); ++k) {
    LD s = 0;
    for (std::size_t t = 0; t < b; ++t) s += x[k * b + t];
    blocks.push_back(s);
  }
  const std::size_t M = m / b;
  LD sum = 0;
  *runs = 0;
  for (std::size_t n = 0; n + 3 * M <= blocks.size(); ++n, ++*runs)
    sum += subsequence_mean(std::vector<LD>(blocks.begin() + n, blocks.begin() + n + 3 * M));
  const LD tau = static_cast<LD>(m) * tau0;
  return sum / (*runs * 2 * static_cast<LD>(m) * m * tau * tau);
}

// HTOTVAR (SP 1065 section 5.2.14) on frequencies averaged over blocks of b samples.
LD htotvar_oracle(const std::vector<double>& x, std::uint64_t m, double tau0, std::uint64_t b, std::uint64_t* runs) {
  std::vector<LD> y;  // sums of b frequencies, times tau0
  for (std::size_t k = 0; (k + 1) * b < x.size(); ++k) y.push_back(static_cast<LD>(x[(k + 1) * b]) - x[k * b]);
  const std::size_t M = m / b;
  LD sum = 0;
  *runs = 0;
  for (std::size_t n = 0; n + 3 * M <= y.size(); ++n, ++*runs)
    sum += subsequence_mean(std::vector<LD>(y.begin() + n, y.begin() + n + 3 * M));
  const LD scale = static_cast<LD>(m) * tau0;
  return sum / (*runs * 6 * scale * scale);
}

// Theo1, SP 1065 eq. 30 with its own indices (i = 1..N-m, delta = 0..m/2-1), sub-sequences every
// `stride`.
LD theo1_oracle(const std::vector<double>& x, std::uint64_t m, double tau0, std::uint64_t stride = 1) {
  auto X = [&](std::size_t i) { return static_cast<LD>(x[i - 1]); };  // 1-based
  const std::size_t N = x.size();
  LD sum = 0;
  std::size_t starts = 0;
  for (std::size_t i = 1; i <= N - m; i += stride, ++starts)
    for (std::size_t d = 0; d < m / 2; ++d) {
      const LD t = (X(i) - X(i - d + m / 2)) + (X(i + m) - X(i + d + m / 2));
      sum += t * t / static_cast<LD>(m / 2 - d);
    }
  const LD tau = static_cast<LD>(m) * tau0;
  return sum / (0.75L * starts * tau * tau);
}

LD oavar_oracle(const std::vector<double>& x, std::uint64_t m, double tau0) {
  LD sum = 0;
  std::size_t n = 0;
  for (std::size_t i = 0; i + 2 * m < x.size(); ++i, ++n) {
    const LD t = static_cast<LD>(x[i + 2 * m]) - 2 * static_cast<LD>(x[i + m]) + x[i];
    sum += t * t;
  }
  const LD tau = static_cast<LD>(m) * tau0;
  return sum / (2 * n * tau * tau);
}

void expect_rel(double got, LD want, double tol, const char* what, std::uint64_t m) {
  EXPECT_NEAR(got / static_cast<double>(want), 1.0, tol) << what << " m=" << m;
}

TEST(Total, TotvarEqualsTheDefinition) {
  const auto x = record(257, 1);
  for (std::uint64_t m : {1u, 2u, 3u, 7u, 64u, 128u, 200u, 256u}) {
    const TotalVariance t = totvar(x, m, 0.5);
    EXPECT_EQ(t.n, 255u);
    expect_rel(t.var, totvar_oracle(x, m, 0.5), 1e-11, "totvar", m);
  }
  EXPECT_EQ(totvar(x, 257, 1.0).n, 0u);  // m > N - 1
  EXPECT_EQ(totvar(std::vector<double>{1, 2}, 1, 1.0).n, 0u);
}

TEST(Total, TotvarFromTheAvarTermsSumEqualsTheDefinition) {
  // The unreflected terms given as the overlapping AVAR's sum (oracle: that sum in long double from
  // its definition, SP 1065 eq. 25 for the whole), at every m the AVAR has.
  const auto x = record(257, 2);
  for (std::uint64_t m = 1; 2 * m <= x.size() - 1; ++m) {
    const LD tau = static_cast<LD>(m) * 0.5;
    const LD avar_terms = oavar_oracle(x, m, 0.5) * 2 * static_cast<LD>(x.size() - 2 * m) * tau * tau;
    const TotalVariance t = totvar_from_interior(x, m, 0.5, static_cast<double>(avar_terms));
    EXPECT_EQ(t.n, 255u);
    expect_rel(t.var, totvar_oracle(x, m, 0.5), 1e-11, "totvar from the AVAR's terms", m);
  }
  EXPECT_EQ(totvar_from_interior(x, 129, 0.5, 1.0).n, 0u);  // 2m > N - 1: no AVAR term
  EXPECT_EQ(totvar_from_interior(x, 4, 0.5, -1.0).n, 0u);
  EXPECT_EQ(totvar_from_interior(x, 4, 0.5, NAN).n, 0u);
}

TEST(Total, MtotvarAndTtotvarEqualTheDefinition) {
  const auto x = record(200, 2);
  std::vector<double> scratch(total_scratch_size(66, 1));
  for (std::uint64_t m : {1u, 2u, 3u, 5u, 8u, 21u, 66u}) {
    std::uint64_t runs = 0;
    const LD want = mtotvar_oracle(x, m, 2.0, 1, &runs);
    const TotalVariance t = mtotvar(x, 1, m, 2.0, scratch);
    EXPECT_EQ(t.n, 200 - 3 * m + 1) << m;
    EXPECT_EQ(t.n, runs);
    EXPECT_EQ(t.stride, 1u);
    expect_rel(t.var, want, 1e-10, "mtotvar", m);
  }
  EXPECT_EQ(mtotvar(x, 1, 67, 2.0, scratch).n, 0u);  // 3m > N
}

TEST(Total, DecimatedMtotvarAndHtotvarComputeTheirSubsetExactly) {
  const auto x = record(1001, 3);
  for (std::uint64_t b : {2u, 4u, 8u}) {
    for (std::uint64_t m : {2 * b, 4 * b, 16 * b}) {
      std::vector<double> scratch(total_scratch_size(m, b));
      std::uint64_t runs = 0;
      const LD mtot = mtotvar_oracle(x, m, 1.0, b, &runs);
      const TotalVariance t = mtotvar(x, b, m, 1.0, scratch);
      EXPECT_EQ(t.n, runs);
      EXPECT_EQ(t.stride, b);
      expect_rel(t.var, mtot, 1e-10, "decimated mtotvar", m);
      const LD htot = htotvar_oracle(x, m, 1.0, b, &runs);
      const TotalVariance h = htotvar(x, b, m, 1.0, scratch);
      EXPECT_EQ(h.n, runs);
      expect_rel(h.var, htot, 1e-10, "decimated htotvar", m);
    }
  }
  std::vector<double> scratch(100);
  EXPECT_EQ(mtotvar(x, 2, 6, 1.0, scratch).n, 0u);  // m / block odd
  EXPECT_EQ(mtotvar(x, 4, 6, 1.0, scratch).n, 0u);  // block does not divide m
}

TEST(Total, HtotvarEqualsTheDefinitionAndOverlappingHadamardAtOne) {
  const auto x = record(200, 4);
  std::vector<double> scratch(total_scratch_size(66, 1));
  for (std::uint64_t m : {2u, 3u, 5u, 8u, 21u, 66u}) {
    std::uint64_t runs = 0;
    const LD want = htotvar_oracle(x, m, 0.25, 1, &runs);
    const TotalVariance t = htotvar(x, 1, m, 0.25, scratch);
    EXPECT_EQ(t.n, 200 - 3 * m) << m;
    EXPECT_EQ(t.n, runs);
    expect_rel(t.var, want, 1e-10, "htotvar", m);
  }
  // m = 1: overlapping Hadamard variance, sum (x[i+3] - 3x[i+2] + 3x[i+1] - x[i])^2 / (6 n tau^2).
  LD sum = 0;
  for (std::size_t i = 0; i + 3 < x.size(); ++i) {
    const LD h = static_cast<LD>(x[i + 3]) - 3.0L * x[i + 2] + 3.0L * x[i + 1] - x[i];
    sum += h * h;
  }
  const TotalVariance one = htotvar(x, 1, 1, 0.25, scratch);
  EXPECT_EQ(one.n, 197u);
  expect_rel(one.var, sum / (6 * 197 * 0.0625L), 1e-11, "htotvar", 1);
}

TEST(Total, Theo1EqualsTheDefinition) {
  const auto x = record(301, 6);
  for (std::uint64_t m : {2u, 10u, 12u, 50u, 150u, 300u}) {
    const TotalVariance t = theo1(x, m, 1.5);
    EXPECT_EQ(t.n, (301 - m) * (m / 2)) << m;
    expect_rel(t.var, theo1_oracle(x, m, 1.5), 1e-11, "theo1", m);
  }
  for (std::uint64_t stride : {3u, 8u}) {
    const TotalVariance t = theo1(x, 100, 1.5, stride);
    EXPECT_EQ(t.stride, stride);
    expect_rel(t.var, theo1_oracle(x, 100, 1.5, stride), 1e-11, "strided theo1", 100);
  }
  EXPECT_EQ(theo1(x, 11, 1.0).n, 0u);   // odd
  EXPECT_EQ(theo1(x, 302, 1.0).n, 0u);  // beyond N - 1
}

TEST(Total, Theo1EqualsTheDefinitionOverSeveralBlocksOfWeights) {
  // theo1() takes the weights 1/k 8192 at a time and 8 k a step: h = m / 2 within one block, of
  // one block and one k, of one block and a remainder not a multiple of 8, every start and strided.
  const auto x = record(16600, 8);
  for (std::uint64_t m : {1038u, 16386u, 16410u, 16598u}) {
    const TotalVariance t = theo1(x, m, 0.5);
    EXPECT_EQ(t.n, (16600 - m) * (m / 2)) << m;
    expect_rel(t.var, theo1_oracle(x, m, 0.5), 1e-11, "theo1", m);
    const TotalVariance s = theo1(x, m, 0.5, 13);
    EXPECT_EQ(s.n, (16600 - m + 12) / 13 * (m / 2)) << m;
    expect_rel(s.var, theo1_oracle(x, m, 0.5, 13), 1e-11, "strided theo1", m);
  }
}

TEST(Total, Theo1EqualsTheDefinitionWithItsStartsFarApart) {
  // From a stride of 4096 on, theo1() sums a span of at most 16384 positions at a time, the spans
  // in periods of twice the stride: runs of k that end within the first span, cross several and end
  // on a span's border, one start or many, periods shorter than a span, as long, one and a half.
  // Phase values and counts (the analyzer's int32 record, converted as they load; on AVX-512 runs
  // of 32 k a step and a tail of fewer).
  const auto x = record(60000, 9);
  std::vector<std::int32_t> counts(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) counts[i] = static_cast<std::int32_t>(std::lround(x[i]));
  const std::vector<double> counted(counts.begin(), counts.end());
  const std::uint64_t cases[][2] = {{9000, 4096},  {40000, 4096},  {40000, 5001},  {32770, 8192},
                                    {59998, 4096}, {20000, 60000}, {50000, 12000}, {30000, 12289}};
  for (const auto& [m, stride] : cases) {
    const TotalVariance t = theo1(x, m, 0.5, stride), c = theo1(counts, m, 0.5, stride);
    EXPECT_EQ(t.n, (60000 - m + stride - 1) / stride * (m / 2)) << m;
    EXPECT_EQ(c.n, t.n) << m;
    expect_rel(t.var, theo1_oracle(x, m, 0.5, stride), 1e-11, "theo1, starts far apart", m);
    expect_rel(c.var, theo1_oracle(counted, m, 0.5, stride), 1e-11, "theo1 of counts, starts far apart", m);
  }
}

TEST(Total, TheoBiasRatioIsTheMeanOfAvarOverTheo1) {
  const auto x = record(400, 7);
  const TheoBiasRatio r = theo_bias_ratio(x, 1.0, 0, 1000);
  const std::uint64_t last = 400 / 6 - 3;  // n = floor(N / 6 - 3) = 63
  LD sum = 0;
  for (std::uint64_t i = 0; i <= last; ++i) sum += oavar_oracle(x, 9 + 3 * i, 1.0) / theo1_oracle(x, 12 + 4 * i, 1.0);
  EXPECT_TRUE(r.exact);
  EXPECT_EQ(r.taus, last + 1);
  EXPECT_EQ(r.defined, last + 1);
  EXPECT_NEAR(r.ratio / static_cast<double>(sum / (last + 1)), 1.0, 1e-11);
  // A subset: first and last taus always in it.
  const TheoBiasRatio some = theo_bias_ratio(x, 1.0, 0, 2);
  EXPECT_FALSE(some.exact);
  const LD two = (oavar_oracle(x, 9, 1.0) / theo1_oracle(x, 12, 1.0) +
                  oavar_oracle(x, 9 + 3 * last, 1.0) / theo1_oracle(x, 12 + 4 * last, 1.0)) /
                 2;
  EXPECT_NEAR(some.ratio / static_cast<double>(two), 1.0, 1e-11);
  EXPECT_EQ(theo_bias_ratio(record(23, 1), 1.0, 0, 10).taus, 0u);  // n < 1
  EXPECT_EQ(theo_bias_ratio(record(24, 1), 1.0, 0, 10).taus, 1u);  // n = 1, whose AVAR (m = 12) needs 25 points
}

TEST(Total, TheoBiasRatioOnARowRunnerIsTheSameBits) {
  // Oracle: the ratio with no runner (its taus in turn). A runner may run the taus in any order
  // (rows.hpp): this one runs each batch backwards and counts them. The taus are summed in order
  // all the same, so the ratio is the same bits; 150 taus make three batches of at most 64.
  struct Backwards final : RowRunner {
    mutable std::size_t rows = 0;
    void run(const Rows& r, std::size_t count) const override {
      for (std::size_t i = count; i-- > 0;) r.row(i);
      rows += count;
    }
  } backwards;
  const auto x = record(940, 8);
  const TheoBiasRatio in_turn = theo_bias_ratio(x, 1.0, 4, 150), run = theo_bias_ratio(x, 1.0, 4, 150, &backwards);
  EXPECT_EQ(in_turn.taus, 150u);
  EXPECT_EQ(backwards.rows, 150u);
  EXPECT_EQ(run.taus, in_turn.taus);
  EXPECT_EQ(run.ratio, in_turn.ratio);
  EXPECT_GT(run.ratio, 0.0);
}

TEST(Total, TheoHSwitchIsTheLargestOctaveWithinTenPercent) {
  EXPECT_EQ(theoh_switch(1001), 64u);   // 100 samples: 64
  EXPECT_EQ(theoh_switch(1281), 128u);  // 128 exactly
  EXPECT_EQ(theoh_switch(5), 1u);
  EXPECT_EQ(theoh_switch(10000001), 524288u);
}

TEST(Total, DecimatedMtotvarSumsItsBlocksAWindowAtATime) {
  // Three windows of block sums (total_window starts each) and a part of one: the oracle is the
  // definition on the blocks (mtotvar_oracle), as with one window above.
  const auto x = record(2 * (2 * total_window + 1000) + 7, 5);
  for (std::uint64_t m : {4u, 8u}) {
    std::vector<double> scratch(total_scratch_size(m, 2));
    std::uint64_t runs = 0;
    const LD want = mtotvar_oracle(x, m, 1.0, 2, &runs);
    const TotalVariance t = mtotvar(x, 2, m, 1.0, scratch);
    EXPECT_EQ(t.n, runs);
    EXPECT_EQ(t.n, x.size() / 2 - 3 * m / 2 + 1);
    expect_rel(t.var, want, 1e-10, "windowed mtotvar", m);
    scratch.pop_back();  // one double short: refused, not overrun
    EXPECT_EQ(mtotvar(x, 2, m, 1.0, scratch).n, 0u);
  }
}

TEST(Total, TheDecimationPlan) {
  // Exact below the budget (2^26 operations), m <= S or S = 0; the cost is 15 m (N - 3m + 1).
  EXPECT_EQ(total_block(1024, 1001, 16), 1u);  // cannot be formed, exact (cost 0)
  EXPECT_EQ(total_block(128, 100000, 0), 1u);
  EXPECT_EQ(total_block(16, 10000000, 16), 1u);  // m <= S
  EXPECT_EQ(total_block(256, 100000, 16), 16u);  // 15 * 256 * 99233 = 3.8e8 > 2^26
  EXPECT_EQ(total_block(4096, 1000000, 0), 1u);
  EXPECT_EQ(total_block(4096, 1000000, 16), 256u);  // 2^26 < 15 * 4096 * 987713
  EXPECT_EQ(total_block(96, 10000000, 16), 4u);     // b <= 96 / 16 = 6, a power of two, 96 / b even
  EXPECT_EQ(total_block(99, 10000000, 16), 1u);     // odd m: only the exact estimator
  EXPECT_EQ(theo1_stride(16, 10000000, 16), 1u);
  EXPECT_EQ(theo1_stride(1000, 10000000, 16), 62u);
  EXPECT_EQ(theo1_stride(1000, 1001, 16), 1u);  // (1001 - 1000) * 500: exact
  EXPECT_EQ(theo_bias_taus(1001, 16), 164u);    // all n + 1 = floor(1001/6 - 3) + 1, exact cost 1.5e7
  EXPECT_EQ(theo_bias_taus(100000, 16), 64u);
  EXPECT_EQ(theo_bias_taus(100000, 0), 16664u);
  EXPECT_EQ(theo_bias_taus(23, 0), 0u);
}

TEST(Total, EdfFormulasOfSp1065) {
  // Table 7 and 8 rows at N = 1001, m = 16 (b N/m - c).
  EXPECT_NEAR(edf_totvar(0, 1001, 16), 1.5 * 1001 / 16, 1e-12);
  EXPECT_NEAR(edf_totvar(-2, 1001, 16), 0.93 * 1001 / 16 - 0.36, 1e-12);
  EXPECT_EQ(edf_totvar(1, 1001, 16), 0.0);
  EXPECT_NEAR(edf_mtotvar(2, 1001, 16), 1.90 * 1001 / 16 - 2.1, 1e-12);
  EXPECT_NEAR(edf_mtotvar(-1, 1001, 16), 0.85 * 1001 / 16 - 0.50, 1e-12);
  EXPECT_NEAR(edf_htotvar(0, 1001, 32), (1001.0 / 32) / (0.559 + 1.004 * 32 / 1001), 1e-12);
  // Theo1 white FM (table 11): ((4.1 N + 0.8)/r - (3.1 N + 6.5)/N) r^1.5 / (r^1.5 + 5.2), r = 0.75 m.
  const double r = 7.5;
  EXPECT_NEAR(edf_theo1(0, 1001, 10),
              ((4.1 * 1001 + 0.8) / r - (3.1 * 1001 + 6.5) / 1001) * std::pow(r, 1.5) / (std::pow(r, 1.5) + 5.2), 1e-9);
  EXPECT_EQ(edf_theo1(-3, 1001, 10), 0.0);
}

}  // namespace
}  // namespace gyrochar
