#pragma once
// The power spectral density of the rate (Welch) and the sinusoids found in it, for
// gyrochar-analyze: --psd FILE, the "psd" block of the JSON, the PSD panel of --plot and the
// frequencies handed to the IEEE-952 fit (FitSetup::sinusoid_hz).
//
// Welch's estimate. The rate is cut into segments of L values that overlap by L/2; each segment
// loses its mean, is weighted by the Hann window w_n = sin^2(pi n / L) and transformed (FFTW);
// the one-sided PSD at f_k = k / (L tau0), k = 1 .. L/2 - 1, is the average over the K segments of
// 2 tau0 |X_k|^2 / sum w_n^2 (rate unit^2/Hz): white rate noise of variance s^2 per sample gives
// 2 s^2 tau0 at every k, and a sinusoid of amplitude A puts A^2/2 into the bins of its main lobe.
// Each bin's estimate is distributed as PSD chi2_nu / nu with Welch's equivalent degrees of freedom
// for 50 % overlapping Hann segments (Percival and Walden 1993, eq. 292b):
//     nu = 36 K^2 / (19 K - 1)   (about 1.9 K: the overlap is worth 0.9 of a segment each)
// from which the confidence band PSD nu / chi2_nu(1 - p) .. PSD nu / chi2_nu(p), p = (1 - c) / 2.
//
// Sinusoid detection. A bin's background is the median of its neighbours at 3 to M bins on either
// side (M = min(64, k - 1, ...), the same count on both sides, so that a sloping background is not
// underestimated), divided by the median of chi2_nu / nu; the bins of a sinusoid's Hann main lobe
// (within 2 bins) are never their own background. A bin is a peak when nu PSD / background exceeds
// the chi2_nu quantile 1 - alpha / bins (Bonferroni over every bin tested): under a background of
// Gaussian noise the chance that a record shows any peak is at most alpha (0.01 by default).
// Contiguous bins above the threshold are one peak; its frequency is the centroid of the excess
// power over the main lobe (the highest bin +- 3), its amplitude A = sqrt(2 E) from the excess
// power E over those bins, each with an uncertainty propagated from the bins' chi-squared variance
// (a sinusoid's own power adds to it: Var P = (2 B^2 + 4 S B) / nu per bin, S = P - B) and from the
// background's (the median's sampling error, the same for every bin of the peak).
#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>
#include <utility>
#include <span>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "analysis.hpp"
#include "gyrochar/ieee952.hpp"

namespace gyrochar {

/// The Welch PSD of a rate record: bins k = 1 .. L/2 - 1 (no DC, no Nyquist).
struct Psd {
  std::size_t segment = 0;   // L, values per segment
  std::size_t segments = 0;  // K
  double tau0_s = 0;
  double edf = 0;           // nu of every bin
  double confidence = 0;    // of the band
  std::vector<double> psd;  // rate unit^2 / Hz, bin k = i + 1
  // A deviation's interval at `edf` over its value (NaN: none): a bin's band is psd times their squares.
  double low = std::numeric_limits<double>::quiet_NaN(), high = std::numeric_limits<double>::quiet_NaN();
  double bin_hz() const { return segment ? 1.0 / (static_cast<double>(segment) * tau0_s) : 0.0; }
  // Bin i's frequency and band, computed as read (the record may have 2^23 bins: no more arrays of them).
  double freq_hz(std::size_t i) const { return static_cast<double>(i + 1) / (static_cast<double>(segment) * tau0_s); }
  double ci_low(std::size_t i) const { return psd[i] * low * low; }
  double ci_high(std::size_t i) const { return psd[i] * high * high; }
};

/// The default segment length for n values: the largest power of two <= n / 16 (so 31 to 63
/// segments, an EDF of 60 to 120 a bin: the bins reach down to 1/16 of the record, where the
/// Allan curve's longer taus see a sinusoid), at least 16; 0 when n < 64 (too short). O(1).
std::size_t default_psd_segment(std::size_t n);

/// Rate values as an analysis holds them: doubles, counts at 4 bytes a value, or the analyzer's
/// own held counts (HeldCounts: no copy), each rate count / tau0_s (the same double as dividing
/// the count read from the file). Views, O(1).
class RateView {
 public:
  RateView(std::span<const double> rate) : rate_(rate) {}
  RateView(const std::vector<double>& rate) : rate_(rate) {}
  RateView(std::span<const std::int32_t> counts, double tau0_s) : counts_(counts), tau0_s_(tau0_s) {}
  RateView(const HeldCounts& held, double tau0_s)
      : narrow_(held.narrow), wide_(held.wide), slope_(held.slope), tau0_s_(tau0_s) {}
  std::size_t size() const {
    if (!counts_.empty()) return counts_.size();
    if (!narrow_.empty() || !wide_.empty()) return narrow_.size() + wide_.size() - 1;
    return rate_.size();
  }
  double operator[](std::size_t i) const {
    if (!counts_.empty()) return counts_[i] / tau0_s_;
    if (!narrow_.empty()) return count(narrow_[i], narrow_[i + 1]) / tau0_s_;
    if (!wide_.empty()) return count(wide_[i], wide_[i + 1]) / tau0_s_;
    return rate_[i];
  }

 private:
  // The count between two residuals, modulo 2^64 as they are held: an int32, exact in a double.
  double count(std::int64_t from, std::int64_t to) const {
    return static_cast<double>(static_cast<std::int64_t>(static_cast<std::uint64_t>(to) - static_cast<std::uint64_t>(from) +
                                                         static_cast<std::uint64_t>(slope_)));
  }
  std::span<const double> rate_;
  std::span<const std::int32_t> counts_, narrow_;
  std::span<const std::int64_t> wide_;
  std::int64_t slope_ = 0;
  double tau0_s_ = 1;
};

/// Welch's PSD of `rate` (any unit u; the result in u^2/Hz) sampled every tau0_s, in segments of
/// `segment` values (even, >= 8, <= rate.size()), with its band at `confidence`. O(n log L),
/// allocates O(L). Throws std::invalid_argument for a segment that does not fit.
Psd welch_psd(RateView rate, double tau0_s, std::size_t segment, double confidence);

/// A sinusoid found in a PSD (units: the PSD's rate unit, Hz).
struct SpectralPeak {
  double frequency_hz = 0, frequency_uncertainty_hz = 0;
  double amplitude = 0, amplitude_uncertainty = 0;
  double power = 0;       // excess power over the main lobe, u^2 (A^2/2)
  double background = 0;  // the background PSD at the highest bin, u^2/Hz
  double ratio = 0;       // highest bin's PSD over its background
  double threshold = 0;   // the ratio a bin must exceed (Bonferroni)
  std::size_t bin = 0;    // index of the highest bin in Psd::freq_hz
  // The Allan curve's cross-check (check_adev_nulls()): -1 not made (taus not dense near 1/f),
  // 0 no dip near tau = 1/f, 1 the smallest OADEV near 1/f lies within 10 % of it; its tau.
  int adev_null = -1;
  double adev_null_tau_s = 0;
  // Counted pulses only (mark_pulse_lines()): k > 0 when the peak lies on the k-th harmonic of
  // the pulse pattern, a line of the quantization, not of the rate (never offered to the fit).
  int pulse_harmonic = 0;
};

struct PeakSearch {
  std::vector<SpectralPeak> peaks;  // by decreasing power
  std::vector<double> background;   // per bin (NaN where not estimated)
  double threshold = 0;             // ratio PSD / background a bin must exceed
  std::size_t bins_tested = 0;
  double false_alarm = 0;  // alpha: chance of any peak in a record without a sinusoid
};

/// Sinusoids in `psd` (header), at a chance `false_alarm` of finding one where there is none.
/// Bins below the 8th are not tested (too few neighbours below them). O(bins x 128): each bin's
/// neighbours kept sorted from the one before; allocates.
PeakSearch find_sinusoids(const Psd& psd, double false_alarm = 0.01);

/// Cross-checks each peak with the nulls of the Allan deviation of a sinusoid (AVAR A^2 (sin^2 x /
/// x)^2, x = pi f tau: zero at tau = k/f) on dense taus: among the OADEV points (tau, dev) within
/// 30 % of tau = 1/f, at least 7 of them, the smallest must lie within 10 % of 1/f and below
/// 0.9 x the largest. O(peaks x points).
void check_adev_nulls(PeakSearch& search, const std::vector<std::pair<double, double>>& oadev);

/// Counted pulses quantize into a pattern: with the angle moving at rho pulses a second, the
/// quantization error is a sawtooth of fundamental rho Hz, and its harmonics k rho fold into the
/// band below 1/(2 tau0). Over a record rho wanders (the rate's own noise) and the pattern's phase
/// diffuses (white rate noise of s pulses a sample spreads harmonic k into a Lorentzian of half
/// width pi k^2 s^2 / tau0 Hz): each line is a hump, which the search finds where no rate
/// sinusoid is (a gyro at 0.15 pulse a sample of earth rate showed 3 to 8 peaks near 15 Hz in
/// every record). The pattern is read from the counts themselves: rho and its spread from the
/// means of non-overlapping blocks of `block` values (sd(block mean) = s / sqrt(block) under
/// white rate noise, which gives s).
struct PulsePattern {
  double rate_hz = 0;    // rho: mean pulses a second
  double spread_hz = 0;  // sd of rho between blocks
  double diffusion = 0;  // s^2: white rate noise, pulses^2 a sample
  double tau0_s = 0;
  /// The Lorentzian half width of harmonic k, Hz.
  double line_half_width(int k) const;
  /// The band of harmonic k moved by offset_hz (folded): centre and half width (3 spreads, 5 line
  /// half widths, 3 bins).
  std::pair<double, double> band(int k, double bin_hz, double offset_hz = 0) const;
};
PulsePattern pulse_pattern(RateView pulses_per_s, double tau0_s, std::size_t block);
/// Marks the peaks of `search` that lie in the band of one of the first `harmonics` harmonics of
/// the pattern whose line half width stays under 64 bins (wider, the search's neighbourhood
/// follows the line and finds no peak on it), and then their sidebands: a rate line at f
/// modulates the pattern's frequency, which puts lines at k rho +- f and k rho +- 2 f (taken from
/// the lowest rate line up; a rate line that is itself such a sideband of a lower one is marked
/// too: a limit). O(peaks^2 x k).
void mark_pulse_lines(PeakSearch& search, const PulsePattern& pattern, double bin_hz, int harmonics = 8);

/// Rate values from the analyzer's input: freq values as they are, counts divided by tau0 (pulses
/// per second), phase points differenced over tau0. The result is in the engine's rate unit
/// (analysis.hpp: phase unit per second). Counts are held as they are, 4 bytes a value, while
/// every one is an int32 (a 120-hour record at 1 kHz: 1.7 GB instead of 3.5), else as rates from
/// the first one that is not. add() is O(n), allocates. The analyzer keeps one only where it does
/// not hold the counts itself (Analyzer::held_counts(): a RateView reads those, no copy).
class RateRecord {
 public:
  RateRecord(bool phase, bool counts, double tau0_s) : phase_(phase), counts_(counts), tau0_s_(tau0_s) {}
  void add(std::span<const double> values);
  RateView rate() const { return narrow_.empty() ? RateView(rate_) : RateView(narrow_, tau0_s_); }

 private:
  bool phase_, counts_;
  double tau0_s_;
  bool have_last_ = false;
  double last_ = 0;
  std::vector<std::int32_t> narrow_;  // counts while every one fits
  std::vector<double> rate_;
};

/// What the analyzer reports of the rate's spectrum: the PSD (engine rate unit^2/Hz), the search
/// and the frequencies given by hand, and how to show them (factor: engine rate -> output rate).
struct Spectrum {
  Psd psd;
  std::optional<PulsePattern> pattern;  // counted pulses
  bool searched = false;                // false: --no-sinusoid-search
  PeakSearch search;
  std::vector<double> given_hz;  // --sinusoid-hz
  double factor = 1;             // engine rate unit -> `unit`
  std::string unit;              // the output rate unit, e.g. "deg/h"; "1" for fractional frequency

  /// The frequencies offered to the IEEE-952 fit: the given ones, then the strongest peaks found
  /// that are not pulse lines, at most max_sinusoids (0: none). O(peaks).
  std::array<double, max_sinusoids> fit_hz() const;
  /// "(deg/h)^2/Hz"
  std::string psd_unit() const;
};

/// CSV of every bin: freq,psd,ci_low,ci_high (Hz, the output unit^2/Hz). O(bins).
std::string spectrum_csv(const Spectrum& s);
/// Welch's PSD and the search with the analyzer's defaults (`segment` 0: default_psd_segment()),
/// pulse lines marked when the rates are of `counts`. Throws std::invalid_argument as welch_psd().
Spectrum spectrum_of(RateView rate, bool counts, double tau0_s, std::size_t segment, double confidence, bool search);

/// The table's lines ("# PSD ..." and one per peak). O(peaks).
std::string spectrum_table(const Spectrum& s);
/// The JSON "psd" block: the Welch parameters, the PSD decimated to about 20 bins a decade
/// ("freq", "psd", "ci_low", "ci_high" as arrays; every bin is in --psd's CSV), the search
/// ("search": false_alarm, bins_tested, threshold) and "peaks" [{frequency, amplitude,
/// power, ratio, threshold}] with {value, uncertainty, unit} members. O(bins).
nlohmann::json spectrum_json(const Spectrum& s);
/// Gives the fits' sinusoids in `fits` (to_json()'s "fit" array) the frequency uncertainty of the
/// peak they came from. O(fits x peaks).
void add_frequency_uncertainties(nlohmann::json& fits, const Spectrum& s);

}  // namespace gyrochar
