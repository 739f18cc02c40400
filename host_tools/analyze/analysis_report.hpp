#pragma once
// What gyrochar-analyze shows of an Analysis: units (gyro data in rate units, time data as
// fractional frequency), the IEEE-952 fits on the Allan and modified Allan curves, and the table,
// CSV and JSON formats.
//
// Units. The engine gives deviations in "phase unit per second" (see analysis.hpp). ReportUnits
// says what one phase unit is: an angle in rad for gyro data (counts times the pulse weight,
// angle samples, rate samples times 1 s) or a time in s for clock data (phase in s, fractional
// frequency times 1 s). Gyro deviations are shown in a rate unit (TDEV in the angle unit equal to
// that rate times 1 s: deg/h -> arcsec, deg/s -> deg, rad/s -> rad); clock deviations as
// fractional frequency (TDEV in s).
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "analysis.hpp"
#include "gyrochar/ieee952.hpp"
#include "gyrochar/readoff.hpp"
#include "sim_truth.hpp"
#include "kalibr.hpp"
#include "psd.hpp"
#include "units.hpp"

namespace gyrochar {

struct ReportUnits {
  bool gyro = false;           // angle/rate data (else clock data)
  double phase_unit_si = 1.0;  // one engine phase unit in rad (gyro) or s (clock)
  RateUnit rate;               // output unit of gyro deviations
  std::string input;           // what the values were, e.g. "counts of 1.5 arcsec", "phase in s"

  /// Factor from engine deviations (and TDEV) to the output units. O(1).
  double factor() const { return gyro ? phase_unit_si / rate.rad_per_s : phase_unit_si; }
  /// Unit of a row of statistic s in the output: e.g. "deg/h", "arcsec", "1" (fractional), "s".
  std::string unit(DevStat s) const;
};

/// The unit a report shows IEEE-952 term k (Q N B K R) in: the gyro units of units::ieee952, or
/// the s-based ones of clock data. O(1).
const units::Ieee952Unit& fit_unit(const ReportUnits& u, std::size_t k);

/// An IEEE-952 fit (ieee952.hpp) of the curves an analysis has: the recommended fit of both
/// curves at once, then the Allan and the modified Allan curve alone (for experts).
struct CurveFit {
  FitCurve curve = FitCurve::both;
  Ieee952Fit fit;    // parameters in SI: Q rad (s), N rad/s^0.5, B rad/s, K rad/s^1.5, R rad/s^2
  int long_tau = 0;  // the LongTau (below) its Allan curve was made of at long tau (0: OADEV alone)
};

/// What the Allan curve of a fit is made of at long tau (docs/metrology.md, "Long taus"): OADEV
/// alone; TOTDEV (bias-corrected) wherever SP 1065's EDF for it exceeds OADEV's; or TheoH: OADEV
/// below its switch point k, TheoBR points at tau = 1.5 k, 3 k, ... up to T/2.
/// A subset of the statistics (stat.hpp), named as they are; its values index the fits.
enum class LongTau : std::uint8_t { oadev, totdev, theoh };
/// "oadev", "totdev", "theoh": the statistic's name(), a static string.
const char* name(LongTau l);
/// "both curves (recommended)", "the Allan curve alone", "the modified Allan curve alone".
const char* curve_title(FitCurve c);

/// Fits the oadev and mdev rows of the analysis (one point per octave, m = 2^k), with the points
/// in SI units; with long_tau totdev or theoh, the record (Analyzer::record()) gives total-family
/// points in place of OADEV at long tau (an empty record: OADEV alone). white_quantization_si:
/// the white-quantization level Q_w = pulse weight / sqrt(12) in rad for counts, 0 otherwise.
/// O(points^2) covariance sums, on two threads (the same bits as each fit alone, in turn),
/// allocates the workspace; empty when the analysis has neither curve. A fit that fails says why
/// in its status.
/// sinusoid_hz: frequencies of sinusoids the model selection may add (Spectrum::fit_hz(); 0: none).
std::vector<CurveFit> fit_curves(const Analysis& a, const ReportUnits& units, double tau0_s, double white_quantization_si,
                                 LongTau long_tau = LongTau::oadev, const PhaseRecord& record = {},
                                 const std::array<double, max_sinusoids>& sinusoid_hz = {});
/// The points fit_curves() fits (SI units), for a single fit_ieee952() of one curve. Allocates.
std::vector<FitPoint> fit_points(const Analysis& a, const ReportUnits& units, double tau0_s,
                                 LongTau long_tau = LongTau::oadev, const PhaseRecord& record = {});

/// The IEEE-952 graphical read-off (readoff.hpp: N on the -1/2 line at 1 s, the ADEV floor and
/// B = floor / 0.664, K on the +1/2 line at 3 s) of every OADEV row of the analysis (not only the
/// octaves), in SI: N rad/s^0.5, floor and B rad/s, K rad/s^1.5; a row without an interval gives
/// NaN bounds. Empty for clock data or without OADEV rows. O(rows), allocates the points.
std::optional<Readoff> readoff_of(const Analysis& a, const ReportUnits& units);

/// The truth a simulated input carries (gyrochar-sim's header, sim_truth.hpp), shown beside the
/// fitted terms when the data are counts with the simulator's own tau0 and pulse weight, and the
/// simulated gyro did not change during the run (no segments). Nothing otherwise. O(header lines).
std::optional<Ieee952Truth> truth_of(const std::vector<std::string>& header, DataType type, double tau0_s,
                                     double pulse_weight_rad);

/// The smallest, largest and mean value read (Stable32's header). add() is O(1).
struct DataRange {
  double min = 0.0, max = 0.0, sum = 0.0;
  std::uint64_t count = 0;
  /// Adds finite values in order (the sum in their order). O(n).
  void add(std::span<const double> values);
  double mean() const { return count ? sum / static_cast<double>(count) : 0.0; }
};

/// Everything a report shows. Refers to (does not own) the analysis.
struct Report {
  const Analysis& analysis;
  DataType type = DataType::phase;
  double tau0_s = 1.0;
  double confidence = 0.683;
  ReportUnits units;
  std::vector<CurveFit> fits;
  std::optional<Ieee952Truth> truth;  // a simulation's truth, shown beside the fits
  std::string source;                 // the input's name, for Stable32's header
  DataRange range;                    // the values read (after --nominal-hz), for Stable32's header
  std::optional<Readoff> readoff;     // gyro data with OADEV rows: the read-off, beside the fits
  std::optional<Spectrum> spectrum;   // the rate's PSD and its sinusoids (psd.hpp), when computed
};

/// Aligned table for people: a header line (data, units, stride factor, confidence), one line per
/// row with its unit, then the fits (parameters in gyro units: Q arcsec, N deg/sqrt(h), B deg/h,
/// K deg/h/sqrt(h), R deg/h/h; clock data: s-based units), then the read-off in the same units (the
/// floor in the deviations' unit), with a line for each value that disagrees with the recommended
/// fit (readoff_agrees()). O(rows), allocates the text.
std::string format_table(const Report& r);
/// CSV: header csv_header, numbers shortest round-trip, empty fields where not available. Fits are
/// not in the CSV. O(rows).
std::string format_csv(const Report& r);
inline constexpr const char* csv_header = "stat,m,tau,n,dev,unit,alpha,edf,ci_low,ci_high,stride";
/// One row's CSV fields (csv_header's columns, no newline). O(1).
std::string csv_fields(const AnalysisRow& row, const ReportUnits& units);
/// JSON: {"tau0", "n_samples", "type", "results": [{"stat", "m", "tau", "n", "dev", "alpha", "edf",
/// "ci_low", "ci_high", "unit", "stride"}], "units", "stride_factor", "confidence", "fit" (only
/// with fits), "readoff" (only with one: "N", "B", "K" as {"value", "ci_low", "ci_high", "tau",
/// "unit", "agrees_with_fit"}, "floor" as {"value", "ci_low", "ci_high", "tau", "unit", "at_end"})};
/// null where not available. O(rows).
nlohmann::json to_json(const Report& r);
/// One element of "results", and the "units" object. O(1).
nlohmann::json row_json(const AnalysisRow& row, const ReportUnits& units);
nlohmann::json units_json(const ReportUnits& units);
/// Whether read-off value `v` (SI) agrees with term `p` of the recommended fit (SI): |v - p| within
/// sqrt(u^2 + h^2), u the fit's standard uncertainty, h the half-width of the read-off's interval.
/// Empty when there is nothing to compare: no read-off value, no interval, or the term not fitted
/// by an ok fit. O(1).
std::optional<bool> readoff_agrees(const ReadoffValue& v, const Ieee952Fit* fit, std::size_t term);
/// Where the record cannot choose between the fit's model and one with a Markov term in B's or K's
/// place (ieee952.hpp), the sentence that says the uncertainties include the difference: one per such
/// term, none otherwise. O(1).
std::vector<std::string> model_difference_notes(const Ieee952Fit& fit, const ReportUnits& u);

/// Stable32's result table, one block per statistic (in the order asked), each as Stable32 writes
/// it: the header ("# STATISTICS FOR FILE:", data points, maximum, minimum, average of the values,
/// "# Sigma Type: Overlapping Allan", confidence factor, dead time, the column line) and rows
/// "AF Tau # Alpha MinSigma Sigma MaxSigma" in its column widths (5, 13, 9, 6, 13, 14, 15;
/// %.4e). Gyro data add one "# Units:" line (Stable32 files are fractional frequency); a row
/// without an interval has 0 bounds and one without identified noise alpha 0, as in Stable32.
/// Blocks are separated by a blank line. O(rows).
std::string format_stable32(const Report& r);
/// The Kalibr imu.yaml (kalibr.hpp) of the fit of both curves; nothing, and why, when the data
/// are not gyro data, the fit was not made or was rejected, or neither N nor K is in its model.
/// With one of them not in the model the file has its key commented out with '?' and `why`
/// says so (a note: the text is returned). O(1).
std::optional<std::string> kalibr_yaml(const Report& r, std::string& why);
/// What of a fitted model a Kalibr file leaves out (Kalibr has white rate noise and rate random
/// walk only: gyroscope_noise_density is the fitted white-rate N, gyroscope_random_walk the fitted
/// K, whatever else the model holds): "sensor filter, 1 Markov term, 1 sinusoid, B"; empty when
/// nothing. O(1).
std::string kalibr_left_out(const Ieee952Fit& fit);

}  // namespace gyrochar
