// The dynamic Allan deviation offline (host_tools/analyze/dynamic.hpp): every window is what the
// analyzer gives for its values cut out into a file of their own, stepped or overlapping, and a
// simulated gyro whose angle random walk doubles halfway shows it, in the windows after the change
// and in none before.
// Oracles: an Analyzer fed each window's values alone (the same computation, so the same rows to
// the last bit); the closed-form Allan variance of white rate noise and white quantization,
// AVAR = N^2 / tau + 3 Q^2 / tau^2 with Q = pulse / sqrt(12) (design brief section 3), in each
// segment of the simulation.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "dynamic.hpp"
#include "sim_truth.hpp"

namespace gyrochar {
namespace {

AnalysisOptions options(DataType type, const std::vector<std::uint64_t>& m_list) {
  AnalysisOptions o;
  o.type = type;
  o.tau0_s = 0.01;
  o.m_list = m_list;
  o.stride_factor = 8;
  return o;
}

void expect_same_rows(const Analysis& a, const Analysis& b) {
  ASSERT_EQ(a.rows.size(), b.rows.size());
  EXPECT_EQ(a.n_values, b.n_values);
  for (std::size_t i = 0; i < a.rows.size(); ++i) {
    EXPECT_EQ(a.rows[i].stat, b.rows[i].stat);
    EXPECT_EQ(a.rows[i].m, b.rows[i].m);
    EXPECT_EQ(a.rows[i].n, b.rows[i].n);
    EXPECT_EQ(a.rows[i].dev, b.rows[i].dev) << "row " << i;
    EXPECT_EQ(a.rows[i].edf, b.rows[i].edf) << "row " << i;
  }
}

TEST(Dynamic, WindowTausReachAQuarterOfTheWindow) {
  EXPECT_EQ(window_taus({1, 2, 4, 8, 16, 32}, 64), (std::vector<std::uint64_t>{1, 2, 4, 8, 16}));
  EXPECT_EQ(window_taus({1, 2, 4}, 3), std::vector<std::uint64_t>{});
  EXPECT_EQ(window_taus({1, 10, 100}, 400), (std::vector<std::uint64_t>{1, 10, 100}));
}

TEST(Dynamic, EveryWindowIsItsValuesAnalysedAlone) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::vector<double> freq(2600), counts(2600);
  for (std::size_t k = 0; k < freq.size(); ++k) {
    freq[k] = 1e-9 * noise(rng) + (k > 1300 ? 3e-9 : 0.0);
    counts[k] = std::round(100 + 4 * noise(rng));
  }
  const std::vector<std::uint64_t> taus = window_taus(octave_taus(1001), 1000);
  for (const auto& [type, values] :
       {std::pair{DataType::freq, &freq}, std::pair{DataType::counts, &counts}, std::pair{DataType::phase, &freq}}) {
    for (const std::uint64_t step : {std::uint64_t{1000}, std::uint64_t{300}}) {
      DynamicAnalyzer dynamic(options(type, taus), 1000, step);
      std::vector<WindowAnalysis> windows;
      for (const double v : *values) {
        dynamic.add(v);
        for (WindowAnalysis& w : dynamic.take_completed()) windows.push_back(std::move(w));
      }
      // Windows j step .. j step + 999 that fit in 2600 values: floor((2600 - 1000) / step) + 1.
      ASSERT_EQ(windows.size(), (2600 - 1000) / step + 1) << name(type) << " step " << step;
      for (std::size_t j = 0; j < windows.size(); ++j) {
        EXPECT_EQ(windows[j].index, j);
        EXPECT_EQ(windows[j].first_value, j * step);
        Analyzer alone(options(type, taus));
        for (std::size_t k = j * step; k < j * step + 1000; ++k) alone.add((*values)[k]);
        expect_same_rows(windows[j].analysis, alone.result());
      }
    }
  }
}

TEST(Dynamic, RefusesAWindowOrStepOfNothing) {
  EXPECT_THROW(DynamicAnalyzer(options(DataType::counts, {1}), 0, 1), std::invalid_argument);
  EXPECT_THROW(DynamicAnalyzer(options(DataType::counts, {1}), 8, 0), std::invalid_argument);
  EXPECT_THROW(DynamicAnalyzer(options(DataType::counts, {}), 8, 8), std::invalid_argument);
}

// The simulated gyro of the DAVAR tests: 1 arcsec pulses every 10 ms, angle random walk N, white
// (the ARW moves the angle by 1.2 pulses per sample at the start), doubling at `change_s`.
SimOptions doubling_gyro(double duration_s, double change_s) {
  SimOptions o;
  o.duration_s = duration_s;
  o.tau0_s = 0.01;
  o.pulse_arcsec = 1.0;
  o.arw_deg_per_sqrt_h = 0.2;
  o.seed = 21;
  SimSegment g;
  g.start_s = change_s;
  g.arw_deg_per_sqrt_h = 0.4;
  o.segments = {g};
  return o;
}

// ADEV in arcsec/s of white rate noise N (deg/sqrt(h)) and white quantization of 1 arcsec pulses.
double closed_form_adev(double n_deg_per_sqrt_h, double tau_s) {
  const double n = n_deg_per_sqrt_h * 60.0;  // arcsec/sqrt(s)
  const double q = 1.0 / std::sqrt(12.0);    // arcsec
  return std::sqrt(n * n / tau_s + 3 * q * q / (tau_s * tau_s));
}

TEST(Dynamic, AGyroWhoseAngleRandomWalkDoublesHalfwayShowsItFromTheWindowAfter) {
  // 16 windows of 60 s; N doubles at 480 s, the start of window 8. At the taus where N dominates
  // (0.16 .. 1.28 s: the quantization is below 1 % of the AVAR), every window's ADEV lies within
  // 4 of its standard errors (1 / sqrt(2 EDF), from the window's own EDF) of its segment's closed
  // form, and so does each half's mean over its eight windows (standard error 1 / sqrt(16 EDF)).
  // Counts of 1 arcsec pulses: the deviations come out in arcsec/s.
  const SimOptions o = doubling_gyro(960, 480);
  SimRun run(o);
  const std::vector<std::uint64_t> taus{16, 32, 64, 128};
  DynamicAnalyzer dynamic(options(DataType::counts, taus), 6000, 6000);
  std::vector<WindowAnalysis> windows;
  for (std::uint64_t k = 0; k < run.samples(); ++k) {
    dynamic.add(static_cast<double>(run.next_count()));
    for (WindowAnalysis& w : dynamic.take_completed()) windows.push_back(std::move(w));
  }
  ASSERT_EQ(windows.size(), 16u);
  for (const std::uint64_t m : taus) {
    const double tau_s = static_cast<double>(m) * 0.01;
    double mean[2] = {0, 0}, edf = 0;
    for (const WindowAnalysis& w : windows) {
      const std::size_t half = w.index < 8 ? 0 : 1;
      const double expected = closed_form_adev(half == 0 ? 0.2 : 0.4, tau_s);
      for (const AnalysisRow& row : w.analysis.rows) {
        if (row.stat != DevStat::oadev || row.m != m) continue;
        ASSERT_GT(row.edf, 10.0);
        EXPECT_NEAR(row.dev / expected, 1.0, 4 / std::sqrt(2 * row.edf)) << "window " << w.index << " tau " << tau_s;
        mean[half] += row.dev / 8;
        edf = row.edf;
      }
    }
    EXPECT_NEAR(mean[0] / closed_form_adev(0.2, tau_s), 1.0, 4 / std::sqrt(16 * edf)) << tau_s;
    EXPECT_NEAR(mean[1] / closed_form_adev(0.4, tau_s), 1.0, 4 / std::sqrt(16 * edf)) << tau_s;
    EXPECT_GT(mean[1] / mean[0], 1.7) << "the doubling shows at " << tau_s << " s";
  }
}

}  // namespace
}  // namespace gyrochar
