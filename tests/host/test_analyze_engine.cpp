// The analysis engine's own contract, beside the reference sets: the tau lists and the stride
// factor, what it refuses, strided taus above the "full" cap against a brute-force strided
// estimator, the floating phase reference (a line added to phase changes nothing), and the lag
// sums' workspace memory, the same bits on one thread or two, TheoH's bias ratio shared with the fit.
#include <gtest/gtest.h>
#include <sys/mman.h>

#include <algorithm>
#include <cfloat>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <map>
#include <new>
#include <random>
#include <span>
#include <stdexcept>
#include <thread>
#include <tuple>
#include <type_traits>
#include <vector>

#include "analysis.hpp"
#include "analysis_report.hpp"
#include "datafile.hpp"
#include "held_memory.hpp"
#include "plan.hpp"
#include "total_analysis.hpp"
#include "gyrochar/batch.hpp"
#include "gyrochar/total_lags.hpp"

namespace gyrochar {
namespace {

TEST(AnalyzeEngine, StrideFactorParsesFullAndWhatTheCharacterizerAccepts) {
  // Oracle: the core characterizer's rule (characterizer.hpp, ConfigureStatus::bad_stride_factor):
  // S a power of two with 2 <= S <= 2^24; "full" left for the planning step.
  EXPECT_TRUE(StrideFactor::parse("full")->is_full());
  EXPECT_EQ(StrideFactor::parse("full")->requested(), 0u);
  EXPECT_EQ(StrideFactor::parse("2")->requested(), 2u);
  EXPECT_EQ(StrideFactor::parse("16777216")->requested(), 1u << 24);
  for (const char* text : {"", "0", "1", "3", "12", "33554432", "4294967296", "8x", " 8", "+8", "-8", "Full"})
    EXPECT_FALSE(StrideFactor::parse(text).has_value()) << "'" << text << "'";
  for (std::uint32_t s = 1; s != 0; s <<= 1) EXPECT_EQ(valid_stride_factor(s), s >= 2 && s <= (1u << 24)) << s;
  // Over a held record (the batch kernels: no history) any power of two from 2 a uint32 holds.
  for (std::uint32_t s = 1; s != 0; s <<= 1) EXPECT_EQ(valid_stride_factor(s, true), s >= 2) << s;
  EXPECT_FALSE(valid_stride_factor(3, true));
}

TEST(AnalyzeEngine, TauRuleAndListParsedOnce) {
  // Oracle: the --taus grammar of gyrochar-analyze --help: octave, decade, all, or positive
  // averaging factors, strictly increasing, separated by commas.
  EXPECT_EQ(tau_rule("octave"), TauRule::octave);
  EXPECT_EQ(tau_rule("decade"), TauRule::decade);
  EXPECT_EQ(tau_rule("all"), TauRule::all);
  EXPECT_EQ(tau_rule("1,10"), TauRule::list);
  std::string why;
  EXPECT_EQ(parse_tau_list("1,10,100", why), (std::vector<std::uint64_t>{1, 10, 100}));
  EXPECT_EQ(why, "");
  EXPECT_TRUE(parse_tau_list("1,x", why).empty());
  EXPECT_EQ(why, "'x' is not octave, decade, all or a positive averaging factor");
  EXPECT_TRUE(parse_tau_list("4,2", why).empty());
  EXPECT_EQ(why, "averaging factors must increase");
  EXPECT_TRUE(parse_tau_list("", why).empty());
  EXPECT_EQ(why, "empty list");
  EXPECT_TRUE(parse_tau_list("0", why).empty());
}

TEST(AnalyzeEngine, FullIsResolvedInThePlanningStep) {
  // Oracle: full_stride_factor() and resolve_stride_factor() (checked above) applied by hand.
  AnalysisOptions o;
  o.type = DataType::phase;
  plan_taus(o, TauRule::octave, StrideFactor::full(), {}, 4000, std::uint64_t{1} << 40);
  EXPECT_EQ(o.stride_factor, full_stride_factor(4000));  // 1024: every tau up to N/4 fully overlapped
  EXPECT_EQ(o.m_list.back(), 1024u);                     // octaves up to N/2 = 2000
  // Counts of a 120 h, 1 kHz file are held (batch kernel, no history): every octave tau up to
  // N/4 is fully overlapped, past the characterizer's 2^24.
  o.type = DataType::counts;
  o.values_hint = 432'000'000;
  plan_taus(o, TauRule::octave, StrideFactor::full(), {}, 432'000'001, std::uint64_t{1} << 40);
  EXPECT_TRUE(o.hold_counts);
  EXPECT_EQ(o.stride_factor, 1u << 27);
  EXPECT_EQ(o.m_list.back(), 1u << 27);  // octaves up to N/2
  for (const std::uint64_t m : o.m_list) EXPECT_EQ(stride_of(m, o.stride_factor), 1u) << m;
  o.type = DataType::phase;
  o.values_hint = 0;
  plan_taus(o, TauRule::list, *StrideFactor::parse("8"), {1, 16}, 4000, std::uint64_t{1} << 40);
  EXPECT_EQ(o.stride_factor, 8u);
  EXPECT_EQ(o.m_list, (std::vector<std::uint64_t>{1, 16}));
  // A dynamic window of 100 values (100 phase points): "all" keeps m with 4 m <= 100, and "full"
  // is the smallest power of two >= the largest of them.
  plan_window_taus(o, TauRule::all, StrideFactor::full(), {}, 100, 100);
  EXPECT_EQ(o.m_list.size(), 25u);
  EXPECT_EQ(o.m_list.back(), 25u);
  EXPECT_EQ(o.stride_factor, 32u);
}

TEST(AnalyzeEngine, StrideFactorAndRepresentableTaus) {
  // "full": the smallest power of two >= m_max, within [2, 2^16] (the documented rule).
  EXPECT_EQ(resolve_stride_factor(0, 1), 2u);
  EXPECT_EQ(resolve_stride_factor(0, 500), 512u);
  EXPECT_EQ(resolve_stride_factor(0, 1u << 16), 1u << 16);
  EXPECT_EQ(resolve_stride_factor(0, 1u << 30), full_stride_cap);
  EXPECT_EQ(resolve_stride_factor(8, 1u << 30), 8u);
  // The analyzer's "full" for a file of N phase points: the smallest power of two >= N/4, within
  // [2, 2^24]; 2^16 for an input of unknown length.
  EXPECT_EQ(full_stride_factor(0), full_stride_cap);
  EXPECT_EQ(full_stride_factor(5), 2u);
  EXPECT_EQ(full_stride_factor(10'000'001), 1u << 22);  // N/4 = 2.5e6 <= 2^22
  EXPECT_EQ(full_stride_factor(std::uint64_t{1} << 40), 1u << 24);
  // A held record has no history: N/4 at any length, up to 2^31.
  EXPECT_EQ(full_stride_factor(432'000'001, true), 1u << 27);  // 120 h at 1 kHz: N/4 = 1.08e8 <= 2^27
  EXPECT_EQ(full_stride_factor(std::uint64_t{1} << 40, true), held_stride_cap);
  EXPECT_EQ(full_stride_factor(10'000'001, true), 1u << 22);
  // History: 3S points for ring 0, 3S/2 for each level above (24 bytes a point, counts or floats).
  EXPECT_EQ(history_bytes(DataType::counts, 8, 8), 24u * 24u);
  EXPECT_EQ(history_bytes(DataType::phase, 8, 32), (24u + 2u * 12u) * 24u);
  // S = 8: every m <= 8, then multiples of 2 up to 16, of 4 up to 32, ...
  EXPECT_TRUE(tau_representable(7, 8));
  EXPECT_TRUE(tau_representable(10, 8));
  EXPECT_FALSE(tau_representable(11, 8));
  EXPECT_TRUE(tau_representable(20, 8));
  EXPECT_FALSE(tau_representable(18, 8));
  EXPECT_FALSE(tau_representable(0, 8));
}

TEST(AnalyzeEngine, AllTausAreEveryRepresentableFactor) {
  // Oracle: the brute-force filter of 1..N/2 by tau_representable.
  for (const std::uint32_t s : {2u, 8u, 64u}) {
    for (const std::uint64_t n_phase : {2ull, 3ull, 17ull, 1000ull, 5000ull}) {
      std::vector<std::uint64_t> want;
      for (std::uint64_t m = 1; m <= n_phase / 2; ++m)
        if (tau_representable(m, s)) want.push_back(m);
      EXPECT_EQ(all_taus(n_phase, s), want) << "S=" << s << " N=" << n_phase;
    }
  }
  EXPECT_EQ(octave_taus(1001), (std::vector<std::uint64_t>{1, 2, 4, 8, 16, 32, 64, 128, 256}));
  EXPECT_EQ(octave_taus(0).back(), std::uint64_t{1} << 39);                                        // unknown length
  EXPECT_EQ(decade_taus(1001), (std::vector<std::uint64_t>{1, 2, 4, 10, 20, 40, 100, 200, 400}));  // Stable32's decade
}

TEST(AnalyzeEngine, RefusesInconsistentOptionsAndValues) {
  AnalysisOptions o;
  o.m_list = {1, 2};
  auto refused = [](AnalysisOptions bad) {
    try {
      Analyzer a(bad);
    } catch (const std::invalid_argument&) {
      return true;
    }
    return false;
  };
  EXPECT_FALSE(refused(o));
  AnalysisOptions b = o;
  b.tau0_s = 0;
  EXPECT_TRUE(refused(b));
  b = o;
  b.m_list = {2, 1};
  EXPECT_TRUE(refused(b));
  b = o;
  b.m_list = {};
  EXPECT_TRUE(refused(b));
  b = o;
  b.stride_factor = 6;
  EXPECT_TRUE(refused(b));
  b = o;
  b.stride_factor = 8;
  b.m_list = {1, 11};  // above S = 8 only even m
  EXPECT_TRUE(refused(b));
  b.m_list = {1, 12};
  EXPECT_FALSE(refused(b));
  b = o;
  b.stats = {};
  EXPECT_TRUE(refused(b));
  b = o;
  b.confidence = 1.0;
  EXPECT_TRUE(refused(b));

  Analyzer phase(o);
  EXPECT_THROW(phase.add(std::nan("")), std::invalid_argument);
  EXPECT_THROW(phase.add(INFINITY), std::invalid_argument);
  o.type = DataType::counts;
  Analyzer counts(o);
  EXPECT_THROW(counts.add(2.5), std::invalid_argument);
  EXPECT_THROW(counts.add(2147483648.0), std::invalid_argument);
  EXPECT_NO_THROW(counts.add(-2147483647.0));
  o.hold_counts = true;  // the batch engine: the bad value's index in its block
  Analyzer held(o);
  for (const double bad : {2.5, 2147483648.0, -double{INFINITY}}) {
    const std::vector<double> block{3600.0, 3601.0, bad, 3599.0};
    try {
      held.add(block);
      ADD_FAILURE() << bad << " taken";
    } catch (const BadValue& e) {
      EXPECT_EQ(e.index(), 2u) << bad;
    }
  }
}

TEST(AnalyzeEngine, TausAboveTheFullCapAreStridedAndTheirEdfSaysSo) {
  // 2^18 + 3000 points of white phase noise, taus 2^15 and 2^17 with S "full": the cap 2^16 makes
  // 2^17 strided by 2. Oracle: the overlapping AVAR formula summed by brute force over every 2nd
  // start j (every start for 2^15); EDF: the closed form for white PM, whose AVAR terms correlate
  // only at lags m (-4/6) and 2m (1/6): EDF = 36 n^2 / (36 n + 32 (n - k)+ + 2 (n - 2k)+), k = m/stride
  // (pairs k grid steps apart: (n - k)+; none when the n terms span less than m).
  const std::uint64_t n = (1u << 18) + 3000;
  std::mt19937_64 rng(11);
  std::normal_distribution<double> normal;
  std::vector<double> x(n);
  for (double& v : x) v = normal(rng);
  AnalysisOptions o;
  o.m_list = {1u << 15, 1u << 17};
  o.stats = {DevStat::oadev};
  o.alpha = 2;
  Analyzer analyzer(o);
  for (const double v : x) analyzer.add(v);
  const Analysis a = analyzer.result();
  EXPECT_EQ(a.stride_factor, full_stride_cap);
  ASSERT_EQ(a.rows.size(), 2u);
  for (const AnalysisRow& row : a.rows) {
    const std::uint64_t m = row.m, stride = m > full_stride_cap ? m / full_stride_cap : 1;
    EXPECT_EQ(row.stride, stride);
    double sum = 0;
    std::uint64_t terms = 0;
    for (std::uint64_t j = 0; j + 2 * m < n; j += stride, ++terms) {
      const double d = x[j + 2 * m] - 2 * x[j + m] + x[j];
      sum += d * d;
    }
    EXPECT_EQ(row.n, terms) << "m=" << m;
    const double tau = static_cast<double>(m);
    EXPECT_NEAR(row.dev / std::sqrt(sum / (2.0 * static_cast<double>(terms) * tau * tau)), 1.0, 1e-9) << "m=" << m;
    const double nn = static_cast<double>(terms), k = static_cast<double>(m / stride);
    const double pairs_m = std::max(0.0, nn - k), pairs_2m = std::max(0.0, nn - 2 * k);
    EXPECT_NEAR(row.edf / (36 * nn * nn / (36 * nn + 32 * pairs_m + 2 * pairs_2m)), 1.0, 1e-12) << "m=" << m;
  }
}

TEST(AnalyzeEngine, PhaseOffsetAndTrendChangeNothing) {
  // Oracle: differences of order >= 2 (all six statistics) do not see a line added to phase. The
  // added line is large (up to 10^6 s, 10^9 times the noise), so this exercises the reference line
  // the engine subtracts; 1e-9 covers the rounding of the shifted input values themselves.
  const std::vector<std::string> stats{"adev", "oadev", "mdev", "tdev", "hdev", "ohdev"};
  DataFile file(std::string(GYROCHAR_TEST_DATA) + "/phasedat/PHASE.DAT");
  std::vector<double> x;
  for (double v = 0; file.next(v);) x.push_back(v);
  AnalysisOptions o;
  o.m_list = octave_taus(x.size());
  for (const auto& s : stats) o.stats.push_back(*parse_dev_stat(s));
  o.alpha = 0;
  Analyzer plain(o), shifted(o);
  for (std::size_t k = 0; k < x.size(); ++k) {
    plain.add(x[k]);
    shifted.add(x[k] + 12345.678 + 987.654321 * static_cast<double>(k));
  }
  const Analysis a = plain.result(), b = shifted.result();
  ASSERT_EQ(a.rows.size(), b.rows.size());
  ASSERT_GT(a.rows.size(), 40u);
  for (std::size_t i = 0; i < a.rows.size(); ++i) {
    EXPECT_EQ(a.rows[i].n, b.rows[i].n);
    EXPECT_NEAR(b.rows[i].dev / a.rows[i].dev, 1.0, 1e-9) << name(a.rows[i].stat) << " m=" << a.rows[i].m;
  }
}

TEST(AnalyzeEngine, FrequencyOffsetChangesNoTotalStatistic) {
  // Oracle: the total family is blind to a line in phase, that is to a constant added to frequency
  // (second or higher differences, line-free sub-sequences, reflections at the ends that continue a
  // line). The values lie on a grid of 2^-60 and so does the offset (3 2^-22, about 7e-7 against
  // noise of about 1e-14), so each offset value is exact in double and the two inputs differ by
  // the offset alone. A plain running sum of the frequencies loses the rounding of the ramp's size
  // at each step (measured before the record took the first frequency out: up to 8.1e-6 here,
  // 1.08e-10 on the OCXO reference set at its 1.26e-8 offset). Both engines that hold the record.
  std::mt19937_64 rng(5);
  const double grid = std::ldexp(1.0, -60), offset = 3.0 * std::ldexp(1.0, -22);
  std::vector<double> y;
  std::int64_t walk = 0;
  for (int k = 0; k < 20000; ++k) {
    walk += static_cast<std::int64_t>(rng() % 201) - 100;                         // random-walk FM
    const std::int64_t white = static_cast<std::int64_t>(rng() % 20001) - 10000;  // white FM
    y.push_back(static_cast<double>(walk + white) * grid);
  }
  for (const bool held : {false, true}) {
    AnalysisOptions o;
    o.type = DataType::freq;
    o.stats = {DevStat::totdev, DevStat::mtotdev, DevStat::ttotdev, DevStat::htotdev, DevStat::theo1, DevStat::theoh};
    o.m_list = octave_taus(y.size() + 1);
    o.theo_m_list = theo_taus("octave", o.m_list, y.size() + 1);
    o.alpha = 0;
    o.hold_phase = held;
    o.values_hint = y.size();
    Analyzer plain(o), shifted(o);
    for (const double v : y) {
      plain.add(v);
      shifted.add(v + offset);
    }
    const Analysis a = plain.result(), b = shifted.result();
    ASSERT_EQ(a.rows.size(), b.rows.size());
    ASSERT_GT(a.rows.size(), 60u);
    for (std::size_t i = 0; i < a.rows.size(); ++i) {
      EXPECT_EQ(a.rows[i].n, b.rows[i].n);
      EXPECT_NEAR(b.rows[i].dev / a.rows[i].dev, 1.0, 1e-14)
          << name(a.rows[i].stat) << " m=" << a.rows[i].m << (held ? " (held phase)" : "");
    }
  }
}

TEST(AnalyzeEngine, CountsEqualTheirPhaseExactly) {
  // Counts c_k and the phase x_k = sum_{i<k} c_i (with x_0 = 0) are the same data: equal n and
  // deviations (oracle: the definitions; integer phase below 2^53 is exact in double as well).
  // Counts' TOTDEV takes its unreflected terms from the exact AVAR sums, phase's sums them.
  std::mt19937_64 rng(3);
  std::uniform_int_distribution<int> count(-1000, 1000);
  AnalysisOptions o;
  o.m_list = {1, 3, 16, 100};
  o.stats = {DevStat::adev, DevStat::oadev, DevStat::mdev, DevStat::hdev, DevStat::ohdev, DevStat::totdev};
  o.alpha = 0;
  AnalysisOptions p = o;
  o.type = DataType::counts;
  Analyzer counts(o), phase(p);
  double x = 0;
  phase.add(x);
  for (int k = 0; k < 3000; ++k) {
    const int c = count(rng) + 5000;
    counts.add(c);
    x += c;
    phase.add(x);
  }
  const Analysis a = counts.result(), b = phase.result();
  ASSERT_EQ(a.rows.size(), b.rows.size());
  for (std::size_t i = 0; i < a.rows.size(); ++i) {
    EXPECT_EQ(a.rows[i].n, b.rows[i].n);
    EXPECT_NEAR(a.rows[i].dev / b.rows[i].dev, 1.0, 1e-12) << name(a.rows[i].stat) << " m=" << a.rows[i].m;
  }
  EXPECT_EQ(a.n_phase, 3001u);
  EXPECT_EQ(a.n_values, 3000u);
}

TEST(AnalyzeEngine, HeldCountsGiveTheCharacterizersRowsBitForBit) {
  // The batch path (hold_counts: core/batch.hpp over the held record) against the characterizer
  // at the same stride factor (oracle: the characterizer, itself checked against brute force in
  // tests/core): a gyro's counts, then a rate step that takes the residuals beyond int32, every
  // overlapping and non-overlapping statistic with its noise identification, EDF and interval.
  std::mt19937_64 rng(11);
  std::vector<double> counts;
  for (int k = 0; k < 3000; ++k) counts.push_back(3600.0 + static_cast<double>(rng() % 21) - 10.0);
  for (int k = 0; k < 3000; ++k) counts.push_back(2.0e6 + static_cast<double>(rng() % 2001));
  for (const bool step : {false, true}) {
    const std::size_t n = step ? counts.size() : 3000;
    AnalysisOptions o;
    o.type = DataType::counts;
    o.stats = {DevStat::adev, DevStat::oadev, DevStat::mdev, DevStat::tdev, DevStat::hdev, DevStat::ohdev, DevStat::totdev};
    o.stride_factor = full_stride_factor(n + 1);
    o.m_list = octave_taus(n + 1);
    Analyzer pyramid(o);
    o.hold_counts = true;
    o.values_hint = n;
    o.threads = 3;  // the taus shared among three threads on any machine
    Analyzer batch(o);
    pyramid.add(std::span<const double>(counts.data(), n));
    // The batch engine in uneven blocks: the first count alone, then 7, then the rest.
    batch.add(std::span<const double>(counts.data(), 1));
    batch.add(std::span<const double>(counts.data() + 1, 7));
    batch.add(std::span<const double>(counts.data() + 8, n - 8));
    const Analysis a = pyramid.result(), b = batch.result();
    ASSERT_EQ(a.rows.size(), b.rows.size());
    ASSERT_GT(a.rows.size(), 40u);
    for (std::size_t i = 0; i < a.rows.size(); ++i) {
      const AnalysisRow &x = a.rows[i], &y = b.rows[i];
      EXPECT_TRUE(x.stat == y.stat && x.m == y.m && x.n == y.n && x.dev == y.dev && x.alpha == y.alpha && x.edf == y.edf &&
                  x.skew_dof == y.skew_dof && x.ci.low == y.ci.low && x.ci.high == y.ci.high)
          << name(x.stat) << " m=" << x.m << (step ? " after the step" : "");
    }
  }
}

TEST(AnalyzeEngine, HeldPhaseGivesTheCharacterizersRowsForEveryTau) {
  // --taus all on phase and frequency data: the batch path (hold_phase: core/float_batch.hpp over
  // the held record) against the characterizer (oracle: itself checked against brute force in
  // tests/core) at the stride factor "full" gives --taus all, every tau of 3000 values. With the
  // prefix sums (float_batch_taus()) the terms are the characterizer's to the last bit and their
  // sums of squares are summed in another order: a deviation within n DBL_EPSILON relative (twice
  // the bound (n - 1) u of two orders of n non-negative terms, halved by the square root). Without
  // (phase_batch_taus()) AVAR and HVAR are its sums to the bit and the MVAR terms are within u of
  // the exact ones where the characterizer's are within a few u: the same bound holds. Counts,
  // noise and EDF the same.
  std::mt19937_64 rng(5);
  std::normal_distribution<double> g;
  std::vector<double> clock;  // phase: offset, frequency, random-walk FM, white PM
  double y = 2e-8, x = 17.0;
  for (int k = 0; k < 3000; ++k) {
    y += 1e-11 * g(rng);
    x += y;
    clock.push_back(x + 3e-10 * g(rng));
  }
  for (const bool prefix_sums : {true, false})  // float_batch_taus() (--taus all), phase_batch_taus()
    for (const DataType type : {DataType::phase, DataType::freq}) {
      const std::size_t n_phase = type == DataType::phase ? clock.size() : clock.size() + 1;
      AnalysisOptions o;
      o.type = type;
      o.tau0_s = 0.5;
      o.stats = {DevStat::adev, DevStat::oadev, DevStat::mdev, DevStat::tdev, DevStat::hdev, DevStat::ohdev};
      o.stride_factor = full_stride_factor(2 * n_phase);  // as gyrochar-analyze takes it for --taus all
      o.m_list = all_taus(n_phase, o.stride_factor);
      ASSERT_EQ(o.m_list.size(), n_phase / 2);
      Analyzer pyramid(o);
      o.hold_phase = true;
      o.hold_prefix_sums = prefix_sums;
      o.values_hint = clock.size();
      o.threads = 3;
      std::size_t told = 0, total = 0;
      o.on_progress = [&](const char* stage, std::size_t done, std::size_t of) {
        EXPECT_STREQ(stage, "summing");
        EXPECT_GT(done, told);
        told = done;
        total = of;
      };
      Analyzer batch(o);
      pyramid.add(clock);
      batch.add(std::span<const double>(clock.data(), 1));
      batch.add(std::span<const double>(clock.data() + 1, clock.size() - 1));
      const Analysis a = pyramid.result(), b = batch.result();
      EXPECT_EQ(told, o.m_list.size());
      EXPECT_EQ(total, o.m_list.size());
      EXPECT_EQ(b.n_phase, a.n_phase);
      EXPECT_EQ(b.n_values, a.n_values);
      ASSERT_EQ(a.rows.size(), b.rows.size());
      ASSERT_GT(a.rows.size(), 4000u);
      for (std::size_t i = 0; i < a.rows.size(); ++i) {
        const AnalysisRow &p = a.rows[i], &q = b.rows[i];
        const double tolerance = static_cast<double>(p.n) * DBL_EPSILON * p.dev;
        EXPECT_TRUE(p.stat == q.stat && p.m == q.m && p.n == q.n && p.alpha == q.alpha && p.edf == q.edf &&
                    std::fabs(p.dev - q.dev) <= tolerance)
            << name(type) << (prefix_sums ? " prefix sums " : " ") << name(p.stat) << " m=" << p.m << ": " << p.dev << " vs "
            << q.dev;
      }
    }
}

// Random-walk phase (unit steps) plus white phase noise of the given size.
std::vector<double> walk_and_white(int n, std::uint64_t seed, double white) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g;
  std::vector<double> x;
  double walk = 0;
  for (int k = 0; k < n; ++k) x.push_back((walk += g(rng)) + white * g(rng));
  return x;
}

TEST(AnalyzeEngine, TheTotalFamilyOnTwoThreadsGivesTheBitsOfOne) {
  // Oracle: the same analysis on one thread. Each tau's estimate is made alone, on its own view of
  // the prepared record (its own FFT buffer and scratch) or reading the record only, and TheoBR's
  // ratio sums its taus in order (rows.hpp), so every row is the same bits on two threads: a shared
  // buffer or a sum in another order would show here. Both the lag sums and the decimated plan.
  const std::vector<double> x = walk_and_white(6000, 11, 10);
  for (const bool decimated : {false, true}) {
    const auto analysis = [&](unsigned threads) {
      AnalysisOptions o;
      o.type = DataType::phase;
      o.stats = {DevStat::oadev,   DevStat::mdev,    DevStat::totdev, DevStat::mtotdev,
                 DevStat::ttotdev, DevStat::htotdev, DevStat::theo1,  DevStat::theoh};
      o.m_list = octave_taus(x.size());
      o.theo_m_list = theo_taus("octave", o.m_list, x.size());
      o.total_stride_factor = 4;  // the decimated plan decimates from m = 8 on
      o.theo_decimated = o.total_decimated = decimated;
      o.threads = threads;
      o.values_hint = x.size();
      Analyzer a(o);
      for (const double v : x) a.add(v);
      return a.result();
    };
    const Analysis one = analysis(1), two = analysis(2);
    ASSERT_EQ(one.rows.size(), two.rows.size());
    ASSERT_GT(one.rows.size(), 60u);
    for (std::size_t i = 0; i < one.rows.size(); ++i) {
      EXPECT_EQ(one.rows[i].m, two.rows[i].m);
      EXPECT_EQ(one.rows[i].stride, two.rows[i].stride);
      EXPECT_EQ(one.rows[i].dev, two.rows[i].dev)
          << name(one.rows[i].stat) << " m=" << one.rows[i].m << (decimated ? " (decimated)" : "");
    }
  }
}

TEST(AnalyzeEngine, TheTotalFamilyTellsHowFarItIsAndStopsWhenTold) {
  // Oracle: AnalysisOptions::on_progress's contract. Each statistic of the total family is a stage
  // (TheoH two: its bias ratio's taus, then its Theo1 taus) whose count rises to its total, told
  // once with done = total, in the order of --stats; what the callback throws in any stage comes
  // out of result(), on one thread and on two. The bias ratio's taus run in core, which the
  // exception must not cross: it is held until core returns.
  const std::vector<double> x = walk_and_white(6000, 11, 10);
  struct Stop {};
  for (const unsigned threads : {1u, 2u})
    for (const std::string stop_at : {"", "totdev", "theoh bias ratio", "theoh"}) {
      AnalysisOptions o;
      o.type = DataType::phase;
      o.stats = {DevStat::oadev, DevStat::totdev, DevStat::theoh};
      o.m_list = octave_taus(x.size());
      o.theo_m_list = theo_taus("octave", o.m_list, x.size());
      o.threads = threads;
      std::vector<std::string> ended;
      std::map<std::string, std::size_t> told;
      o.on_progress = [&](const char* stage, std::size_t done, std::size_t total) {
        EXPECT_GT(done, told[stage]) << stage;
        EXPECT_LE(done, total) << stage;
        told[stage] = done;
        if (done == total) ended.push_back(stage);
        if (stage == stop_at) throw Stop{};
      };
      Analyzer a(o);
      for (const double v : x) a.add(v);
      if (stop_at.empty()) {
        EXPECT_GT(a.result().rows.size(), 20u);
        EXPECT_EQ(ended, (std::vector<std::string>{"totdev", "theoh bias ratio", "theoh"})) << threads;
        EXPECT_GT(told["theoh bias ratio"], 1u);
      } else {
        EXPECT_THROW(a.result(), Stop) << stop_at << ", " << threads << " threads";
      }
    }
}

TEST(AnalyzeEngine, TheFitsLongTauPointsReuseTheoHsBiasRatio) {
  // Oracle: the fit's TheoBR points with the bias ratio computed afresh (an Analysis that kept
  // none). TheoH's rows keep their ratio (Analysis::theoh_bias, at their stride factor, 16 by
  // default); the fit's long-tau points, whose stride factor is 16 too, reuse it: the same bits. A
  // different ratio kept changes those points in proportion, so it is the one they read.
  const std::vector<double> x = walk_and_white(20000, 12, 3);
  AnalysisOptions o;
  o.type = DataType::phase;
  o.stats = {DevStat::oadev, DevStat::mdev, DevStat::theoh};
  o.m_list = octave_taus(x.size());
  o.theo_m_list = theo_taus("octave", o.m_list, x.size());
  Analyzer analyzer(o);
  for (const double v : x) analyzer.add(v);
  const Analysis kept = analyzer.result();
  ASSERT_GT(kept.theoh_bias.ratio, 0.0);
  EXPECT_EQ(kept.theoh_bias.stride_factor, 16u);
  Analysis fresh = kept, doubled = kept;
  fresh.theoh_bias = {};
  doubled.theoh_bias.ratio *= 2;
  const ReportUnits units;
  const auto points = [&](const Analysis& a) { return fit_points(a, units, 1.0, LongTau::theoh, analyzer.record()); };
  const std::vector<FitPoint> reused = points(kept), afresh = points(fresh), twice = points(doubled);
  ASSERT_EQ(reused.size(), afresh.size());
  ASSERT_EQ(twice.size(), afresh.size());
  std::size_t long_tau = 0;
  for (std::size_t i = 0; i < afresh.size(); ++i) {
    EXPECT_EQ(reused[i].variance, afresh[i].variance) << i;
    if (afresh[i].variance_scale == 1.0) continue;  // an Allan-family point: no ratio in it
    ++long_tau;
    EXPECT_DOUBLE_EQ(twice[i].variance, 2 * afresh[i].variance) << i;
  }
  EXPECT_GE(long_tau, 2u);
}

TEST(AnalyzeEngine, HeldCountsPastTheirReserveAreTheSameBits) {
  // Oracle: the same counts held under a bound that holds them. Under a short bound (a gzip
  // member's stated size can be one) the held residuals move past their reserve while their pages
  // are being faulted in ahead (held_memory.hpp's Prefault, from 4 MiB on): every row is the same
  // bits, with int32 residuals and across the switch to int64 ones.
  const std::size_t n = std::size_t{3} << 20;
  std::mt19937_64 rng(5);
  std::vector<double> counts(n);
  for (double& c : counts) c = 3600.0 + static_cast<double>(rng() % 21) - 10.0;
  for (const bool step : {false, true}) {
    if (step)
      for (std::size_t k = n / 2; k < n; ++k) counts[k] += 2.0e6;  // residuals past int32 within 1100 counts
    const auto analysis = [&](std::uint64_t hint) {
      AnalysisOptions o;
      o.type = DataType::counts;
      o.stats = {DevStat::oadev, DevStat::mdev};
      o.stride_factor = full_stride_factor(n + 1);
      o.m_list = octave_taus(n + 1);
      o.hold_counts = true;
      o.values_hint = hint;
      Analyzer a(o);
      for (std::size_t k = 0; k < n; k += std::size_t{1} << 16)
        a.add(std::span<const double>(counts.data() + k, std::min(std::size_t{1} << 16, n - k)));
      return a.result();
    };
    const Analysis held = analysis(n), outgrown = analysis((std::size_t{1} << 20) + 10);
    ASSERT_EQ(held.rows.size(), outgrown.rows.size());
    ASSERT_GT(held.rows.size(), 30u);
    for (std::size_t i = 0; i < held.rows.size(); ++i)
      EXPECT_EQ(held.rows[i].dev, outgrown.rows[i].dev)
          << name(held.rows[i].stat) << " m=" << held.rows[i].m << " step " << step;
  }
}

TEST(AnalyzeEngine, GroupSumsAreTheRecordsBlockSumsNarrowOrWide) {
  // Oracle: the sums over each group written out modulo 2^64 from the record, and the lag table of
  // the record's own block sums (total_lags.hpp's group), which counts' decimated MTOTDEV read
  // from GroupSums instead: the same integers, so the same tables bit for bit. A record whose
  // group sums all fit in int32 keeps them narrow; one that passes 2^31 goes wide from the group
  // it passes on, keeping the sums before it; a record of doubles has none.
  std::mt19937_64 rng(5);
  std::uniform_int_distribution<std::int32_t> step(-40, 40);
  std::vector<std::int32_t> small{0}, large{0};
  for (int i = 0; i < 20000; ++i) small.push_back(small.back() + step(rng));
  for (int i = 0; i < 20000; ++i)
    large.push_back(i < 9000 ? step(rng) : (1 << 29) + step(rng));  // four sum to about 2^31: some pass it
  const std::vector<std::int64_t> wide(large.begin(), large.end());
  std::vector<std::int64_t> huge(wide);  // groups of 16 whose sums pass 2^63: modulo 2^64, no overflow
  for (std::int64_t& v : huge) v += std::int64_t{1} << 61;
  std::vector<ExactSum> held_work, direct_work;
  for (const auto& [record, g, narrow] : {std::tuple{PhaseSpan(small), 16u, true}, std::tuple{PhaseSpan(small), 64u, true},
                                          std::tuple{PhaseSpan(large), 4u, false}, std::tuple{PhaseSpan(wide), 64u, false},
                                          std::tuple{PhaseSpan(huge), 16u, false}}) {
    const GroupSums held(record, g);
    EXPECT_EQ(held.group(), g);
    const PhaseSpan sums = held.sums();
    ASSERT_EQ(sums.size(), record.size() / g) << g;
    record.visit([&](auto x) {
      sums.visit([&](auto y) {
        using Held = typename decltype(y)::value_type;
        EXPECT_EQ((std::is_same_v<Held, std::int32_t>), narrow) << g;
        for (std::size_t k = 0; k < y.size(); ++k) {
          std::uint64_t want = 0;
          for (std::size_t i = k * g; i < (k + 1) * g; ++i)
            want += static_cast<std::uint64_t>(static_cast<std::int64_t>(x[i]));
          ASSERT_EQ(static_cast<std::uint64_t>(static_cast<std::int64_t>(y[k])), want) << "group " << k << " of " << g;
        }
      });
    });
    for (const std::uint64_t k : {1u, 2u, 4u}) {
      held_work.resize(lag_table_size(22));
      direct_work.resize(lag_table_size(22));
      const LagTable from_held = lag_table(sums, 2, 22, held_work, nullptr, k);
      const LagTable direct = lag_table(record, 2, 22, direct_work, nullptr, k * g);
      ASSERT_EQ(from_held.ready, direct.ready) << g << " x " << k;
      ASSERT_EQ(from_held.values, direct.values);
      for (std::size_t d = 0; d < direct.total.size(); ++d) {
        EXPECT_EQ(from_held.total[d].hi, direct.total[d].hi) << d;
        EXPECT_EQ(from_held.total[d].lo, direct.total[d].lo) << d;
      }
      for (std::size_t i = 0; i < direct.head.size(); ++i) {
        EXPECT_EQ(from_held.head[i].hi, direct.head[i].hi) << i;
        EXPECT_EQ(from_held.tail[i].hi, direct.tail[i].hi) << i;
      }
    }
  }
  const std::vector<double> doubles(1000, 1.0);
  EXPECT_EQ(GroupSums(PhaseSpan(doubles), 16).sums().size(), 0u);
}

TEST(AnalyzeEngine, LagSumWorkspacesAreWholeOrRefused) {
  // uninitialized_doubles()'s contract (held_memory.hpp): n doubles, every one writable; an impossible size
  // is std::bad_alloc, never a short buffer.
  for (const std::size_t n :
       {std::size_t{0}, std::size_t{1}, std::size_t{1000}, std::size_t{1} << 20, (std::size_t{3} << 20) + 5}) {
    const UninitializedDoubles a = uninitialized_doubles(n);
    ASSERT_NE(a.get(), nullptr) << n;
    for (std::size_t i = 0; i < n; i += 4096) a[i] = static_cast<double>(i);
    if (n > 0) a[n - 1] = 1.0;
  }
  EXPECT_THROW(uninitialized_doubles(std::numeric_limits<std::size_t>::max() / 4), std::bad_alloc);
}

// Oracle: held_memory.hpp's contract. From 4 MiB on a buffer starts on a 2 MiB huge-page boundary
// (where the kernel can map it in huge pages); below that it is malloc's. A held vector that
// grows across the boundary keeps its values.
TEST(AnalyzeEngine, HeldMemoryIsAlignedToHugePagesFromFourMiB) {
  constexpr std::size_t huge = std::size_t{1} << 21;
  for (const std::size_t bytes : {2 * huge, 2 * huge + 1, 5 * huge + 8}) {
    void* p = allocate_held(bytes);
    EXPECT_EQ(reinterpret_cast<std::uintptr_t>(p) % huge, 0u) << bytes;
    static_cast<unsigned char*>(p)[bytes - 1] = 1;  // the whole size is ours
    std::free(p);
  }
  void* small = allocate_held(100);
  ASSERT_NE(small, nullptr);
  std::free(small);
  Held<std::int32_t> v;
  for (std::int32_t i = 0; i < (1 << 21) + 5; ++i) v.push_back(i);  // 8 MiB: past the boundary
  EXPECT_EQ(reinterpret_cast<std::uintptr_t>(v.data()) % huge, 0u);
  for (std::int32_t i = 0; i < (1 << 21) + 5; i += 4099) ASSERT_EQ(v[static_cast<std::size_t>(i)], i);
  EXPECT_THROW((void)allocate_held(SIZE_MAX - 10), std::bad_alloc);
}

// Oracle: mincore(2), the kernel's own account of which pages are in memory, and the values
// written. Prefault (held_memory.hpp) brings in the pages up to its lead past what is written,
// not the rest of the buffer, and never changes what the writer wrote, while both run. A buffer
// below 4 MiB is left alone.
TEST(AnalyzeEngine, PrefaultBringsInThePagesAheadOfTheWriterAndNoMore) {
  constexpr std::size_t mib = std::size_t{1} << 20, bytes = 64 * mib;
  void* p = allocate_held(bytes);
  auto* v = static_cast<std::uint32_t*>(p);
  const auto resident = [&](std::size_t from, std::size_t to) {  // every 4 KiB page of [from, to)
    std::vector<unsigned char> in((to - from) / 4096);
    EXPECT_EQ(mincore(static_cast<char*>(p) + from, to - from, in.data()), 0);
    return std::all_of(in.begin(), in.end(), [](unsigned char c) { return (c & 1) != 0; });
  };
  const auto nothing_in = [&](std::size_t from, std::size_t to) {
    std::vector<unsigned char> in((to - from) / 4096);
    EXPECT_EQ(mincore(static_cast<char*>(p) + from, to - from, in.data()), 0);
    return std::none_of(in.begin(), in.end(), [](unsigned char c) { return (c & 1) != 0; });
  };
  {
    Prefault ahead;
    ahead.start(p, bytes);
    const std::size_t written = 4 * mib;
    for (std::size_t i = 0; i < written / 4; ++i) v[i] = static_cast<std::uint32_t>(i * 2654435761u);
    ahead.written(written);
    bool in = false;  // the thread's work: waited for, at most 10 s
    for (int tries = 0; tries < 1000 && !(in = resident(written, written + Prefault::lead)); ++tries)
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    EXPECT_TRUE(in);
    EXPECT_TRUE(nothing_in(written + Prefault::lead + 2 * mib, bytes));  // past the lead, rounded to 2 MiB
    for (std::size_t i = written / 4; i < bytes / 4; ++i) {              // the rest, the thread running beside
      v[i] = static_cast<std::uint32_t>(i * 2654435761u);
      if (i % (1 << 18) == 0) ahead.written(4 * i);
    }
  }
  for (std::size_t i = 0; i < bytes / 4; ++i) ASSERT_EQ(v[i], static_cast<std::uint32_t>(i * 2654435761u)) << i;
  std::free(p);
  void* small = allocate_held(mib);
  Prefault none;
  none.start(small, mib);
  none.written(0);  // nothing to do, nothing to wait for
  std::free(small);
}

}  // namespace
}  // namespace gyrochar
