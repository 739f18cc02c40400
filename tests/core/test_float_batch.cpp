// The batch path of floating phase (float_batch.hpp) against Characterizer<FloatArith> fed the
// same values (oracle: the characterizer, itself checked against the definitions in
// test_characterizer.cpp): per tau the same term counts, the non-overlapped sums and the noise
// sums to the last bit (the same terms summed in the same order), and the overlapping sums within
// the bound of summing the same n non-negative terms in another order, 2 (n - 1) u relative
// (u = 2^-53: each order is within (n - 1) u of the exact sum). Phase (relative to its line) and
// frequency (relative to its first value), fully overlapped and strided taus.
#include <gtest/gtest.h>

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

void expect_same_sums(bool phase, std::uint32_t s, const std::vector<std::uint64_t>& m_list) {
  const std::vector<double> values = clock(phase, 2500);
  FloatHeap heap(s, m_list);
  Record record;
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

}  // namespace
}  // namespace gyrochar
