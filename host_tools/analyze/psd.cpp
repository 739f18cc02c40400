#include "psd.hpp"

#include <fftw3.h>
#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <boost/math/distributions/chi_squared.hpp>
#include <cmath>
#include <iterator>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <utility>
#include <vector>

#include "confidence.hpp"
#include "held_memory.hpp"

namespace gyrochar {

std::size_t default_psd_segment(std::size_t n) {
  if (n < 16 * 16) return n < 64 ? 0 : 16;
  return std::bit_floor(n / 16);
}

Psd welch_psd(RateView rate, double tau0_s, std::size_t segment, double confidence) {
  const std::size_t L = segment;
  if (L < 8 || L % 2 != 0 || L > rate.size())
    throw std::invalid_argument("the segment must be an even number of values from 8 to the record's length");
  Psd out;
  out.segment = L;
  out.tau0_s = tau0_s;
  out.confidence = confidence;
  // The periodograms' sum, and the transform's one buffer (in place: L + 2 doubles) while they are
  // summed. The Hann window is not an array of L values: sin(pi n / L) by angle addition from two
  // tables of about sqrt(L) angles (within a few units of rounding of std::sin).
  std::vector<double> sum(L / 2 + 1, 0.0);
  std::size_t k_segments = 0;
  const std::size_t fine = std::max<std::size_t>(std::bit_floor(static_cast<std::size_t>(std::sqrt(static_cast<double>(L)))),
                                                 1);
  std::vector<double> sin_fine(fine), cos_fine(fine), sin_coarse(L / fine + 1), cos_coarse(L / fine + 1);
  for (std::size_t j = 0; j < fine; ++j) {
    sin_fine[j] = std::sin(std::numbers::pi * static_cast<double>(j) / static_cast<double>(L));
    cos_fine[j] = std::cos(std::numbers::pi * static_cast<double>(j) / static_cast<double>(L));
  }
  for (std::size_t j = 0; j < sin_coarse.size(); ++j) {
    sin_coarse[j] = std::sin(std::numbers::pi * static_cast<double>(j * fine) / static_cast<double>(L));
    cos_coarse[j] = std::cos(std::numbers::pi * static_cast<double>(j * fine) / static_cast<double>(L));
  }
  const int fine_bits = std::countr_zero(fine);  // fine is a power of two: n / fine by a shift
  const auto window = [&](std::size_t n) {
    const std::size_t c = n >> fine_bits, f = n & (fine - 1);
    const double s = sin_coarse[c] * cos_fine[f] + cos_coarse[c] * sin_fine[f];
    return s * s;
  };
  double window_power = 0;
  for (std::size_t n = 0; n < L; ++n) window_power += window(n) * window(n);
  {
    const UninitializedDoubles buffer = uninitialized_doubles(L + 2);  // huge pages: fewer faults, fewer TLB misses
    double* in = buffer.get();
    auto* spectrum = reinterpret_cast<fftw_complex*>(in);  // FFTW's in-place layout: L / 2 + 1 complex values
    const fftw_plan plan = fftw_plan_dft_r2c_1d(static_cast<int>(L), in, spectrum, FFTW_ESTIMATE);
    for (std::size_t start = 0; start + L <= rate.size(); start += L / 2, ++k_segments) {
      double mean = 0;
      for (std::size_t n = 0; n < L; ++n) mean += rate[start + n];
      mean /= static_cast<double>(L);
      for (std::size_t n = 0; n < L; ++n) in[n] = (rate[start + n] - mean) * window(n);
      fftw_execute(plan);
      for (std::size_t k = 0; k <= L / 2; ++k) sum[k] += spectrum[k][0] * spectrum[k][0] + spectrum[k][1] * spectrum[k][1];
    }
    fftw_destroy_plan(plan);
  }
  out.segments = k_segments;
  const double K = static_cast<double>(k_segments);
  out.edf = 36 * K * K / (19 * K - 1);
  const Interval unit = confidence_interval(1.0, out.edf, confidence);  // of a deviation: square it
  const double scale = 2 * tau0_s / (window_power * K);
  if (unit.valid) out.low = unit.low, out.high = unit.high;
  // The bins k = 1 .. L / 2 - 1, in the sum's own storage.
  for (std::size_t k = 1; k < L / 2; ++k) sum[k - 1] = sum[k] * scale;
  sum.resize(L / 2 - 1);
  out.psd = std::move(sum);
  return out;
}

namespace {

constexpr std::size_t lobe = 2;       // a Hann main lobe: within 2 bins of the sinusoid's frequency
constexpr std::size_t span_half = 3;  // the bins summed for a peak: its highest +- 3
constexpr std::size_t max_neighbours = 64;
static_assert(2 * max_neighbours < 256);
constexpr std::size_t first_bin = 7;  // index 7: the 8th bin, k = 8

}  // namespace

PeakSearch find_sinusoids(const Psd& psd, double false_alarm) {
  PeakSearch out;
  out.false_alarm = false_alarm;
  const std::size_t bins = psd.psd.size();
  out.background.assign(bins, std::numeric_limits<double>::quiet_NaN());
  if (bins <= first_bin + span_half || !(psd.edf > 0)) return out;
  const double nu = psd.edf;
  const boost::math::chi_squared chi2(nu);
  const double median_factor = boost::math::quantile(chi2, 0.5) / nu;
  // The neighbours' count: at most 64 each side, no further than the first bin below, and the same
  // count above (the last bins test with fewer). Their median: the element of rank n / 2.
  std::vector<double> near;
  std::vector<std::uint8_t> neighbours(bins, 0);  // at most 2 (max_neighbours - lobe): a byte a bin
  // Where every bin has all 2 (max_neighbours - lobe) neighbours, they are kept sorted from one bin
  // to the next (two leave, two come: O(128) a bin where nth_element took a few thousand
  // comparisons), the same element of rank n / 2. Values that do not order (NaN) take nth_element.
  const bool ordered = std::all_of(psd.psd.begin(), psd.psd.end(), [](double v) { return !std::isnan(v); });
  bool sorted = false;
  for (std::size_t i = first_bin; i < bins; ++i) {
    const std::size_t m = std::min({max_neighbours, i, bins - 1 - i});
    if (m < lobe + 1 + 3) continue;  // at least 4 neighbours each side
    if (sorted && m == max_neighbours) {
      // From bin i - 1's neighbours to bin i's: i - 1 - m and i + lobe leave, i - 1 - lobe and i + m come.
      const auto replace = [&](double gone, double come) {
        near.erase(std::lower_bound(near.begin(), near.end(), gone));
        near.insert(std::upper_bound(near.begin(), near.end(), come), come);
      };
      replace(psd.psd[i - 1 - m], psd.psd[i - 1 - lobe]);
      replace(psd.psd[i + lobe], psd.psd[i + m]);
      out.background[i] = near[near.size() / 2] / median_factor;
    } else {
      near.clear();
      for (std::size_t d = lobe + 1; d <= m; ++d) {
        near.push_back(psd.psd[i - d]);
        near.push_back(psd.psd[i + d]);
      }
      const auto mid = near.begin() + static_cast<std::ptrdiff_t>(near.size() / 2);
      sorted = ordered && m == max_neighbours;
      if (sorted) {
        std::sort(near.begin(), near.end());
      } else {
        std::nth_element(near.begin(), mid, near.end());
      }
      out.background[i] = *mid / median_factor;
    }
    neighbours[i] = static_cast<std::uint8_t>(near.size());
    ++out.bins_tested;
  }
  if (out.bins_tested == 0) return out;
  out.threshold = boost::math::quantile(boost::math::complement(chi2, false_alarm / static_cast<double>(out.bins_tested))) /
                  nu;
  const auto above = [&](std::size_t i) {
    return std::isfinite(out.background[i]) && psd.psd[i] > out.threshold * out.background[i];
  };
  const double df = psd.bin_hz();
  for (std::size_t i = 0; i < bins;) {
    if (!above(i)) {
      ++i;
      continue;
    }
    std::size_t top = i, end = i;
    for (; end < bins && above(end); ++end)
      if (psd.psd[end] / out.background[end] > psd.psd[top] / out.background[top]) top = end;
    i = end;
    // The main lobe's bins around the highest: excess power, its centroid, their variances.
    const std::size_t lo = top >= span_half ? top - span_half : 0, hi = std::min(bins - 1, top + span_half);
    const double b = out.background[top];
    double excess = 0, moment = 0, var_sum = 0;
    for (std::size_t j = lo; j <= hi; ++j) {
      const double s = psd.psd[j] - b;
      excess += s * df;
      moment += s * df * psd.freq_hz(j);
      var_sum += (2 * b * b + 4 * std::max(s, 0.0) * b) / nu * df * df;
    }
    if (!(excess > 0)) continue;
    // Neighbouring Hann bins are correlated (periodogram correlation 4/9 at one bin, 1/36 at two):
    // the variance of their sum is about twice the sum of their variances.
    var_sum *= 2;
    const double f = moment / excess;
    double var_moment = 0;
    for (std::size_t j = lo; j <= hi; ++j) {
      const double s = std::max(psd.psd[j] - b, 0.0);
      const double d = (psd.freq_hz(j) - f) * df / excess;
      var_moment += d * d * (2 * b * b + 4 * s * b) / nu;
    }
    var_moment *= 2;
    // The background: a median of n neighbours (about n / 2 independent: the bins' correlation)
    // has relative variance (pi / 2) (2 / nu) / (n / 2), and its error is common to every bin summed.
    const double rel_b = std::sqrt(std::numbers::pi / 2 * 2 / nu / (static_cast<double>(neighbours[top]) / 2));
    const double var_excess = var_sum + std::pow(static_cast<double>(hi - lo + 1) * b * rel_b * df, 2);
    SpectralPeak p;
    p.bin = top;
    p.frequency_hz = f;
    p.frequency_uncertainty_hz = std::sqrt(var_moment);
    p.power = excess;
    p.amplitude = std::sqrt(2 * excess);
    p.amplitude_uncertainty = std::sqrt(var_excess) / p.amplitude;  // dA = dE / A
    p.background = b;
    p.ratio = psd.psd[top] / b;
    p.threshold = out.threshold;
    out.peaks.push_back(p);
  }
  std::sort(out.peaks.begin(), out.peaks.end(),
            [](const SpectralPeak& a, const SpectralPeak& c) { return a.power > c.power; });
  return out;
}

void check_adev_nulls(PeakSearch& search, const std::vector<std::pair<double, double>>& oadev) {
  for (SpectralPeak& p : search.peaks) {
    const double null = 1 / p.frequency_hz;
    std::size_t count = 0;
    double low = INFINITY, low_tau = 0, high = 0;
    for (const auto& [tau, dev] : oadev) {
      if (tau < 0.7 * null || tau > 1.3 * null) continue;
      ++count;
      if (dev < low) low = dev, low_tau = tau;
      high = std::max(high, dev);
    }
    if (count < 7) continue;
    p.adev_null = std::fabs(low_tau / null - 1) <= 0.1 && low < 0.9 * high ? 1 : 0;
    p.adev_null_tau_s = low_tau;
  }
}

std::pair<double, double> PulsePattern::band(int k, double bin_hz, double offset_hz) const {
  const double nyquist = 1 / (2 * tau0_s);
  double f = std::fmod(k * rate_hz + offset_hz, 2 * nyquist);
  if (f < 0) f += 2 * nyquist;
  if (f > nyquist) f = 2 * nyquist - f;
  return {f, 3 * k * spread_hz + 5 * line_half_width(k) + 3 * bin_hz};
}

double PulsePattern::line_half_width(int k) const { return std::numbers::pi * k * k * diffusion / tau0_s; }

PulsePattern pulse_pattern(RateView pulses_per_s, double tau0_s, std::size_t block) {
  PulsePattern p;
  p.tau0_s = tau0_s;
  const std::size_t blocks = block ? pulses_per_s.size() / block : 0;
  double sum = 0, sum2 = 0;
  for (std::size_t b = 0; b < blocks; ++b) {
    double mean = 0;
    for (std::size_t n = 0; n < block; ++n) mean += pulses_per_s[b * block + n];
    mean /= static_cast<double>(block);
    sum += mean;
    sum2 += mean * mean;
  }
  if (blocks < 2) return p;
  const double nb = static_cast<double>(blocks);
  p.rate_hz = sum / nb;
  p.spread_hz = std::sqrt(std::max(0.0, (sum2 - sum * sum / nb) / (nb - 1)));
  const double per_sample = p.spread_hz * tau0_s;  // sd of a block's mean in pulses a sample
  p.diffusion = per_sample * per_sample * static_cast<double>(block);
  return p;
}

void mark_pulse_lines(PeakSearch& search, const PulsePattern& pattern, double bin_hz, int harmonics) {
  int last = 0;  // the highest harmonic whose line is narrow enough to be found
  while (last < harmonics && pattern.line_half_width(last + 1) <= static_cast<double>(max_neighbours) * bin_hz) ++last;
  auto mark = [&](int k, double offset_hz, const SpectralPeak* except) {
    const auto [centre, half_width] = pattern.band(k, bin_hz, offset_hz);
    for (SpectralPeak& p : search.peaks)
      if (&p != except && p.pulse_harmonic == 0 && std::fabs(p.frequency_hz - centre) <= half_width) p.pulse_harmonic = k;
  };
  for (int k = 1; k <= last; ++k) mark(k, 0, nullptr);
  std::vector<SpectralPeak*> lines;
  for (SpectralPeak& p : search.peaks) lines.push_back(&p);
  std::sort(lines.begin(), lines.end(),
            [](const SpectralPeak* a, const SpectralPeak* b) { return a->frequency_hz < b->frequency_hz; });
  for (const SpectralPeak* line : lines) {
    if (line->pulse_harmonic != 0) continue;
    for (int k = 1; k <= last; ++k)
      for (const double offset : {-2.0, -1.0, 1.0, 2.0}) mark(k, offset * line->frequency_hz, line);
  }
}

Spectrum spectrum_of(RateView rate, bool counts, double tau0_s, std::size_t segment, double confidence, bool search) {
  Spectrum sp;
  if (segment == 0) segment = default_psd_segment(rate.size());
  sp.psd = welch_psd(rate, tau0_s, segment, confidence);
  sp.searched = search;
  if (!search) return sp;
  sp.search = find_sinusoids(sp.psd);
  if (counts && rate.size() / segment >= 2) {  // the pattern needs two blocks' means
    sp.pattern = pulse_pattern(rate, tau0_s, segment);
    mark_pulse_lines(sp.search, *sp.pattern, sp.psd.bin_hz());
  }
  return sp;
}

void RateRecord::add(std::span<const double> values) {
  for (const double v : values) {
    if (counts_ && rate_.empty()) {
      const bool fits = v >= std::numeric_limits<std::int32_t>::min() && v <= std::numeric_limits<std::int32_t>::max();
      if (fits && static_cast<double>(static_cast<std::int32_t>(v)) == v) {
        narrow_.push_back(static_cast<std::int32_t>(v));
        continue;
      }
      rate_.reserve(narrow_.size() + values.size());  // the first count that does not fit: rates from here
      for (const std::int32_t c : narrow_) rate_.push_back(c / tau0_s_);
      narrow_ = {};
    }
    if (!phase_) {
      rate_.push_back(counts_ ? v / tau0_s_ : v);
      continue;
    }
    if (have_last_) rate_.push_back((v - last_) / tau0_s_);
    have_last_ = true;
    last_ = v;
  }
}

std::array<double, max_sinusoids> Spectrum::fit_hz() const {
  std::array<double, max_sinusoids> hz{};
  std::size_t n = 0;
  for (const double f : given_hz)
    if (n < hz.size()) hz[n++] = f;
  for (const SpectralPeak& p : search.peaks)
    if (n < hz.size() && p.pulse_harmonic == 0) hz[n++] = p.frequency_hz;
  return hz;
}

std::string Spectrum::psd_unit() const { return unit == "1" ? "1/Hz" : "(" + unit + ")^2/Hz"; }

std::string spectrum_csv(const Spectrum& s) {
  std::string out = "freq,psd,ci_low,ci_high\n";
  const double k = s.factor * s.factor;
  auto to = std::back_inserter(out);
  for (std::size_t i = 0; i < s.psd.psd.size(); ++i)
    fmt::format_to(to, "{},{},{},{}\n", s.psd.freq_hz(i), s.psd.psd[i] * k, s.psd.ci_low(i) * k, s.psd.ci_high(i) * k);
  return out;
}

std::string spectrum_table(const Spectrum& s) {
  std::string out;
  auto to = std::back_inserter(out);
  const Psd& p = s.psd;
  fmt::format_to(to,
                 "# PSD of the rate (Welch, Hann, 50 % overlap): {} segments of {} values, bins of {:.4g} Hz from "
                 "{:.4g} to {:.4g} Hz, EDF {:.4g} per bin, in {}\n",
                 p.segments, p.segment, p.bin_hz(), p.freq_hz(0), p.freq_hz(p.psd.size() - 1), p.edf, s.psd_unit());
  for (const double f : s.given_hz) fmt::format_to(to, "#   sinusoid offered to the fit at {:.6g} Hz (--sinusoid-hz)\n", f);
  if (!s.searched) return out;
  const PeakSearch& r = s.search;
  fmt::format_to(to,
                 "#   sinusoid search: {} bins tested, a peak above {:.3g} x the local background (false alarms in "
                 "{:.2g} % of records without a sinusoid): {}\n",
                 r.bins_tested, r.threshold, 100 * r.false_alarm,
                 r.peaks.empty() ? "none found" : fmt::format("{} found", r.peaks.size()));
  for (const SpectralPeak& q : r.peaks)
    fmt::format_to(to, "#   peak at {:.6g} +- {:.2g} Hz: amplitude {:.4g} +- {:.2g} {} (PSD {:.3g} x its background){}\n",
                   q.frequency_hz, q.frequency_uncertainty_hz, q.amplitude * s.factor, q.amplitude_uncertainty * s.factor,
                   s.unit, q.ratio,
                   q.pulse_harmonic > 0
                       ? fmt::format("; a line of the pulse pattern (harmonic {} of {:.6g} Hz), not offered to the fit",
                                     q.pulse_harmonic, s.pattern ? s.pattern->rate_hz : 0.0)
                   : q.adev_null < 0
                       ? ""
                       : fmt::format("; OADEV {} at tau = 1/f = {:.4g} s (smallest at {:.4g} s)",
                                     q.adev_null ? "dips" : "does not dip", 1 / q.frequency_hz, q.adev_null_tau_s));
  return out;
}

nlohmann::json spectrum_json(const Spectrum& s) {
  using nlohmann::json;
  const Psd& p = s.psd;
  const double k = s.factor * s.factor;
  json freq = json::array(), psd = json::array(), low = json::array(), high = json::array();
  double next = 0;  // the next frequency on a grid of 20 a decade
  for (std::size_t i = 0; i < p.psd.size(); ++i) {
    if (p.freq_hz(i) < next) continue;
    freq.push_back(p.freq_hz(i));
    psd.push_back(p.psd[i] * k);
    low.push_back(std::isfinite(p.ci_low(i)) ? json(p.ci_low(i) * k) : json(nullptr));
    high.push_back(std::isfinite(p.ci_high(i)) ? json(p.ci_high(i) * k) : json(nullptr));
    next = p.freq_hz(i) * std::pow(10.0, 0.05);
  }
  const auto measured = [](double value, double uncertainty, const std::string& unit) {
    return json{{"value", value}, {"uncertainty", uncertainty}, {"unit", unit}};
  };
  json peaks = json::array();
  for (const SpectralPeak& q : s.search.peaks)
    peaks.push_back(
        {{"frequency", measured(q.frequency_hz, q.frequency_uncertainty_hz, "Hz")},
         {"amplitude", measured(q.amplitude * s.factor, q.amplitude_uncertainty * s.factor, s.unit)},
         {"power", q.power * k},
         {"ratio", q.ratio},
         {"threshold", q.threshold},
         {"adev_null", q.adev_null < 0 ? json(nullptr) : json{{"found", q.adev_null == 1}, {"tau", q.adev_null_tau_s}}},
         {"pulse_harmonic", q.pulse_harmonic > 0 ? json(q.pulse_harmonic) : json(nullptr)}});
  return {{"unit", s.psd_unit()},
          {"segment", p.segment},
          {"segments", p.segments},
          {"bin_hz", p.bin_hz()},
          {"edf", p.edf},
          {"confidence", p.confidence},
          {"decimated", "about 20 bins a decade; every bin: --psd FILE"},
          {"freq", std::move(freq)},
          {"psd", std::move(psd)},
          {"ci_low", std::move(low)},
          {"ci_high", std::move(high)},
          {"given_hz", s.given_hz},
          {"search", s.searched ? json{{"false_alarm", s.search.false_alarm},
                                       {"bins_tested", s.search.bins_tested},
                                       {"threshold", s.search.threshold}}
                                : json(nullptr)},
          {"pulse_pattern", s.pattern ? json{{"rate_hz", s.pattern->rate_hz},
                                             {"spread_hz", s.pattern->spread_hz},
                                             {"line_half_width_hz", s.pattern->line_half_width(1)}}
                                      : json(nullptr)},
          {"peaks", std::move(peaks)}};
}

void add_frequency_uncertainties(nlohmann::json& fits, const Spectrum& s) {
  for (nlohmann::json& fit : fits) {
    if (!fit.contains("sinusoids")) continue;
    for (nlohmann::json& sn : fit["sinusoids"]) {
      const double f = sn["frequency"]["value"].get<double>();
      for (const SpectralPeak& q : s.search.peaks)
        if (q.frequency_hz == f) sn["frequency"]["uncertainty"] = q.frequency_uncertainty_hz;
    }
  }
}

}  // namespace gyrochar
