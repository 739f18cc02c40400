// Exact Theo1 and MTOTVAR from lag sums (core/include/gyrochar/total_fast.hpp). Theo1 against its
// definition summed in long double at every even m of small records (and n against the direct theo1
// of total.hpp); TheoBR's bias ratio against theo_bias_ratio with every tau exact; the FFT against
// the DFT written out; MTOTVAR against its definition in long double at every m (below). Each
// tolerance is the rounding bound of the lag-sum form (`tolerance`, `mtot_tolerance`). Records:
// white phase plus a random walk plus offset and drift, a quadratic drift, and a 1e-3 ramp with
// 1e-12 noise (where expanding raw phase products fails).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <complex>
#include <cstdint>
#include <numbers>
#include <random>
#include <vector>

#include "gyrochar/total.hpp"
#include "gyrochar/total_fast.hpp"
#include "gyrochar/total_lags.hpp"

namespace gyrochar {
namespace {

std::vector<double> record(std::size_t n, std::uint64_t seed, double walk_step, double white, double drift,
                           double curvature) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> z;
  std::vector<double> x(n);
  double walk = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double t = static_cast<double>(i);
    walk += walk_step * z(rng);
    x[i] = 1e3 + drift * t + curvature * t * t + walk + white * z(rng);
  }
  return x;
}

// Theo1 by its definition (SP 1065 eq. 30, as total.hpp states it), summed in long double.
long double theo1_oracle(const std::vector<double>& x, std::uint64_t m) {
  using LD = long double;
  const std::size_t N = x.size();
  LD sum = 0;
  for (std::size_t i = 0; i + m < N; ++i)
    for (std::size_t k = 1; k <= m / 2; ++k) {
      const LD t = (LD(x[i]) - x[i + k]) - (LD(x[i + m - k]) - x[i + m]);
      sum += t * t / LD(k);
    }
  const LD md = LD(m);
  return sum / (0.75L * LD(N - m) * md * md);
}

// The tolerance of theo1_fast at m (tau0 = 1; docs/total.md, "Rounding"), two parts:
// - the lag sums: 64 units of rounding times log2 of the FFT length times H(m / 2) times 8 sum r^2,
//   scaled like the estimate, plus 2^-48 of the estimate (r held in double, each value to 2^-53);
// - the residual: r[i] = (x[i] - x[0]) - q(i) in long double carries up to e = 2^-61 (|x[i] - x[0]|
//   + |q(i)|); Theo1 of an error sequence bounded by e is at most V_e = 16 e^2 H(m/2) / (0.75 m^2),
//   and moves the estimate V by at most 2 sqrt(V V_e) + V_e.
double tolerance(const std::vector<double>& x, const Theo1Workspace& w, std::uint64_t m, double estimate) {
  double r2 = 0, e = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const long double d = static_cast<long double>(x[i]) - x[0];
    r2 += w.r[i] * w.r[i];
    e = std::max(e, 0x1p-61 * static_cast<double>(std::abs(d) + std::abs(d - w.r[i])));
  }
  double harmonic = 0;
  for (std::uint64_t k = 1; k <= m / 2; ++k) harmonic += 1.0 / static_cast<double>(k);
  const double L = static_cast<double>(w.r.size() - m), md = static_cast<double>(m);
  const double lag_sums = 64.0 * 0x1p-53 * std::log2(static_cast<double>(w.P)) * harmonic * 8.0 * r2 / (0.75 * L * md * md);
  const double ve = 16.0 * e * e * harmonic / (0.75 * md * md);
  return lag_sums + 0x1p-48 * std::abs(estimate) + 2.0 * std::sqrt(std::abs(estimate) * ve) + ve;
}

// The m a sweep checks, `last` being the sweep's largest: every one natively. Under an emulator
// (GYROCHAR_EMULATED, about 17 times slower, long double in software on aarch64) every m up to 32,
// every 97th beyond and the last six: the oracles' cost grows with m, so the long records' sweeps
// cost a few percent of the native ones, with the small and the largest m all kept.
bool checked_m(std::size_t m, std::size_t last) {
#ifdef GYROCHAR_EMULATED
  return m <= 32 || m % 97 == 0 || m + 6 > last;
#else
  (void)m, (void)last;
  return true;
#endif
}

void every_m(const std::vector<double>& x, const char* what) {
  std::vector<double> work(theo1_workspace_size(x.size()));
  Theo1Workspace w = theo1_prepare(x, work);
  ASSERT_TRUE(w.ready);
  double worst = 0;  // the largest error relative to the estimate, reported
  for (std::uint64_t m = 2; m <= x.size() - 1; m += 2) {
    if (!checked_m(m, x.size() - 1)) continue;
    const double oracle = static_cast<double>(theo1_oracle(x, m));
    const TotalVariance direct = theo1(x, m, 1.0, 1), fast = theo1_fast(w, m, 1.0);
    ASSERT_GT(direct.n, 0u);
    EXPECT_EQ(fast.n, direct.n) << what << " m=" << m;
    EXPECT_EQ(fast.stride, 1u);
    EXPECT_NEAR(fast.var, oracle, tolerance(x, w, m, oracle)) << what << " N=" << x.size() << " m=" << m;
    worst = std::max(worst, std::abs(fast.var / oracle - 1));
  }
  ::testing::Test::RecordProperty(std::string(what) + "_worst_relative", std::to_string(worst));
  std::printf("%s N=%zu: worst relative error %.2e\n", what, x.size(), worst);
}

TEST(TotalFast, Theo1EqualsTheDirectSumAtEveryEvenM) {
  for (const std::size_t n : {3u, 4u, 30u, 31u, 97u, 256u, 1000u, 2000u})
    every_m(record(n, n, 0.3, 1.0, 2.5, 0.0), "walk+white+drift");
}

TEST(TotalFast, Theo1EqualsTheDirectSumUnderStrongDrift) {
  // A 1e-3 ramp with 1e-12 white noise: products of raw phase values would lose all 16 digits.
  every_m(record(1500, 7, 0.0, 1e-12, 1e-3, 0.0), "ramp");
  // A frequency drift (quadratic phase) over random-walk FM: the quadratic comes back exactly.
  std::vector<double> x = record(1200, 8, 0.0, 1e-9, 1e-3, 1e-6);
  double y = 0;
  std::mt19937_64 rng(9);
  std::normal_distribution<double> z;
  for (std::size_t i = 0; i < x.size(); ++i) {
    y += 1e-9 * z(rng);
    x[i] += y * static_cast<double>(i);
  }
  every_m(x, "quadratic+rwfm");
}

std::vector<double> values(const std::string& path) {
  std::ifstream in(path);
  EXPECT_TRUE(in) << path;
  std::vector<double> v;
  for (std::string line; std::getline(in, line);)
    if (!line.empty() && line[0] != '#') v.push_back(std::stod(line));
  return v;
}

TEST(TotalFast, Theo1EqualsTheDefinitionOnTheReferenceRecords) {
  const std::string ref = GYROCHAR_TEST_DATA;
  every_m(values(ref + "/phasedat/PHASE.DAT"), "PHASE.DAT");
  // The OCXO's frequencies (tests/data/ocxo) as phase, x[k+1] = x[k] + (f - 1e7) / 1e7: a drifting
  // oscillator. Its first 1500 points (the oracle's cost grows as N^3 over every m).
  std::vector<double> x{0.0};
  for (const double f : values(ref + "/ocxo/ocxo_frequency.txt"))
    if (x.size() < 1500) x.push_back(x.back() + (f - 1e7) / 1e7);
  every_m(x, "ocxo");
}

TEST(TotalFast, TheoBiasRatioEqualsTheExactOne) {
  // Oracle: theo_bias_ratio with S = 0 (every tau, each Theo1 and AVAR exact, direct sums).
  for (const std::size_t n : {24u, 60u, 301u, 1000u}) {
    const std::vector<double> x = record(n, 100 + n, 0.3, 1.0, 2.5, 0.0);
    std::vector<double> work(theo1_workspace_size(n));
    Theo1Workspace w = theo1_prepare(x, work);
    const TheoBiasRatio direct = theo_bias_ratio(x, 1.0, 0, ~0ull), fast = theo_bias_ratio_fast(x, w, 1.0, ~0ull);
    ASSERT_GT(direct.taus, 0u);
    EXPECT_EQ(fast.taus, direct.taus);
    EXPECT_EQ(fast.defined, direct.defined);
    EXPECT_TRUE(fast.exact);
    EXPECT_NEAR(fast.ratio, direct.ratio, 1e-9 * direct.ratio) << n;  // rounding of a mean of ratios
    // A subset of taus: the same indices as the direct estimator's decimated call spreads.
    const TheoBiasRatio few = theo_bias_ratio_fast(x, w, 1.0, 3);
    EXPECT_EQ(few.taus, std::min<std::uint64_t>(3, direct.taus));
  }
}

TEST(TotalFast, Theo1InPiecesOnBuffersOfTheirOwnIsTheSameBits) {
  // Oracle: theo1_fast. Its pieces, each on a copy of the workspace with an FFT buffer of its own
  // (as a thread each would run them), in another order, combined: the same bits at every even m,
  // the smallest (no triangle square by FFT) to N - 1 (the largest triangles, ends meeting).
  const std::vector<double> x = record(3000, 9, 0.3, 1.0, 2.5, 1e-4);
  std::vector<double> work(theo1_workspace_size(x.size()));
  Theo1Workspace w = theo1_prepare(x, work);
  ASSERT_TRUE(w.ready);
  std::vector<double> other_buffer(w.buffer.size()), third_buffer(w.buffer.size());
  Theo1Workspace other = w, third = w;
  other.buffer = other_buffer, third.buffer = third_buffer;
  for (std::uint64_t m = 2; m <= x.size() - 1; m += m < 64 ? 2 : 98) {
    Theo1Pieces p;
    theo1_piece(other, m, 2, p);
    theo1_piece(third, m, 1, p);
    theo1_piece(w, m, 0, p);
    const TotalVariance fast = theo1_fast(w, m, 1.0), pieces = theo1_from_pieces(w, m, 1.0, p);
    EXPECT_EQ(pieces.var, fast.var) << m;
    EXPECT_EQ(pieces.n, fast.n) << m;
  }
  Theo1Pieces untouched;
  theo1_piece(w, 11, 0, untouched);  // odd m: nothing written, no estimate
  EXPECT_EQ(untouched.sums, 0.0);
  EXPECT_EQ(theo1_from_pieces(w, 11, 1.0, untouched).n, 0u);
}

// Rows in reverse order, as no thread would run them in turn: each row's work must not depend on
// another's.
class ReverseRows final : public RowRunner {
 public:
  void run(const Rows& rows, std::size_t count) const override {
    for (std::size_t i = count; i-- > 0;) rows.row(i);
  }
};

TEST(TotalFast, ThePreparationsFftAsRowsIsTheSameBits) {
  // Oracle: theo1_prepare in turn. On a runner (rows in reverse order), its transforms (2^15
  // complex points: the split into halves and quarters applies from 4 x 2048) give the same
  // autocorrelation to the last bit at every lag.
  const std::vector<double> x = record(20000, 12, 0.3, 1.0, 2.5, 1e-4);
  std::vector<double> a(theo1_workspace_size(x.size())), b(a.size());
  const ReverseRows reverse;
  const Theo1Workspace in_turn = theo1_prepare(x, a), as_rows = theo1_prepare(x, b, &reverse);
  ASSERT_TRUE(in_turn.ready && as_rows.ready);
  ASSERT_GE(in_turn.P / 2, 4u * 2048u);
  std::size_t differ = 0;
  for (std::size_t d = 0; d < x.size(); ++d) differ += in_turn.ac[d] != as_rows.ac[d];
  EXPECT_EQ(differ, 0u);
}

TEST(MtotFast, InPiecesOnBuffersOfTheirOwnIsTheSameBits) {
  // Oracle: mtotvar_fast (htotvar_fast). Its two pieces, piece 1 on a copy of the workspace with an
  // FFT buffer and scratch of its own, in reverse order, combined: the same bits at every m from 1
  // to N / 3 (the largest: the fixed terms by three autocorrelation sums), the record curved (the
  // quadratic's terms).
  const std::vector<double> x = record(3000, 10, 0.3, 1.0, 2.5, 1e-4);
  std::vector<double> work(theo1_workspace_size(x.size())), scratch(mtotvar_scratch_size(x.size()));
  Theo1Workspace w = theo1_prepare(x, work);
  ASSERT_TRUE(w.ready);
  ASSERT_NE(w.curvature, 0.0);
  std::vector<double> other_buffer(w.buffer.size()), other_scratch(scratch.size());
  Theo1Workspace other = w;
  other.buffer = other_buffer;
  for (std::uint64_t m = 1; 3 * m <= x.size(); m += m < 40 ? 1 : 97) {
    MtotPieces p;
    mtotvar_piece(other, other_scratch, m, 1, p);
    mtotvar_piece(w, scratch, m, 0, p);
    const TotalVariance fast = mtotvar_fast(w, scratch, m, 1.0), pieces = mtotvar_from_pieces(w, m, 1.0, p);
    EXPECT_EQ(pieces.var, fast.var) << m;
    EXPECT_EQ(pieces.n, fast.n) << m;
  }
  MtotPieces last;
  mtotvar_piece(other, other_scratch, 1000, 1, last);
  mtotvar_piece(w, scratch, 1000, 0, last);
  EXPECT_EQ(mtotvar_from_pieces(w, 1000, 1.0, last).var, mtotvar_fast(w, scratch, 1000, 1.0).var);  // 3m = N
  // HTOTVAR: the same kernel on the frequencies.
  std::vector<double> y(x.size() - 1);
  for (std::size_t i = 0; i + 1 < x.size(); ++i) y[i] = x[i + 1] - x[i];
  Theo1Workspace f = theo1_prepare(y, work);
  Theo1Workspace f_other = f;
  f_other.buffer = other_buffer;
  for (const std::uint64_t m : {2u, 17u, 333u, 999u}) {
    MtotPieces p;
    mtotvar_piece(f_other, other_scratch, m, 1, p);
    mtotvar_piece(f, scratch, m, 0, p);
    EXPECT_EQ(htotvar_from_pieces(f, m, 1.0, p).var, htotvar_fast(f, scratch, m, 1.0).var) << m;
  }
  MtotPieces untouched;
  mtotvar_piece(w, scratch, 1001, 0, untouched);  // 3m > N: nothing written, no estimate
  EXPECT_EQ(untouched.moving, 0.0L);
  EXPECT_EQ(mtotvar_from_pieces(w, 1001, 1.0, untouched).n, 0u);
}

TEST(TotalFast, UndefinedInputGivesNoTerms) {
  const std::vector<double> x = record(40, 1, 0.3, 1.0, 2.5, 0.0);
  std::vector<double> work(theo1_workspace_size(x.size()));
  Theo1Workspace w = theo1_prepare(x, work);
  EXPECT_EQ(theo1_fast(w, 3, 1.0).n, 0u);  // odd m
  EXPECT_EQ(theo1_fast(w, 0, 1.0).n, 0u);
  EXPECT_EQ(theo1_fast(w, 40, 1.0).n, 0u);  // m > N - 1
  EXPECT_EQ(theo1_fast(w, 10, 0.0).n, 0u);  // tau0 <= 0
  std::vector<double> small(theo1_workspace_size(x.size()) - 1);
  Theo1Workspace none = theo1_prepare(x, small);
  EXPECT_FALSE(none.ready);
  EXPECT_EQ(theo1_fast(none, 10, 1.0).n, 0u);
  EXPECT_FALSE(theo1_prepare(std::vector<double>{1, 2}, work).ready);  // N < 3
}

TEST(TotalFast, FftEqualsTheDftWrittenOut) {
  // Oracle: X_k = sum_p x_p exp(-+2 pi i k p / n) summed directly in long double.
  const std::size_t P = 64;
  std::vector<double> tw(2 * P);
  fft_twiddles(tw, P);
  std::mt19937_64 rng(3);
  std::normal_distribution<double> z;
  for (const std::size_t n : {1u, 2u, 8u, 64u})
    for (const bool inverse : {false, true}) {
      std::vector<double> d(2 * n), in;
      for (double& v : d) v = z(rng);
      in = d;
      fft(d, n, tw, inverse);
      for (std::size_t k = 0; k < n; ++k) {
        std::complex<long double> sum = 0;
        for (std::size_t p = 0; p < n; ++p) {
          const long double a = (inverse ? 2 : -2) * std::numbers::pi_v<long double> * static_cast<long double>(k * p) / n;
          sum += std::complex<long double>(in[2 * p], in[2 * p + 1]) * std::polar(1.0L, a);
        }
        EXPECT_NEAR(d[2 * k], static_cast<double>(sum.real()), 1e-13) << n << " k=" << k;
        EXPECT_NEAR(d[2 * k + 1], static_cast<double>(sum.imag()), 1e-13) << n << " k=" << k;
      }
    }
}

TEST(TotalFast, FftEqualsTheDftWrittenOutBeyondTheWholeStages) {
  // Lengths whose stages above 2^16 take their twiddles as products from the table's two short
  // lists, one such stage alone (2^17) and two in one pass (2^18). Oracle: the DFT summed directly
  // in long double at 97 outputs (7 under an emulator), exp(-+2 pi i j / n) from a table of
  // std::polar in long double.
  // Bound: an FFT's error is at most a few units of rounding times log2 n times the norm of its
  // output, sqrt(n) times that of its input; 8 log2(n) 2^-53 sqrt(n) |x|_2.
  const std::size_t P = 1u << 18;
#ifdef GYROCHAR_EMULATED
  const std::size_t outputs = 7;  // long double is software arithmetic under qemu-aarch64
#else
  const std::size_t outputs = 97;
#endif
  std::vector<double> tw(fft_twiddle_size(P));
  EXPECT_LT(tw.size(), 2 * P);
  fft_twiddles(tw, P);
  std::mt19937_64 rng(4);
  std::normal_distribution<double> z;
  for (const std::size_t n : {1u << 17, 1u << 18})
    for (const bool inverse : {false, true}) {
      std::vector<double> d(2 * n), in;
      double norm = 0;
      for (double& v : d) v = z(rng), norm += v * v;
      in = d;
      fft(d, n, tw, inverse);
      std::vector<std::complex<long double>> cis(n);
      for (std::size_t j = 0; j < n; ++j)
        cis[j] = std::polar(1.0L, (inverse ? 2 : -2) * std::numbers::pi_v<long double> * static_cast<long double>(j) / n);
      const double bound = 8.0 * std::log2(static_cast<double>(n)) * 0x1p-53 * std::sqrt(static_cast<double>(n) * norm);
      for (std::size_t k = 0; k < n; k += n / outputs + 1) {  // every part of the spectrum
        std::complex<long double> sum = 0;
        for (std::size_t p = 0; p < n; ++p) sum += std::complex<long double>(in[2 * p], in[2 * p + 1]) * cis[k * p % n];
        EXPECT_NEAR(d[2 * k], static_cast<double>(sum.real()), bound) << n << " k=" << k;
        EXPECT_NEAR(d[2 * k + 1], static_cast<double>(sum.imag()), bound) << n << " k=" << k;
      }
    }
}

// ---- Exact MTOTVAR from lag sums (mtotvar_fast) against MTOTVAR's definition summed in long double
// at every m of small records (and n against the direct mtotvar of total.hpp). Records as above, plus
// pure white phase and a pure random walk.

// MTOTVAR by its definition (SP 1065 eq. 27 with Stable32's half-average slope, as total.hpp states
// it), in long double: each 3m-point window detrended, reflected to 9m points, every one of the 6m
// modified-Allan terms summed out.
long double mtotvar_oracle(const std::vector<double>& x, std::size_t m) {
  using LD = long double;
  const std::size_t N = x.size(), len = 3 * m, half = len / 2;
  std::vector<LD> e(9 * m), E(9 * m + 1);
  LD total = 0;
  for (std::size_t n = 0; n + len <= N; ++n) {
    LD first = 0, second = 0;
    for (std::size_t t = 0; t < half; ++t) first += x[n + t], second += x[n + len - half + t];
    const LD slope = (second - first) / LD(half) / LD(len - half);
    for (std::size_t t = 0; t < len; ++t) {
      const LD u = LD(x[n + t]) - x[n] - slope * LD(t);
      e[len - 1 - t] = u, e[len + t] = u, e[3 * len - 1 - t] = u;
    }
    E[0] = 0;
    for (std::size_t i = 0; i < 9 * m; ++i) E[i + 1] = E[i] + e[i];
    LD window = 0;
    for (std::size_t k = 0; k < 6 * m; ++k) {
      const LD z = (E[k + 3 * m] - E[k + 2 * m]) - 2 * (E[k + 2 * m] - E[k + m]) + (E[k + m] - E[k]);
      window += z * z;
    }
    total += window / LD(6 * m);
  }
  const LD md = LD(m);
  return total / (LD(N - len + 1) * 2 * md * md * md * md);
}

// The tolerance of mtotvar_fast at m (tau0 = 1; docs/total.md, "Rounding"), two parts:
// - the lag sums: the estimate is the sum over lags of the residual's autocorrelation (each lag's
//   FFT error below a few units of 2^-53 log2(P) sum r^2) times the kernel's autocorrelation A(d),
//   whose absolute sum is at most 2 len A(0), A(0) = sum_k |g_k|^2 <= 6m len 16 (no coefficient of a
//   term above 4 in size), less the end windows (of the same order); scaled like the estimate, a
//   factor 64 for the constants not counted, and 2^-44 of the estimate for the sums;
// - the residual: r[i] = (x[i] - x[0]) - q(i) in long double carries up to e = 2^-61 (|x[i] - x[0]|
//   + |q(i)|); each z_k of an error sequence bounded by e is at most 48 m e (sum_t |g_k[t]| <= 48 m),
//   so its MTOTVAR is at most V_e = (48 m e)^2 / (2 m^4), and it moves the estimate V by at most
//   2 sqrt(V V_e) + V_e.
double mtot_tolerance(const std::vector<double>& x, const Theo1Workspace& w, std::size_t m, double estimate) {
  double r2 = 0, e = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const long double d = static_cast<long double>(x[i]) - x[0];
    r2 += w.r[i] * w.r[i];
    e = std::max(e, 0x1p-61 * static_cast<double>(std::abs(d) + std::abs(d - w.r[i])));
  }
  const double md = static_cast<double>(m), len = 3 * md, windows = static_cast<double>(w.r.size()) - len + 1;
  const double a0 = 6 * md * len * 16;
  const double lag_sums = 64.0 * 0x1p-53 * std::log2(static_cast<double>(w.P)) * 2 * len * a0 * r2;
  const double ve = (48 * md * e) * (48 * md * e) / (2 * md * md * md * md);
  return lag_sums / (6 * md * windows * 2 * md * md * md * md) + 0x1p-44 * std::abs(estimate) +
         2.0 * std::sqrt(std::abs(estimate) * ve) + ve;
}

double mtot_every_m(const std::vector<double>& x, const char* what) {
  std::vector<double> work(theo1_workspace_size(x.size())), scratch(mtotvar_scratch_size(x.size()));
  std::vector<double> direct_scratch(total_scratch_size(x.size() / 3, 1));
  Theo1Workspace w = theo1_prepare(x, work);
  EXPECT_TRUE(w.ready);
  double worst = 0;  // the largest error relative to the estimate, reported
  for (std::size_t m = 1; 3 * m <= x.size(); ++m) {
    if (!checked_m(m, x.size() / 3)) continue;
    const double oracle = static_cast<double>(mtotvar_oracle(x, m));
    const TotalVariance direct = mtotvar(x, 1, m, 1.0, direct_scratch), fast = mtotvar_fast(w, scratch, m, 1.0);
    EXPECT_GT(direct.n, 0u);
    EXPECT_EQ(fast.n, direct.n) << what << " m=" << m;
    EXPECT_EQ(fast.stride, 1u);
    EXPECT_NEAR(fast.var, oracle, mtot_tolerance(x, w, m, oracle)) << what << " N=" << x.size() << " m=" << m;
    worst = std::max(worst, std::abs(fast.var / oracle - 1));
  }
  std::printf("%s N=%zu: worst relative error %.2e\n", what, x.size(), worst);
  return worst;
}

TEST(MtotFast, EqualsTheDefinitionAtEveryM) {
  for (const std::size_t n : {3u, 4u, 5u, 6u, 7u, 8u, 12u, 31u, 97u, 256u, 1000u})
    mtot_every_m(record(n, n, 0.3, 1.0, 2.5, 0.0), "walk+white+drift");
  mtot_every_m(record(2000, 11, 0.0, 1.0, 0.0, 0.0), "white");
  mtot_every_m(record(2000, 12, 1.0, 0.0, 0.0, 0.0), "walk");
}

TEST(MtotFast, EqualsTheDefinitionUnderStrongDrift) {
  // A 1e-3 ramp with 1e-12 white noise: products of raw phase values would lose all 16 digits (the
  // direct double-precision mtotvar loses most of them too; the oracle is in long double).
  mtot_every_m(record(1500, 7, 0.0, 1e-12, 1e-3, 0.0), "ramp");
  // A frequency drift (quadratic phase) over a random walk: the quadratic comes back exactly.
  mtot_every_m(record(1200, 8, 1e-6, 0.0, 1e-3, 1e-6), "quadratic+walk");
}

TEST(MtotFast, EqualsTheDefinitionOnPhaseDat) {
  mtot_every_m(values(std::string(GYROCHAR_TEST_DATA) + "/phasedat/PHASE.DAT"), "PHASE.DAT");
}

// HTOTVAR by lag sums (htotvar_fast on the prepared frequencies) at every m >= 2. Oracle: MTOTVAR's
// definition in long double on the frequencies y (HTOTVAR's sub-sequences and terms are MTOTVAR's on
// y; the scales differ by m^2 / 3 at tau0 = 1: z^2 / (6 m^2) against z^2 / (2 m^4)), with
// mtot_tolerance's bound on y scaled the same; n against the direct htotvar of total.hpp.
void htot_every_m(const std::vector<double>& x, const char* what) {
  std::vector<double> y(x.size() - 1);
  for (std::size_t i = 0; i + 1 < x.size(); ++i) y[i] = x[i + 1] - x[i];
  std::vector<double> work(theo1_workspace_size(y.size())), scratch(mtotvar_scratch_size(y.size()));
  std::vector<double> direct_scratch(total_scratch_size(y.size() / 3, 1));
  Theo1Workspace w = theo1_prepare(y, work);
  ASSERT_TRUE(w.ready);
  double worst = 0;
  for (std::size_t m = 2; 3 * m <= y.size(); ++m) {
    if (!checked_m(m, y.size() / 3)) continue;
    const double scale = static_cast<double>(m * m) / 3.0;
    const double oracle = static_cast<double>(mtotvar_oracle(y, m)) * scale;
    const TotalVariance direct = htotvar(x, 1, m, 1.0, direct_scratch), fast = htotvar_fast(w, scratch, m, 1.0);
    EXPECT_GT(direct.n, 0u);
    EXPECT_EQ(fast.n, direct.n) << what << " m=" << m;
    EXPECT_EQ(fast.stride, 1u);
    EXPECT_NEAR(fast.var, oracle, scale * mtot_tolerance(y, w, m, oracle / scale))
        << what << " N=" << x.size() << " m=" << m;
    worst = std::max(worst, std::abs(fast.var / oracle - 1));
  }
  EXPECT_EQ(htotvar_fast(w, scratch, 1, 1.0).n, 0u);  // m = 1: the overlapping Hadamard variance, not this kernel
  std::printf("%s N=%zu: HTOTVAR worst relative error %.2e\n", what, x.size(), worst);
}

TEST(HtotFast, EqualsTheDefinitionAtEveryM) {
  for (const std::size_t n : {7u, 8u, 12u, 31u, 97u, 400u, 1500u})
    htot_every_m(record(n, 50 + n, 0.3, 1.0, 2.5, 0.0), "walk+white+drift");
  htot_every_m(record(1200, 8, 1e-6, 0.0, 1e-3, 1e-6), "quadratic+walk");
  htot_every_m(values(std::string(GYROCHAR_TEST_DATA) + "/phasedat/PHASE.DAT"), "PHASE.DAT");
}

TEST(MtotFast, UndefinedInputGivesNoTerms) {
  const std::vector<double> x = record(40, 1, 0.3, 1.0, 2.5, 0.0);
  std::vector<double> work(theo1_workspace_size(x.size())), scratch(mtotvar_scratch_size(x.size()));
  Theo1Workspace w = theo1_prepare(x, work);
  EXPECT_GT(mtotvar_fast(w, scratch, 13, 1.0).n, 0u);  // 3m = 39 <= N
  EXPECT_EQ(mtotvar_fast(w, scratch, 14, 1.0).n, 0u);  // 3m > N
  EXPECT_EQ(mtotvar_fast(w, scratch, 0, 1.0).n, 0u);
  EXPECT_EQ(mtotvar_fast(w, scratch, 4, 0.0).n, 0u);  // tau0 <= 0
  EXPECT_EQ(mtotvar_fast(w, std::span<double>(scratch).first(scratch.size() - 1), 4, 1.0).n, 0u);
  std::vector<double> small(theo1_workspace_size(x.size()) - 1);
  Theo1Workspace none = theo1_prepare(x, small);
  EXPECT_EQ(mtotvar_fast(none, scratch, 4, 1.0).n, 0u);
}

// A counter's phase read three ways (total.hpp, PhaseSpan): as doubles, as int64 pulses and as
// int32 residuals from the line of the first count, as the analyzer holds them. Oracle: the doubles
// (each estimator is tested against its definition above). The int64 phase converts to the same
// doubles: the same bits. The statistics are blind to a line: the residuals give the same
// variances to the rounding of the doubles path, whose terms are differences of values near 3e6
// (2^-53 of 3e6 against terms of order 10: below 1e-10 relative; the tolerance is 1e-9).
TEST(TotalFast, CountsAndTheirResidualsFromALineGiveThePhasesVariances) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> z;
  constexpr std::size_t N = 3001;
  std::vector<std::int64_t> pulses(N);
  std::vector<std::int32_t> residuals(N);
  std::vector<double> x(N);
  double walk = 0;
  std::int64_t slope = 0;
  for (std::size_t i = 0; i + 1 < N; ++i) {
    walk += 0.5 * z(rng);
    const auto count = static_cast<std::int64_t>(std::lround(1000.0 + walk + 3.0 * z(rng)));
    if (i == 0) slope = count;
    pulses[i + 1] = pulses[i] + count;
  }
  for (std::size_t i = 0; i < N; ++i) {
    residuals[i] = static_cast<std::int32_t>(pulses[i] - slope * static_cast<std::int64_t>(i));
    x[i] = static_cast<double>(pulses[i]);
  }
  const auto same = [&](const char* what, std::uint64_t m, auto of) {
    const TotalVariance d = of(PhaseSpan(x)), p = of(PhaseSpan(pulses)), r = of(PhaseSpan(residuals));
    ASSERT_GT(d.n, 0u) << what << " m = " << m;
    EXPECT_EQ(p.var, d.var) << what << " m = " << m;
    EXPECT_EQ(p.n, d.n);
    EXPECT_EQ(r.n, d.n);
    EXPECT_NEAR(r.var, d.var, 1e-9 * d.var) << what << " m = " << m;
  };
  std::vector<double> scratch(total_scratch_size(256, 2));
  for (const std::uint64_t m : {1u, 4u, 16u, 64u, 256u, 1000u}) {
    same("totvar", m, [&](PhaseSpan v) { return totvar(v, m, 0.5); });
    same("oavar", m, [&](PhaseSpan v) { return oavar(v, m, 0.5, m > 8 ? m / 8 : 1); });
    if (m <= 256) {
      same("mtotvar", m, [&](PhaseSpan v) { return mtotvar(v, 1, m, 0.5, scratch); });
      same("htotvar", m, [&](PhaseSpan v) { return htotvar(v, 1, m, 0.5, scratch); });
    }
    if (m >= 4 && m <= 256) same("decimated mtotvar", m, [&](PhaseSpan v) { return mtotvar(v, 2, m, 0.5, scratch); });
    if (m >= 4) same("theo1", m, [&](PhaseSpan v) { return theo1(v, m, 0.5, m > 16 ? m / 16 : 1); });
  }
  const TheoBiasRatio bd = theo_bias_ratio(x, 0.5, 8, 16), bp = theo_bias_ratio(pulses, 0.5, 8, 16),
                      br = theo_bias_ratio(residuals, 0.5, 8, 16);
  ASSERT_GT(bd.ratio, 0.0);
  EXPECT_EQ(bp.ratio, bd.ratio);
  EXPECT_NEAR(br.ratio, bd.ratio, 1e-9 * bd.ratio);
  // The lag sums: the prepared record is the residual from a quadratic, whichever form it came in.
  std::vector<double> work(theo1_workspace_size(N)), fast_scratch(mtotvar_scratch_size(N));
  for (const std::uint64_t m : {16u, 600u}) {
    same("theo1_fast", m, [&](PhaseSpan v) {
      Theo1Workspace w = theo1_prepare(v, work);
      return theo1_fast(w, m, 0.5);
    });
    same("mtotvar_fast", m, [&](PhaseSpan v) {
      Theo1Workspace w = theo1_prepare(v, work);
      return mtotvar_fast(w, fast_scratch, m, 0.5);
    });
  }
}

// MTOTVAR and HTOTVAR at short taus from the exact lag products of an integer record's differences
// (total_lags.hpp), the estimator for counts too long for the lag sums' workspace. Records: the ones
// above times 1000, rounded to integers (a counter's phase). Oracle: MTOTVAR's definition in long
// double on their doubles (mtotvar_oracle; HTOTVAR's on the frequencies, as htot_every_m). The
// table's sums are exact and the estimate is formed in double-double from exact coefficients, then
// rounded: a relative tolerance of 1e-14, a few units of the oracle's own rounding (largest
// measured printed). Every m up to 40, then every 23rd and the last two (each m costs O(m^3)).
std::vector<std::int64_t> counted(const std::vector<double>& x) {
  std::vector<std::int64_t> c(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) c[i] = std::llround(1000.0 * x[i]);
  return c;
}

double lagged_every_m(const std::vector<std::int64_t>& counts, bool hadamard, const char* what) {
  const std::vector<double> x(counts.begin(), counts.end());
#ifdef GYROCHAR_EMULATED
  constexpr std::size_t largest = 64;  // under QEMU: the m^3 of the largest taus would take minutes
#else
  constexpr std::size_t largest = lag_table_max_m;
#endif
  const std::size_t n_seq = hadamard ? x.size() - 1 : x.size(), last = std::min<std::size_t>(n_seq / 3, largest);
  if (last < (hadamard ? 2u : 1u)) return 0;
  std::vector<ExactSum> work(lag_table_size(3 * last - 2));
  std::vector<double> scratch(lagged_scratch_size(last));
  const LagTable t = lag_table(counts, hadamard ? 3 : 2, 3 * last - 2, work);
  EXPECT_TRUE(t.ready) << what;
  std::vector<double> y(x.size() - 1), direct_scratch(total_scratch_size(last, 1));
  for (std::size_t i = 0; i + 1 < x.size(); ++i) y[i] = x[i + 1] - x[i];
  double worst = 0;
  for (std::size_t m = hadamard ? 2 : 1; m <= last; ++m) {
    if (!checked_m(m, last) || (m > 40 && m % 23 != 0 && m + 2 < last)) continue;  // each m costs O(m^3)
    const double scale = hadamard ? static_cast<double>(m * m) / 3.0 : 1.0;
    const double oracle = static_cast<double>(mtotvar_oracle(hadamard ? y : x, m)) * scale;
    const TotalVariance direct = hadamard ? htotvar(x, 1, m, 1.0, direct_scratch) : mtotvar(x, 1, m, 1.0, direct_scratch);
    const TotalVariance lagged = hadamard ? htotvar_lagged(t, m, 1.0, scratch) : mtotvar_lagged(t, m, 1.0, scratch);
    EXPECT_EQ(lagged.n, direct.n) << what << " m=" << m;
    EXPECT_EQ(lagged.stride, 1u);
    EXPECT_NEAR(lagged.var, oracle, 1e-14 * oracle) << what << " N=" << x.size() << " m=" << m;
    worst = std::max(worst, std::abs(lagged.var / oracle - 1));
  }
  std::printf("%s N=%zu: %s from the lag table, worst relative error %.2e\n", what, x.size(),
              hadamard ? "HTOTVAR" : "MTOTVAR", worst);
  return worst;
}

TEST(TotalLags, EqualsTheDefinitionAtEveryM) {
  for (const bool hadamard : {false, true}) {
    for (const std::size_t n : {3u, 4u, 5u, 6u, 7u, 8u, 12u, 31u, 97u, 256u, 1000u})
      lagged_every_m(counted(record(n, n, 0.3, 1.0, 2.5, 0.0)), hadamard, "walk+white+drift");
    lagged_every_m(counted(record(2000, 11, 0.0, 1.0, 0.0, 0.0)), hadamard, "white");
    lagged_every_m(counted(record(2000, 12, 1.0, 0.0, 0.0, 0.0)), hadamard, "walk");
    lagged_every_m(counted(record(1500, 7, 0.0, 1.0, 1e3, 0.0)), hadamard, "ramp");  // phase up to 1.5e9
    lagged_every_m(counted(record(1200, 8, 1e-3, 0.0, 1.0, 1e-3)), hadamard, "quadratic+walk");
  }
}

// A counter's phase in int32 (x_0 = 0): counts of a random-walk rate plus white noise, rounded.
std::vector<std::int32_t> counter_phase(std::size_t n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> z;
  std::vector<std::int32_t> x(n);
  double walk = 0;
  std::int64_t phase = 0;
  for (std::size_t i = 1; i < x.size(); ++i) {
    walk += 0.5 * z(rng);
    phase += std::lround(walk + 3.0 * z(rng));
    x[i] = static_cast<std::int32_t>(phase);
  }
  return x;
}

TEST(TotalLags, CountsGiveExactSumsOnAnyThreads) {
  // A counter's phase as int32 residuals from a line (the analyzer's record): the differences are
  // integers, so every sum of the table is exact. Oracle: the same sums in int64, written out; the
  // table built on a runner (its stripes in reverse order) against the table built in turn: the
  // same bits. The same with a pulse of 5000 counts every 7919 samples: the stripes it reaches have
  // differences past the int16 products' limit (2048) and take the doubles, the others the int16.
  const std::vector<std::int32_t> x = counter_phase(40000, 9);
  std::vector<std::int32_t> pulsed(x);
  for (std::size_t j = 3000; j < pulsed.size(); j += 7919) pulsed[j] += 5000;
  constexpr std::size_t lags = 3 * 64 - 2;
  std::vector<ExactSum> work(lag_table_size(lags)), again(lag_table_size(lags));
  const auto value = [](ExactSum e) { return static_cast<std::int64_t>(e.hi) + static_cast<std::int64_t>(e.lo); };
  for (const std::vector<std::int32_t>* record : {static_cast<const std::vector<std::int32_t>*>(&pulsed), &x}) {
    const LagTable t = lag_table(*record, 2, lags, work);
    const ReverseRows reverse;
    const LagTable u = lag_table(*record, 2, lags, again, &reverse);
    ASSERT_TRUE(t.ready && u.ready);
    const std::vector<std::int32_t>& r = *record;
    std::vector<std::int64_t> w(r.size() - 2);
    for (std::size_t j = 0; j < w.size(); ++j) w[j] = std::int64_t{r[j + 2]} - 2 * std::int64_t{r[j + 1]} + r[j];
    EXPECT_EQ(*std::max_element(w.begin(), w.end()) >= 2048, record == &pulsed);
    for (std::size_t d = 0; d < lags; ++d) {
      std::int64_t total = 0, head = 0, tail = 0;
      for (std::size_t j = 0; j + d < w.size(); ++j) total += w[j] * w[j + d];
      EXPECT_EQ(value(t.total[d]), total) << d;
      for (std::size_t c = 0; c < lags; ++c) {
        EXPECT_EQ(value(t.head[d * lags + c]), head) << d << " " << c;
        EXPECT_EQ(value(t.tail[d * lags + c]), tail) << d << " " << c;
        head += w[c] * w[c + d], tail += w[w.size() - 1 - d - c] * w[w.size() - 1 - c];
      }
    }
    for (std::size_t i = 0; i < work.size(); ++i) ASSERT_TRUE(work[i].hi == again[i].hi && work[i].lo == again[i].lo) << i;
  }
  const LagTable t = lag_table(x, 2, lags, work);
  std::vector<double> scratch(lagged_scratch_size(64));
  std::vector<double> phase_doubles(x.begin(), x.end()), direct_scratch(total_scratch_size(64, 1));
  for (const std::uint64_t m : {1u, 2u, 7u, 16u, 64u}) {
    const TotalVariance lagged = mtotvar_lagged(t, m, 0.5, scratch), direct = mtotvar(x, 1, m, 0.5, direct_scratch);
    ASSERT_GT(lagged.n, 0u);
    EXPECT_EQ(lagged.n, direct.n);
    EXPECT_NEAR(lagged.var, direct.var, 1e-12 * direct.var) << m;  // the direct sums' own rounding
  }
  // Differences too large for exact chunk sums (8192 |w|^2 >= 2^53): no table.
  std::vector<std::int64_t> wide(100);
  wide[50] = std::int64_t{1} << 40;
  EXPECT_FALSE(lag_table(wide, 2, lags, work).ready);
}

TEST(TotalLags, GroupSumsGiveTheDecimatedEstimator) {
  // The table of a counter's sums over groups of g samples, formed as they are read. Oracles: the
  // group sums' products written out in int64 (exact), and the decimated estimator mtotvar(x, g,
  // m) (total.hpp, direct double sums: their own rounding), which is MTOTVAR at m / g of the group
  // sums over g^4. N = 40001 is a multiple of none of the groups: the last partial group is left out.
  const std::vector<std::int32_t> x = counter_phase(40001, 10);
  constexpr std::size_t lags = 3 * 16 - 2;
  std::vector<ExactSum> work(lag_table_size(lags));
  std::vector<double> scratch(lagged_scratch_size(16)), direct_scratch;
  const auto value = [](ExactSum e) { return static_cast<std::int64_t>(e.hi) + static_cast<std::int64_t>(e.lo); };
  for (const std::uint64_t g : {2u, 3u, 16u, 64u}) {
    const LagTable t = lag_table(x, 2, lags, work, nullptr, g);
    ASSERT_TRUE(t.ready) << g;
    std::vector<std::int64_t> sums(x.size() / g, 0), w;
    for (std::size_t k = 0; k < sums.size(); ++k)
      for (std::size_t i = 0; i < g; ++i) sums[k] += x[k * g + i];
    for (std::size_t j = 0; j + 2 < sums.size(); ++j) w.push_back(sums[j + 2] - 2 * sums[j + 1] + sums[j]);
    ASSERT_EQ(t.values, w.size()) << g;
    for (const std::size_t d : {0u, 1u, 17u, 45u}) {
      std::int64_t total = 0, head = 0, tail = 0;
      for (std::size_t j = 0; j + d < w.size(); ++j) total += w[j] * w[j + d];
      for (std::size_t c = 0; c < 20; ++c) head += w[c] * w[c + d], tail += w[w.size() - 1 - d - c] * w[w.size() - 1 - c];
      EXPECT_EQ(value(t.total[d]), total) << g << " " << d;
      EXPECT_EQ(value(t.head[d * lags + 20]), head) << g << " " << d;
      EXPECT_EQ(value(t.tail[d * lags + 20]), tail) << g << " " << d;
    }
    if (g % 2 != 0) continue;  // the decimated estimator takes blocks of a power of two
    for (const std::uint64_t s : {2u, 4u, 16u}) {
      const std::uint64_t m = s * g;
      direct_scratch.resize(total_scratch_size(m, g));
      const TotalVariance lagged = mtotvar_lagged(t, s, 0.5, scratch), direct = mtotvar(x, g, m, 0.5, direct_scratch);
      ASSERT_GT(direct.n, 0u);
      EXPECT_EQ(lagged.n, direct.n) << g << " " << m;
      const double g4 = static_cast<double>(g * g * g * g);
      EXPECT_NEAR(lagged.var / g4, direct.var, 1e-12 * direct.var) << g << " " << m;  // the direct sums' rounding
    }
  }
  EXPECT_FALSE(lag_table(x, 2, lags, work, nullptr, 0).ready);
  EXPECT_FALSE(lag_table(x, 2, lags, work, nullptr, x.size() / 2).ready);  // two sums: no difference of order 2
}

TEST(TotalLags, UndefinedInputGivesNoTerms) {
  const std::vector<std::int64_t> x = counted(record(40, 1, 0.3, 1.0, 2.5, 0.0));
  std::vector<ExactSum> work(lag_table_size(37));
  std::vector<double> scratch(lagged_scratch_size(13));
  EXPECT_FALSE(lag_table(x, 1, 37, work).ready);                                  // order 2 or 3
  EXPECT_FALSE(lag_table(record(40, 1, 0.3, 1.0, 2.5, 0.0), 2, 37, work).ready);  // doubles
  EXPECT_FALSE(lag_table(x, 2, 3 * lag_table_max_m - 1, work).ready);
  EXPECT_FALSE(lag_table(x, 2, 37, std::span<ExactSum>(work).first(work.size() - 1)).ready);
  EXPECT_FALSE(lag_table(std::vector<std::int64_t>{1, 2}, 2, 1, work).ready);
  const LagTable t = lag_table(x, 2, 37, work);
  ASSERT_TRUE(t.ready);
  EXPECT_GT(mtotvar_lagged(t, 13, 1.0, scratch).n, 0u);  // 3m = 39 <= N, 3m - 2 <= 37 lags
  EXPECT_EQ(mtotvar_lagged(t, 0, 1.0, scratch).n, 0u);
  EXPECT_EQ(mtotvar_lagged(t, 4, 0.0, scratch).n, 0u);
  EXPECT_EQ(mtotvar_lagged(t, 4, 1.0, std::span<double>(scratch).first(lagged_scratch_size(4) - 1)).n, 0u);
  EXPECT_EQ(htotvar_lagged(t, 4, 1.0, scratch).n, 0u);  // a table of second differences
  const LagTable short_table = lag_table(x, 2, 30, work);
  EXPECT_EQ(mtotvar_lagged(short_table, 11, 1.0, scratch).n, 0u);  // 3m - 2 = 31 lags
}

}  // namespace
}  // namespace gyrochar
