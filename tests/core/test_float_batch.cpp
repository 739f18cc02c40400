// The batch path of floating phase (float_batch.hpp) against Characterizer<FloatArith> fed the
// same values (oracle: the characterizer, itself checked against the definitions in
// test_characterizer.cpp): per tau the same term counts, the non-overlapped sums and the noise
// sums to the last bit (the same terms summed in the same order), and the overlapping sums within
// the bound of summing the same n non-negative terms in another order, 2 (n - 1) u relative
// (u = 2^-53: each order is within (n - 1) u of the exact sum). Phase (relative to its line) and
// frequency (relative to its first value), fully overlapped and strided taus. phase_batch_taus()
// below: against the characterizer and against the definitions in long double.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "gyrochar/characterizer.hpp"
#include "gyrochar/float_batch.hpp"

namespace gyrochar {
namespace {

struct FloatHeap {
  std::vector<FloatArith::Entry> history;
  std::vector<Characterizer<FloatArith>::TauState> taus;
  Characterizer<FloatArith> c;
  FloatHeap(std::uint32_t s, const std::vector<std::uint64_t>& m_list)
      : history(history_entries(s, m_list.back())), taus(m_list.size()), c(history, taus) {
    EXPECT_EQ(c.configure({s, 0}, m_list), ConfigureStatus::ok);
  }
};

// The record float_batch_sums() takes, staged as the characterizer stages phase points or
// frequency values.
struct Record {
  std::vector<double> x, hi, lo;
  FloatArith::Prefix p;
  void stage(double v) {
    p = FloatArith::add_prefix(p, v);
    x.push_back(v);
    hi.push_back(p.hi);
    lo.push_back(p.lo);
  }
  FloatRecord view() const { return {x, hi, lo}; }
};

// A clock's phase: an offset, a frequency, random-walk FM and white PM; or its frequency values.
std::vector<double> clock(bool phase, std::size_t n) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> g;
  std::vector<double> v;
  double y = 3e-7, x = 1234.5;
  for (std::size_t k = 0; k < n; ++k) {
    y += 1e-10 * g(rng);
    x += y;
    v.push_back(phase ? x + 1e-9 * g(rng) : y + 1e-9 * g(rng));
  }
  return v;
}

// The values into the characterizer (phase points or frequency values) and, staged as it stages
// them, into the record.
void feed_both(bool phase, const std::vector<double>& values, FloatHeap& heap, Record& record) {
  double x0 = 0, slope = 0, first = 0;
  for (std::size_t k = 0; k < values.size(); ++k) {
    if (phase) {
      heap.c.add_phase_point(values[k]);
      record.stage(line_residual(values[k], k, x0, slope));
    } else {
      heap.c.add_increment(values[k]);
      if (k == 0) {
        first = values[0];
        record.stage(0.0);
      }
      record.stage(record.x.back() + (values[k] - first));
    }
  }
}

void expect_same_sums(bool phase, std::uint32_t s, const std::vector<std::uint64_t>& m_list) {
  const std::vector<double> values = clock(phase, 2500);
  FloatHeap heap(s, m_list);
  Record record;
  feed_both(phase, values, heap, record);
  ASSERT_EQ(heap.c.phase_points(), record.x.size());
  for (std::size_t i = 0; i < m_list.size(); ++i) {
    const std::uint64_t m = m_list[i];
    const auto want = heap.c.result(i);
    NoiseIdAccumulator noise;
    const auto got = float_batch_sums(record.view(), m, want.stride, noise);
    const std::string where = std::string(phase ? "phase" : "freq") + " m=" + std::to_string(m);
    EXPECT_EQ(got.m, m);
    EXPECT_EQ(got.stride, want.stride) << where;
    EXPECT_EQ(got.n, want.n) << where;
    ASSERT_GT(want.n[0], 0u) << where;
    for (std::size_t k = 0; k < 3; ++k) {
      const double bound = 2.0 * static_cast<double>(want.n[k]) * 0x1p-53 * want.sum[k];
      EXPECT_NEAR(got.sum[k], want.sum[k], bound) << where << " kind " << k;
      EXPECT_GT(got.sum[k], 0.0) << where;
    }
    for (const SumKind k : {SumKind::avar_nonoverlapped, SumKind::hvar_nonoverlapped})
      EXPECT_EQ(got.sum[static_cast<std::size_t>(k)], want.sum[static_cast<std::size_t>(k)]) << where;
    for (int d = 0; d < 4; ++d) {
      const Lag1Sums a = noise.order(d), b = heap.c.noise(i).order(d);
      EXPECT_TRUE(a.n == b.n && a.pairs == b.pairs && a.shift == b.shift && a.sum == b.sum && a.sum_sq == b.sum_sq &&
                  a.sum_lag == b.sum_lag && a.sum_left == b.sum_left && a.sum_right == b.sum_right)
          << where << " order " << d;
    }
  }
}

TEST(FloatBatch, FullyOverlappedTausGiveTheCharacterizersSums) {
  // S = 1024 >= every m: stride 1, the four-lane loop from 3m on (m = 1 .. 7 and longer taus
  // whose steady part is not a multiple of four points).
  const std::vector<std::uint64_t> m_list{1, 2, 3, 4, 5, 6, 7, 10, 33, 100, 255, 500, 624};
  for (const bool phase : {true, false}) expect_same_sums(phase, 1024, m_list);
}

TEST(FloatBatch, StridedTausGiveTheCharacterizersSums) {
  // S = 8: taus above 8 have their terms every m/8 points rounded up to a power of two.
  const std::vector<std::uint64_t> m_list{1, 3, 8, 10, 12, 20, 64, 96, 256};
  for (const bool phase : {true, false}) expect_same_sums(phase, 8, m_list);
}

TEST(FloatBatch, ShortRecordsHaveNoTermButTheirDecimatedPoint) {
  Record record;
  for (const double v : {1.0, 2.5, 2.0}) record.stage(v);
  NoiseIdAccumulator noise;
  const auto r = float_batch_sums(record.view(), 5, 1, noise);  // m beyond the record
  EXPECT_EQ(r.n, (std::array<std::uint64_t, sum_kinds>{}));
  EXPECT_EQ(noise.points(), 1u);  // x_0, as the characterizer decimates it
  NoiseIdAccumulator none;
  EXPECT_EQ(float_batch_sums(Record{}.view(), 1, 1, none).n[0], 0u);
  EXPECT_EQ(none.points(), 0u);
}

// float_batch_taus() against float_batch_sums() tau by tau (oracle: the per-tau path, itself held
// to the characterizer above): the same terms added in the same order, so every sum, count and
// noise sum is the same to the last bit. Random records of several lengths (around the group's
// chunk of 512 points and below), every m up to N/2 in one list (more than one group of 64), with
// strided taus, m = 0 and m beyond the record mixed in.
void expect_taus_match_one_by_one(const Record& record, const std::vector<std::uint64_t>& m,
                                  const std::vector<std::uint64_t>& stride) {
  std::vector<TauResult<double>> got(m.size());
  std::vector<NoiseIdAccumulator> noise(m.size());
  float_batch_taus(record.view(), m, stride, got, noise);
  for (std::size_t i = 0; i < m.size(); ++i) {
    NoiseIdAccumulator one;
    const auto want = float_batch_sums(record.view(), m[i], stride[i], one);
    const std::string where = "N=" + std::to_string(record.x.size()) + " m=" + std::to_string(m[i]) +
                              " stride=" + std::to_string(stride[i]);
    EXPECT_EQ(got[i].m, want.m) << where;
    EXPECT_EQ(got[i].stride, want.stride) << where;
    EXPECT_EQ(got[i].n, want.n) << where;
    for (std::size_t k = 0; k < sum_kinds; ++k)
      EXPECT_EQ(std::bit_cast<std::uint64_t>(got[i].sum[k]), std::bit_cast<std::uint64_t>(want.sum[k]))
          << where << " kind " << k << ": " << got[i].sum[k] << " vs " << want.sum[k];
    for (int d = 0; d < 4; ++d) {
      const Lag1Sums a = noise[i].order(d), b = one.order(d);
      EXPECT_TRUE(a.n == b.n && a.pairs == b.pairs && a.shift == b.shift && a.sum == b.sum && a.sum_sq == b.sum_sq &&
                  a.sum_lag == b.sum_lag && a.sum_left == b.sum_left && a.sum_right == b.sum_right)
          << where << " order " << d;
    }
  }
}

TEST(FloatBatch, TausTogetherGiveTheSumsOfEachAlone) {
  std::mt19937_64 rng(11);
  std::normal_distribution<double> g;
  for (const std::size_t n : {1, 2, 3, 4, 7, 8, 13, 100, 511, 512, 513, 1000, 1537, 2051}) {
    Record record;  // white and random-walk noise of several scales, as phase relative to a line
    double walk = 0;
    for (std::size_t k = 0; k < n; ++k) {
      walk += 1e-3 * g(rng);
      record.stage(walk + 1e-6 * g(rng) * std::exp(g(rng)));
    }
    std::vector<std::uint64_t> m, stride;
    for (std::uint64_t tau = 1; 2 * tau <= n + 1; ++tau) {  // every m with an overlapping term, and one without
      m.push_back(tau);
      stride.push_back(1);
    }
    expect_taus_match_one_by_one(record, m, stride);
    // Strided and termless taus among fully overlapped ones, in no order.
    m = {n + 5, 3, 0, 24, 5, 8, 2, n, 1};
    stride = {1, 1, 1, 8, 1, 4, 1, 1, 1};
    expect_taus_match_one_by_one(record, m, stride);
  }
}

// phase_batch_taus() (the held record of the analyzer: x alone) against the characterizer fed the
// same values (oracle: the characterizer, checked against the definitions in
// test_characterizer.cpp): the same counts; AVAR, HVAR, the non-overlapped and the noise sums to
// the last bit (the same terms, each sum in e's order). Its MVAR sums are held to the definition
// below.
void expect_phase_batch_as_characterizer(bool phase, std::uint32_t s, const std::vector<std::uint64_t>& m_list) {
  const std::vector<double> values = clock(phase, 2500);
  FloatHeap heap(s, m_list);
  Record record;
  feed_both(phase, values, heap, record);
  std::vector<std::uint64_t> stride;
  for (std::size_t i = 0; i < m_list.size(); ++i) stride.push_back(heap.c.result(i).stride);
  std::vector<TauResult<double>> got(m_list.size());
  std::vector<NoiseIdAccumulator> noise(m_list.size());
  phase_batch_taus(record.x, m_list, stride, got, noise);
  for (std::size_t i = 0; i < m_list.size(); ++i) {
    const auto want = heap.c.result(i);
    const std::string where = std::string(phase ? "phase" : "freq") + " m=" + std::to_string(m_list[i]);
    EXPECT_EQ(got[i].m, m_list[i]);
    EXPECT_EQ(got[i].stride, want.stride) << where;
    EXPECT_EQ(got[i].n, want.n) << where;
    ASSERT_GT(want.n[0], 0u) << where;
    for (const SumKind k : {SumKind::avar, SumKind::hvar, SumKind::avar_nonoverlapped, SumKind::hvar_nonoverlapped}) {
      const auto j = static_cast<std::size_t>(k);
#ifdef __FP_FAST_FMA
      // Where the compiler fuses a multiply and an add (GCC on aarch64), the two codes may fuse
      // different steps: each of the at most N squares added then rounds differently by at most
      // one unit in the last place of the running sum, which (terms >= 0) is at most the final one's.
      EXPECT_NEAR(got[i].sum[j], want.sum[j], static_cast<double>(values.size()) * 0x1p-52 * std::abs(want.sum[j]))
          << where << " kind " << j;
#else
      EXPECT_EQ(std::bit_cast<std::uint64_t>(got[i].sum[j]), std::bit_cast<std::uint64_t>(want.sum[j]))
          << where << " kind " << j << ": " << got[i].sum[j] << " vs " << want.sum[j];
#endif
    }
    for (int d = 0; d < 4; ++d) {
      const Lag1Sums a = noise[i].order(d), b = heap.c.noise(i).order(d);
      EXPECT_TRUE(a.n == b.n && a.pairs == b.pairs && a.shift == b.shift && a.sum == b.sum && a.sum_sq == b.sum_sq &&
                  a.sum_lag == b.sum_lag && a.sum_left == b.sum_left && a.sum_right == b.sum_right)
          << where << " order " << d;
    }
  }
}

TEST(PhaseBatch, GivesTheCharacterizersAvarHvarAndNoiseSumsToTheLastBit) {
  // S = 1024: every tau fully overlapped (four side by side from 3m of the largest of four);
  // S = 8: the taus above 8 strided (one by one).
  for (const bool phase : {true, false}) {
    expect_phase_batch_as_characterizer(phase, 1024, {1, 2, 3, 4, 5, 6, 7, 10, 33, 100, 255, 500, 624});
    expect_phase_batch_as_characterizer(phase, 8, {1, 3, 8, 10, 12, 20, 64, 96, 256});
  }
}

// The definitions in long double (oracle: each term formed from the points directly, MVAR's as
// the sum of its m second differences, O(m) a term; 64-bit significands), with the tolerance each
// sum is owed: a term of the kernel differs from the exact one by the roundings of its double
// differences (first order: 2 u times the magnitudes it is formed from, doubled for the second
// order), the MVAR term by the bound of float_batch.hpp (the roundings of its m AVAR terms, as
// above, plus u |t| + n^2 u^2 (T + 2 A), doubled), and a sum of n squares by n u of itself for its
// own roundings, u = 2^-53. Every difference is also within the long double's own rounding (2^-64
// relative), far below these.
struct Definition {
  long double sum[3] = {0, 0, 0}, tolerance[3] = {0, 0, 0};
  std::uint64_t n[3] = {0, 0, 0};
  // MVAR again from the sums of m AVAR terms as the kernel rounds them (in double), with the
  // tolerance of the double-double running sum alone: u |t| + n^2 u^2 (T + 2 A), doubled.
  long double mvar_of_rounded = 0, rounded_tolerance = 0;
};

Definition definition(const std::vector<double>& x, std::size_t m, std::size_t stride) {
  using L = long double;
  const L u = 0x1p-53L;
  const std::size_t size = x.size();
  L big_a = 0, big_t = 0;
  const auto second = [&](std::size_t e) {
    return static_cast<L>(x[e]) - 2 * static_cast<L>(x[e - m]) + static_cast<L>(x[e - 2 * m]);
  };
  // The rounding bound of the AVAR term at e (as below), and of the sum of m of them ending at e.
  const auto avar_bound = [&](std::size_t e) {
    const L d1 = static_cast<L>(x[e]) - x[e - m], d2 = static_cast<L>(x[e - m]) - x[e - 2 * m];
    return 4 * u * (std::fabs(d1) + std::fabs(d2) + std::fabs(d1 - d2));
  };
  const auto rounded = [&](std::size_t e) { return (x[e] - x[e - m]) - (x[e - m] - x[e - 2 * m]); };  // in double
  std::vector<L> t_of(size, 0), t_bound(size, 0), t_rounded(size, 0), t_rounded_abs(size, 0);
  for (std::size_t e = 2 * m; e < size; ++e) big_a = std::max(big_a, std::fabs(second(e)));
  for (std::size_t e = 3 * m - 1; e < size; ++e) {
    for (std::size_t j = 0; j < m; ++j) {
      t_of[e] += second(e - j), t_bound[e] += avar_bound(e - j);
      t_rounded[e] += rounded(e - j), t_rounded_abs[e] += std::fabs(static_cast<L>(rounded(e - j)));
    }
    big_t = std::max(big_t, std::fabs(t_of[e]));
  }
  const L n_l = static_cast<L>(size);
  Definition d;
  for (std::size_t e = (2 * m + stride - 1) / stride * stride; e < size; e += stride) {
    const L x0 = x[e], x1 = x[e - m], x2 = x[e - 2 * m];
    const L d1 = x0 - x1, d2 = x1 - x2, a = d1 - d2;
    const L da = 4 * u * (std::fabs(d1) + std::fabs(d2) + std::fabs(a));
    d.sum[0] += a * a;
    d.tolerance[0] += 2 * std::fabs(a) * da + da * da;
    ++d.n[0];
    if (e >= 3 * m) {
      const L d3 = x2 - static_cast<L>(x[e - 3 * m]), a1 = d2 - d3, h = a - a1;
      const L dh = 4 * u * (std::fabs(d1) + 2 * std::fabs(d2) + std::fabs(d3) + std::fabs(a) + std::fabs(a1) + std::fabs(h));
      d.sum[2] += h * h;
      d.tolerance[2] += 2 * std::fabs(h) * dh + dh * dh;
      ++d.n[2];
    }
    if (e + 1 >= 3 * m) {
      const L t = t_of[e];
      const L dt = t_bound[e] + 2 * (u * std::fabs(t) + n_l * n_l * (big_t + 2 * big_a) * u * u);
      d.sum[1] += t * t;
      d.tolerance[1] += 2 * std::fabs(t) * dt + dt * dt;
      ++d.n[1];
      // The long double sum of m doubles: within m 2^-64 of their magnitudes.
      const L r = t_rounded[e];
      const L dr = 2 * (u * std::fabs(r) + n_l * n_l * (big_t + 2 * big_a) * u * u) +
                   static_cast<L>(m) * 0x1p-64L * t_rounded_abs[e];
      d.mvar_of_rounded += r * r;
      d.rounded_tolerance += 2 * std::fabs(r) * dr + dr * dr;
    }
  }
  for (std::size_t k = 0; k < 3; ++k) d.tolerance[k] += static_cast<L>(d.n[k] + 1) * u * d.sum[k];
  d.rounded_tolerance += static_cast<L>(d.n[1] + 1) * u * d.mvar_of_rounded;
  return d;
}

TEST(PhaseBatch, SumsAreTheDefinitionsWithinTheirRoundingBounds) {
  std::mt19937_64 rng(23);
  std::normal_distribution<double> g;
  const std::size_t n = 1500;
  std::vector<std::vector<double>> records(3);
  double walk = 0;
  for (std::size_t k = 0; k < n; ++k) {
    records[0].push_back(1e-9 * g(rng));  // random (white phase)
    walk += g(rng);
    records[1].push_back(3.0e4 + walk);                                            // random walk far from 0
    records[2].push_back(0.125 + 0.37 * static_cast<double>(k) + 1e-12 * g(rng));  // ramp: terms ~ 0
  }
  const std::vector<std::uint64_t> m{1, 2, 3, 5, 8, 13, 64, 100, 250, 333, 400, 499, 500, 700, 750};
  const std::vector<std::uint64_t> stride{1, 1, 1, 1, 1, 1, 1, 4, 2, 1, 16, 1, 1, 1, 1};
  for (std::size_t r = 0; r < records.size(); ++r) {
    std::vector<TauResult<double>> got(m.size());
    std::vector<NoiseIdAccumulator> noise(m.size());
    phase_batch_taus(records[r], m, stride, got, noise);
    for (std::size_t i = 0; i < m.size(); ++i) {
      const Definition want = definition(records[r], m[i], stride[i]);
      for (std::size_t k = 0; k < 3; ++k) {
        const std::string where = "record " + std::to_string(r) + " m=" + std::to_string(m[i]) + " kind " +
                                  std::to_string(k);
        EXPECT_EQ(got[i].n[k], want.n[k]) << where;
        EXPECT_LE(std::fabs(static_cast<long double>(got[i].sum[k]) - want.sum[k]), want.tolerance[k])
            << where << ": " << got[i].sum[k] << " vs " << static_cast<double>(want.sum[k]);
      }
      EXPECT_LE(std::fabs(static_cast<long double>(got[i].sum[1]) - want.mvar_of_rounded), want.rounded_tolerance)
          << "record " << r << " m=" << m[i] << ": MVAR " << got[i].sum[1] << " vs the rounded AVAR terms' "
          << static_cast<double>(want.mvar_of_rounded);
    }
  }
}

TEST(PhaseBatch, TausSideBySideGiveTheSumsOfEachAlone) {
  // Oracle: phase_batch_taus() of one tau at a time (the lanes and the one-by-one path form the
  // same terms in the same order): every sum to the last bit, lists of several lengths.
  std::mt19937_64 rng(31);
  std::normal_distribution<double> g;
  for (const std::size_t n : {3, 8, 13, 100, 513, 2051}) {
    std::vector<double> x;
    double walk = 0;
    for (std::size_t k = 0; k < n; ++k) x.push_back(walk += g(rng));
    std::vector<std::uint64_t> m{n + 5, 3, 0, 24, 5, 8, 2, n, 1}, stride{1, 1, 1, 8, 1, 4, 1, 1, 1};
    for (std::uint64_t tau = 1; 3 * tau < n; tau = tau * 3 / 2 + 1) m.push_back(tau), stride.push_back(1);
    std::vector<TauResult<double>> got(m.size());
    std::vector<NoiseIdAccumulator> noise(m.size());
    phase_batch_taus(x, m, stride, got, noise);
    for (std::size_t i = 0; i < m.size(); ++i) {
      TauResult<double> one[1];
      NoiseIdAccumulator one_noise[1];
      phase_batch_taus(x, std::span(&m[i], 1), std::span(&stride[i], 1), one, one_noise);
      EXPECT_EQ(got[i].n, one[0].n) << "N=" << n << " m=" << m[i];
      for (std::size_t k = 0; k < sum_kinds; ++k)
        EXPECT_EQ(std::bit_cast<std::uint64_t>(got[i].sum[k]), std::bit_cast<std::uint64_t>(one[0].sum[k]))
            << "N=" << n << " m=" << m[i] << " kind " << k;
    }
  }
}

TEST(PhaseBatch, OnlyTheSumsAskedForEachWithTheSameBits) {
  // Oracle: phase_batch_taus() with every sum (checked above against the characterizer and the
  // definitions): asked for a subset, each sum formed is the same to the last bit, each other one 0
  // with no term, and the noise sums the same or untouched (m = 1 takes its non-overlapped sums
  // from its AVAR and HVAR sums when it forms both, from its own decimation otherwise).
  std::mt19937_64 rng(37);
  std::normal_distribution<double> g;
  std::vector<double> x;
  double walk = 0;
  for (std::size_t k = 0; k < 1200; ++k) x.push_back(walk += g(rng));
  const std::vector<std::uint64_t> m{1, 2, 3, 5, 8, 13, 21, 100, 250, 333, 399, 400, 600, 1200},
      stride{1, 1, 1, 1, 1, 1, 4, 1, 2, 1, 1, 16, 1, 1};
  std::vector<TauResult<double>> all(m.size());
  std::vector<NoiseIdAccumulator> all_noise(m.size());
  phase_batch_taus(x, m, stride, all, all_noise);
  for (unsigned kinds = 1; kinds <= (all_sums | noise_sums); ++kinds) {
    std::vector<TauResult<double>> got(m.size());
    std::vector<NoiseIdAccumulator> noise(m.size());
    phase_batch_taus(x, m, stride, got, noise, kinds);
    for (std::size_t i = 0; i < m.size(); ++i) {
      for (std::size_t k = 0; k < sum_kinds; ++k) {
        const std::string where = "kinds " + std::to_string(kinds) + " m=" + std::to_string(m[i]) + " kind " +
                                  std::to_string(k);
        const bool formed = (kinds & sum_bit(static_cast<SumKind>(k))) != 0;
        EXPECT_EQ(got[i].n[k], formed ? all[i].n[k] : 0u) << where;
        EXPECT_EQ(std::bit_cast<std::uint64_t>(got[i].sum[k]), std::bit_cast<std::uint64_t>(formed ? all[i].sum[k] : 0.0))
            << where;
      }
      const bool lag1 = (kinds & noise_sums) != 0;
      for (int d = 0; d < 4; ++d) {
        const Lag1Sums a = noise[i].order(d), b = lag1 ? all_noise[i].order(d) : Lag1Sums{};
        EXPECT_TRUE(a.n == b.n && a.sum == b.sum && a.sum_sq == b.sum_sq && a.sum_lag == b.sum_lag)
            << "kinds " << kinds << " m=" << m[i] << " order " << d;
      }
    }
  }
}

}  // namespace
}  // namespace gyrochar
