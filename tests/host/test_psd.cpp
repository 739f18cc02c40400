// The analyzer's Welch PSD and its sinusoid search (host_tools/analyze/psd.hpp) against exact
// oracles: Parseval's identity for one segment, white noise of known variance (one-sided PSD
// 2 sigma^2 tau0, each bin distributed as chi2_nu / nu with Welch's nu), a sinusoid's power A^2/2.
#include <gtest/gtest.h>

#include <algorithm>
#include <boost/math/distributions/chi_squared.hpp>
#include <cmath>
#include <complex>
#include <numbers>
#include <random>
#include <span>
#include <vector>

#include "analysis.hpp"
#include "psd.hpp"

namespace {

using namespace gyrochar;

std::vector<double> white(std::size_t n, double sigma, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, sigma);
  std::vector<double> x(n);
  for (double& v : x) v = g(rng);
  return x;
}

TEST(WelchPsd, OneSegmentObeysParseval) {
  // Oracle: Parseval for the DFT of the windowed, mean-removed segment, computed here directly:
  // sum over k = 1 .. L/2-1 of PSD df = (sum (x w)^2 - (X_0^2 + X_{L/2}^2) / L) / sum w^2.
  const std::size_t L = 256;
  const double tau0 = 0.1;
  std::vector<double> x = white(L, 2.0, 7);
  for (std::size_t n = 0; n < L; ++n) x[n] += 5 + std::sin(0.3 * static_cast<double>(n));
  const Psd p = welch_psd(x, tau0, L, 0.683);
  ASSERT_EQ(p.segments, 1u);
  ASSERT_EQ(p.psd.size(), L / 2 - 1);
  double mean = 0;
  for (const double v : x) mean += v / static_cast<double>(L);
  double energy = 0, w2 = 0, x0 = 0, xn = 0;
  for (std::size_t n = 0; n < L; ++n) {
    const double w = std::pow(std::sin(std::numbers::pi * static_cast<double>(n) / static_cast<double>(L)), 2);
    const double y = (x[n] - mean) * w;
    energy += y * y;
    w2 += w * w;
    x0 += y;
    xn += n % 2 ? -y : y;
  }
  double sum = 0;
  for (const double v : p.psd) sum += v * p.bin_hz();
  EXPECT_NEAR(sum, (energy - (x0 * x0 + xn * xn) / static_cast<double>(L)) / w2, 1e-10 * sum);
}

TEST(WelchPsd, WhiteNoiseIsFlatAt2Sigma2Tau0WithinWelchsBand) {
  // Oracle: white noise of variance sigma^2 sampled every tau0 has the one-sided PSD 2 sigma^2
  // tau0; each bin is PSD chi2_nu / nu, nu = 36 K^2 / (19 K - 1) (Percival and Walden eq. 292b).
  const double sigma = 1.5, tau0 = 0.01, truth = 2 * sigma * sigma * tau0;
  const std::vector<double> x = white(1 << 18, sigma, 11);
  const std::size_t L = default_psd_segment(x.size());
  EXPECT_EQ(L, 16384u);  // 2^18 / 16
  const Psd p = welch_psd(x, tau0, L, 0.683);
  EXPECT_EQ(p.segments, 2 * (x.size() / L) - 1);
  const double K = static_cast<double>(p.segments);
  EXPECT_DOUBLE_EQ(p.edf, 36 * K * K / (19 * K - 1));
  double mean = 0, var = 0;
  std::size_t inside = 0;
  for (std::size_t k = 0; k < p.psd.size(); ++k) {
    mean += p.psd[k] / truth;
    var += std::pow(p.psd[k] / truth - 1, 2);
    inside += p.ci_low(k) <= truth && truth <= p.ci_high(k);
  }
  const double bins = static_cast<double>(p.psd.size());
  mean /= bins;
  var /= bins;
  // The mean of 8191 bins (about 4000 independent: neighbours correlate 4/9) within 1 %.
  EXPECT_NEAR(mean, 1.0, 0.01);
  // The spread of a bin is chi2_nu / nu's: variance 2 / nu (within 10 %: the variance of ~4000 draws).
  EXPECT_NEAR(var, 2 / p.edf, 0.1 * 2 / p.edf);
  // The 68.3 % band holds the truth in 68.3 % of the bins, within 3 % (about 4 standard errors).
  EXPECT_NEAR(static_cast<double>(inside) / bins, 0.683, 0.03);
  // No sinusoid in white noise (the search's false-alarm rate is 1 % per record).
  EXPECT_TRUE(find_sinusoids(p).peaks.empty());
}

TEST(WelchPsd, ASinusoidsPowerIsHalfItsAmplitudeSquaredAndIsFound) {
  // Oracle: a sinusoid of amplitude A has mean power A^2 / 2; its frequency is the one generated.
  const double A = 3.0, f = 1.2345, tau0 = 0.01, sigma = 0.5;
  std::vector<double> x = white(1 << 18, sigma, 5);
  for (std::size_t n = 0; n < x.size(); ++n)
    x[n] += A * std::sin(2 * std::numbers::pi * f * static_cast<double>(n) * tau0 + 0.4);
  const Psd p = welch_psd(x, tau0, default_psd_segment(x.size()), 0.683);
  const PeakSearch s = find_sinusoids(p);
  ASSERT_EQ(s.peaks.size(), 1u);
  const SpectralPeak& peak = s.peaks[0];
  EXPECT_NEAR(peak.power, A * A / 2, 0.01 * A * A / 2);
  EXPECT_NEAR(peak.amplitude, A, 3 * peak.amplitude_uncertainty);
  EXPECT_LT(peak.amplitude_uncertainty, 0.01 * A);
  EXPECT_NEAR(peak.frequency_hz, f, 0.1 * p.bin_hz());
  EXPECT_GT(peak.ratio, peak.threshold);
}

TEST(WelchPsd, EachBinsBackgroundIsTheMedianOfItsNeighbours) {
  // Oracle: the definition (psd.hpp): bin i's background is the median (the element of rank n / 2,
  // here from a whole sort) of the bins 3 to m away on either side, m = min(64, i, bins - 1 - i),
  // over chi2_nu's median / nu. Values from a small set, so that ties cross the window's edges.
  Psd p;
  p.edf = 20;
  p.tau0_s = 1;
  p.segment = 2 * 1001;
  std::mt19937_64 rng(9);
  std::uniform_int_distribution<int> level(1, 12);
  for (std::size_t k = 0; k < 1000; ++k) p.psd.push_back(0.25 * level(rng));
  const PeakSearch s = find_sinusoids(p);
  const boost::math::chi_squared chi2(p.edf);
  const double median_factor = boost::math::quantile(chi2, 0.5) / p.edf;
  std::size_t tested = 0;
  for (std::size_t i = 0; i < p.psd.size(); ++i) {
    const std::size_t m = std::min<std::size_t>({64, i, p.psd.size() - 1 - i});
    if (i < 7 || m < 6) {  // the 8th bin on, at least 4 neighbours each side
      EXPECT_TRUE(std::isnan(s.background[i])) << i;
      continue;
    }
    std::vector<double> near;
    for (std::size_t d = 3; d <= m; ++d) near.insert(near.end(), {p.psd[i - d], p.psd[i + d]});
    std::sort(near.begin(), near.end());
    ASSERT_EQ(s.background[i], near[near.size() / 2] / median_factor) << "bin " << i;
    ++tested;
  }
  EXPECT_EQ(s.bins_tested, tested);
  EXPECT_GT(tested, 900u);
}

TEST(WelchPsd, APeakIsCrossCheckedWithTheAllanNullAtOneOverF) {
  // Oracle: a sinusoid's ADEV A sin^2(x) / x, x = pi f tau, is zero at tau = 1/f (IEEE 952).
  const double f = 0.05, A = 2;
  PeakSearch s;
  s.peaks.push_back({});
  s.peaks[0].frequency_hz = f;
  std::vector<std::pair<double, double>> dense, flat, sparse;
  for (double tau = 10; tau <= 30; tau += 0.5) {
    const double x = std::numbers::pi * f * tau;
    dense.emplace_back(tau, A * std::sin(x) * std::sin(x) / x + 0.01);
    flat.emplace_back(tau, 1.0 / std::sqrt(tau));
  }
  for (double tau = 1; tau < 1000; tau *= 2) sparse.emplace_back(tau, 1.0);
  check_adev_nulls(s, dense);
  EXPECT_EQ(s.peaks[0].adev_null, 1);
  EXPECT_DOUBLE_EQ(s.peaks[0].adev_null_tau_s, 20.0);
  check_adev_nulls(s, flat);
  EXPECT_EQ(s.peaks[0].adev_null, 0);  // falling as 1/sqrt(tau): its smallest at the window's end
  s.peaks[0].adev_null = -1;
  check_adev_nulls(s, sparse);
  EXPECT_EQ(s.peaks[0].adev_null, -1);  // octave taus: no check
}

TEST(WelchPsd, RefusesASegmentThatDoesNotFit) {
  const std::vector<double> x(100, 1.0);
  EXPECT_THROW(welch_psd(x, 0.1, 128, 0.683), std::invalid_argument);
  EXPECT_THROW(welch_psd(x, 0.1, 15, 0.683), std::invalid_argument);
  EXPECT_EQ(default_psd_segment(63), 0u);
}

}  // namespace

namespace {

// Counts of an angle that moves by `per_sample` pulses a sample plus white rate noise of `s`
// pulses a sample, quantized to whole pulses (floor of the running angle, differenced).
RateRecord counted(std::size_t n, double per_sample, double s, double tau0, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, s);
  RateRecord r(false, true, tau0);
  double angle = 0.37, last = std::floor(angle);
  for (std::size_t k = 0; k < n; ++k) {
    angle += per_sample + g(rng);
    const double now = std::floor(angle), count = now - last;
    last = now;
    r.add(std::span(&count, 1));
  }
  return r;
}

}  // namespace

TEST(PulseLines, ThePatternIsReadFromTheCounts) {
  // Oracle: the construction. 0.15 pulse a sample at tau0 0.01 s is 15 pulses a second; white
  // rate noise of 0.02 pulse a sample has s^2 = 4e-4 (the blocks' means estimate it with
  // 2^20 / 2^14 = 64 blocks: relative sd of a variance sqrt(2/63) = 18 %, 3 sd allowed).
  const RateRecord r = counted(1u << 20, 0.15, 0.02, 0.01, 3);
  const PulsePattern p = pulse_pattern(r.rate(), 0.01, 1u << 14);
  EXPECT_NEAR(p.rate_hz, 15.0, 0.01);  // the mean of 2^20 counts: within a few pulses of 157 286
  EXPECT_NEAR(p.diffusion, 4e-4, 3 * 0.18 * 4e-4);
  // Harmonic 1 sits at 15 Hz; harmonic 4 (60 Hz, above the Nyquist frequency 50 Hz) folds to 40 Hz.
  EXPECT_NEAR(p.band(1, 0.006).first, p.rate_hz, 1e-12);
  EXPECT_NEAR(p.band(4, 0.006).first, 100 - 4 * p.rate_hz, 1e-9);
  // Half width of harmonic 1: pi s^2 / tau0 (the Lorentzian of a phase diffusing by (2 pi s)^2 a sample).
  EXPECT_NEAR(p.line_half_width(1), std::numbers::pi * p.diffusion / 0.01, 1e-15);
}

TEST(PulseLines, ThePulsePatternsHumpIsNotOfferedToTheFitButARateSinusoidIs) {
  // Oracle: the construction. Counts at 0.15 pulse a sample quantize into a pattern at 15 Hz
  // (the search finds humps there, ThePatternIsReadFromTheCounts); a rate sinusoid of 0.005 pulse
  // a sample at 2 Hz is a line of the rate and lies in no harmonic's band (15, 30, 45, 40 Hz ...).
  // It modulates the pattern's frequency by +-0.5 Hz (index 0.25): its sidebands at 15 +- 2 and
  // 15 +- 4 Hz are marked too; the third ones are 3000 times weaker than the line (Bessel J3).
  const double tau0 = 0.01;
  std::mt19937_64 rng(5);
  std::normal_distribution<double> g(0.0, 0.005);  // lines of half width pi 0.005^2 / tau0 = 0.008 Hz
  RateRecord r(false, true, tau0);
  double angle = 0.37, last = std::floor(angle);
  for (std::size_t k = 0; k < (1u << 20); ++k) {
    angle += 0.15 + g(rng) + 0.005 * std::sin(2 * std::numbers::pi * 2.0 * tau0 * static_cast<double>(k));
    const double now = std::floor(angle), count = now - last;
    last = now;
    r.add(std::span(&count, 1));
  }
  const Spectrum sp = spectrum_of(r.rate(), true, tau0, 0, 0.683, true);
  ASSERT_TRUE(sp.pattern.has_value());
  std::size_t lines = 0;
  bool rate_line_found = false;
  for (const SpectralPeak& q : sp.search.peaks) {
    if (std::fabs(q.frequency_hz - 2.0) < 0.01) {
      rate_line_found = true;
      EXPECT_EQ(q.pulse_harmonic, 0);
    } else {
      EXPECT_GT(q.pulse_harmonic, 0) << "a peak at " << q.frequency_hz << " Hz on no harmonic";
      lines += q.pulse_harmonic > 0;
    }
  }
  EXPECT_TRUE(rate_line_found);
  EXPECT_GT(lines, 0u);  // the pattern's hump was found, and marked
  const auto hz = sp.fit_hz();
  EXPECT_NEAR(hz[0], 2.0, 0.01);
  for (std::size_t j = 1; j < hz.size(); ++j) EXPECT_EQ(hz[j], 0.0);
}

TEST(RateRecord, CountsHeldAtFourBytesGiveTheRatesOfTheCountsAsRead) {
  // Oracle: the definition, rate = count / tau0 with the count as read (a double). The counts are
  // held as int32 until one is not an int32; from there the record holds rates, the same doubles.
  const double tau0 = 0.003;
  const std::vector<double> counts = {3602, -7, 0, 2147483647, -2147483648.0, 12, 2147483648.0, 5, 0.5, 9};
  // The first six fit; the seventh (2^31) does not: held as counts, switched within one add() and
  // between two.
  for (const auto& [size, first] : {std::pair<std::size_t, std::size_t>{6, 6}, {10, 10}, {10, 3}, {10, 6}}) {
    RateRecord r(false, true, tau0);
    r.add(std::span(counts.data(), first));
    r.add(std::span(counts.data() + first, size - first));
    const RateView v = r.rate();
    ASSERT_EQ(v.size(), size) << first;
    for (std::size_t i = 0; i < size; ++i) EXPECT_EQ(v[i], counts[i] / tau0) << size << " " << first << " " << i;
  }
  // The PSD of counts held at 4 bytes is the same bits as that of the rates in doubles.
  std::mt19937_64 rng(11);
  std::poisson_distribution<int> pulses(40);
  RateRecord r(false, true, tau0);
  std::vector<double> rates;
  for (int k = 0; k < 4096; ++k) {
    const double c = pulses(rng);
    r.add(std::span(&c, 1));
    rates.push_back(c / tau0);
  }
  const Psd held = welch_psd(r.rate(), tau0, 256, 0.683), doubles = welch_psd(rates, tau0, 256, 0.683);
  ASSERT_EQ(held.psd.size(), doubles.psd.size());
  for (std::size_t k = 0; k < held.psd.size(); ++k) EXPECT_EQ(held.psd[k], doubles.psd[k]) << k;
}

TEST(RateView, TheAnalyzersHeldCountsGiveTheRatesOfTheCountsAsRead) {
  // Oracle: the definition, rate = count / tau0 with the count as read. The analyzer that holds
  // counts (hold_counts) keeps them as residuals from the line of the first count, int32 while
  // they fit: the PSD reads them there instead of a copy of its own.
  const double tau0 = 0.004;
  AnalysisOptions o;
  o.type = DataType::counts;
  o.stats = {DevStat::oadev};
  o.m_list = {1};
  o.hold_counts = true;
  // Residuals within int32 throughout; then leaving it at the fourth count (held in int64 from
  // there, modulo 2^64, the counts still exact): switched within one add() and between two.
  const std::vector<double> narrow = {3602, -7, 0, 2147483647, -2147483647, 12, 3601, 3603};
  const std::vector<double> wide = {5, 2147483647, 2147483647, 2147483647, -2147483647, -2147483647, 0, 9};
  for (const std::vector<double>* counts : {&narrow, &wide})
    for (const std::size_t first : {std::size_t{1}, std::size_t{3}, counts->size()}) {
      Analyzer a(o);
      ASSERT_TRUE(a.held_counts().held) << "known before the first count";
      a.add(std::span(counts->data(), first));
      a.add(std::span(counts->data() + first, counts->size() - first));
      const HeldCounts held = a.held_counts();
      EXPECT_EQ(held.wide.empty(), counts == &narrow) << first;
      const RateView v(held, tau0);
      ASSERT_EQ(v.size(), counts->size()) << first;
      for (std::size_t i = 0; i < v.size(); ++i) EXPECT_EQ(v[i], (*counts)[i] / tau0) << first << " " << i;
    }
  o.hold_counts = false;  // the characterizer's engine holds no counts: the PSD keeps a record
  EXPECT_FALSE(Analyzer(o).held_counts().held);
}
