// gyrochar-analyze: Allan-family deviations of a recorded file, with EDF, confidence intervals,
// noise identification and the IEEE-952 fit, computed by the same streaming core as the board.
// This file is the command line: options, the read passes, progress and exit codes. The engine is
// host_tools/analyze/analysis.*, the output formats host_tools/analyze/analysis_report.*.
#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cfloat>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <iterator>
#include <memory>
#include <new>
#include <span>
#include <sstream>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include "acceptance.hpp"
#include "analysis.hpp"
#include "analysis_html.hpp"
#include "analysis_report.hpp"
#include "datafile.hpp"
#include "dynamic.hpp"
#include "heat_map.hpp"
#include "html_report.hpp"
#include "limits.hpp"
#include "verdict_output.hpp"
#include "input_units.hpp"
#include "output_paths.hpp"
#include "plan.hpp"
#include "psd.hpp"
#include "static_plot.hpp"
#include "hal/program/command_line.hpp"
#include "hal/program/exit_codes.hpp"

namespace {

using namespace gyrochar;

constexpr const char* program = "gyrochar-analyze";

bool progress_line_open = false;  // a progress line without its newline is on stderr

[[noreturn]] void fail(int code, const std::string& what, const std::string& why) {
  if (progress_line_open) std::fputc('\n', stderr);
  exit_with(code, program, what, why);
}
[[noreturn]] void bad(const std::string& what, const std::string& why) { fail(exit_code::bad_input, what, why); }

constexpr const char* footer = R"(Data type and units (the type is required: for a gyro "frequency" is rate and "phase" is angle):
  --type phase   phase samples: --unit s (clock phase, the default; deviations as fractional
                 frequency, TDEV in s) or an angle unit rad, mrad, urad, deg, arcsec (gyro angle)
  --type freq    frequency samples, each the average over tau0: --unit 1 (fractional, the default),
                 Hz with --nominal-hz F0 (y = (f - F0)/F0), or a rate unit deg/h, deg/s, rad/s
  --type counts  integer pulses per tau0 (exact arithmetic); --pulse-weight gives the angle of one
                 pulse with its unit: 1.5arcsec, "0.5 urad", or 1.5 with --pulse-unit arcsec
  Gyro data (angle, rate, counts) come out in --rate-unit (TDEV in deg/h -> arcsec, deg/s -> deg,
  rad/s -> rad); IEEE-952 parameters in Q arcsec, N deg/sqrt(h), B deg/h, K deg/h/sqrt(h), R deg/h/h.

Formats: table (people), csv, json, stable32 (Stable32's result table: AF Tau # Alpha MinSigma
Sigma MaxSigma, one block per statistic; values in the output unit). --kalibr FILE also writes the
IEEE-952 fit's N and K as the gyroscope part of a Kalibr imu.yaml (N in rad/s/sqrt(Hz) = rad/s^0.5,
K in rad/s^2/sqrt(Hz) = rad/s^1.5, update_rate 1/tau0; the accelerometer keys are left to fill, and
so is N or K when the fit left it out of its model, said on stderr): the fitted white-rate N and
rate random walk K alone; a filter, Markov terms, sinusoids, B or R of the model have no place in
Kalibr's model, and the file and stderr say which were left out.
Gyro data with OADEV rows also get the IEEE-952 graphical read-off that data sheets print (table
and json): N on the -1/2 line at tau = 1 s, the ADEV floor and B = floor/0.664, K on the +1/2 line
at 3 s, each with the interval of the point it was read at and, beside --fit, whether they agree.

The rate's PSD (--psd FILE: freq,psd,ci_low,ci_high; JSON "psd", decimated): Welch, Hann window,
segments of --psd-segment values overlapping by half (default: the largest power of two <= N/16),
one-sided, in the output rate unit^2/Hz (white rate noise: 2 N^2), with its chi-squared band (EDF
36 K^2/(19 K - 1) for K segments). With --fit ieee952 it is searched for sinusoids: peaks above
their local background (running median) beyond the Bonferroni threshold of a 1 % false-alarm
chance per record, frequency and amplitude with uncertainties (table; JSON psd.peaks), offered to
the fit's model selection with any --sinusoid-hz F (at most 2 in all; --no-sinusoid-search: only
those given); with dense taus near 1/f (--taus all or a list) each peak is checked against the
OADEV's null at tau = 1/f. The PSD holds the rate in memory (8 bytes a value).
--plot PREFIX (without --dynamic): PREFIX.svg and .png with ADEV and MDEV and their intervals, each
term of the fitted model and its total, the read-off, the PSD with its band, background and peaks,
and the fit's residuals in sigma.

Input: numbers, one per line or in columns separated by blanks, ',' or ';' ('#' or '%' starts a comment),
plain or gzip (recognized by content), '-' for standard input; read once. Every data line has as
many fields as the first. Without --column a table of two columns whose first one increases
(time, value) is read from column 2, and stderr says so; other tables need --column. A comma
between two digits beside another separator is a decimal comma, refused; with no other separator
it is ambiguous and needs --column. A number is never half read.

Range: values whose squared differences overflow or underflow a double, a tau0 whose square leaves
its range, an output unit that takes a deviation out of it, or --nominal-hz rounding the values
away (fractional frequency given as Hz) are errors naming the cause (exit 2), never infinities or
silent zeros; a constant input (phase: a straight line) gives deviations of 0, with a note.

Taus (averaging factors m, tau = m tau0) and memory:
  octave        1, 2, 4, ... while a term fits
  decade        1, 2, 4, 10, 20, 40, ... (Stable32's decade)
  all           every m up to N/2 that the stride factor can form (keeps the values in memory;
                the sums of every tau make it O(N^2), on every core, --progress counting them:
                10^5 values take seconds, 10^6 many minutes; from m = 64 the EDF is
                interpolated between exact anchors, within 2e-3 of the exact one)
  1,10,100      a list of m (strictly increasing)
  The taus are sized from the file's length (an upper bound: rows the data does not reach are
  left out) and cover any length on standard input. --stride-factor full (the default) makes
  every tau up to N/4 fully overlapped (Stable32's estimators, same number of terms): the history
  then grows with N, up to S = 2^24 (3S points of 24 bytes); on standard input, whose length is
  unknown, every tau up to 2^16 is fully overlapped and taus above it are strided, their terms
  m/2^16 points apart, with the EDF of the strided estimator. A stride factor S keeps the history
  at about 3S (1 + levels/2) points whatever the length. adev and hdev are Stable32's
  non-overlapped estimators at any tau.

The total and Theo family (docs/total.md): totdev, mtotdev, ttotdev, htotdev, theo1, theoh need the
whole record, which the analyzer then holds (8 bytes a value, plus 4 for mtotdev). Theo1 and
TheoBR rows carry m as their averaging factor at tau = 0.75 m tau0 (m even, from 10 up to N - 1:
octave 16, 32, ...; decade 10, 20, 40, ...); theoh is overlapping ADEV below its switch point (the
largest octave at or below 10 % of the record) and TheoBR from there on. Theo1 and TheoBR rows
are exact at every tau (lag sums, O(N log N) once and about O(m log^2 m) per tau; it holds about
6 N + 4 fft_length(2 N) doubles, 1.6 GB at 10^7 points, or the decimated estimator below when
that passes the memory budget); --theo-decimated takes the decimated estimator instead where the
direct one costs over 2^26 operations. Mtotdev, ttotdev and htotdev rows are exact at every tau
the same way (lag sums, about O(m log m) per tau, holding 8 N doubles more than Theo1;
--total-decimated takes the plan below instead). TheoBR's bias ratio, and totdev (and mtotdev,
ttotdev, htotdev under --total-decimated), are exact where that costs at most 2^26 operations at their
tau and decimated beyond (blocks or sub-sequences every m/S samples, S from
--total-stride-factor, 16 by default; 'exact' never decimates): the stride column says which. Where the noise is identified the deviations carry Stable32's bias
corrections (totdev for flicker and random-walk FM, htotdev for alpha <= 0) and the EDF is NIST
SP 1065's for the statistic. --fit-long-tau totdev or theoh lets the IEEE-952 fit take TOTDEV or
TheoBR points in place of OADEV at long tau, where they have more degrees of freedom.

Acceptance limits (--limits FILE, docs/metrology.md "Acceptance limits and verdicts"): one limit
a line, '#' comments, e.g.
  N <= 0.003 deg/sqrt(h)      B <= 0.01 deg/h      K <= 0.001 deg/h/sqrt(h)
  adev(100 s) <= 0.005 deg/h  mdev(10 s) <= 0.01 deg/h
  (Q N B K R need --fit ieee952; adev and mdev are read at that tau, added to the taus when it is a
  whole multiple of tau0.) Each verdict by a guard-banded rule on 95 % two-sided intervals (each
  bound one-sided 97.5 %): pass when the upper bound is within the limit, fail when the lower bound
  is beyond it, otherwise undecided (always for a term that is not resolved by an accepted fit),
  with the run length at which the interval is expected to decide (width ~ 1/sqrt(run length)).
  Verdicts in the table, CSV (a second table after a blank line), JSON ("acceptance"; with
  stable32, whose format has no place for them, on stderr), and the exit code: 5 when a limit is
  undecided and none failed, 6 when one failed.
  --summary FILE.csv appends one row for the file (terms, uncertainties, status, verdicts; the
  header written once; a file with another header is refused).
--report FILE.html: one self-contained page (inline SVG plots and CSS, no script, no external
reference; prints to PDF): provenance, ADEV and MDEV with intervals and the fitted model, every
statistic with its intervals, the fit's terms, the read-off values and the verdicts.

Dynamic Allan deviation (--dynamic WINDOW[,STEP], in seconds; STEP defaults to WINDOW): the
  statistics of every window of WINDOW/tau0 values, one starting every STEP/tau0 values, each as
  if its values were a file of their own, at the taus with 4 m <= the window's values (--taus
  chooses among them). Output: the tau x time surface (table, CSV or JSON); --plot PREFIX also
  draws it as heat maps, one per statistic, in PREFIX.svg and PREFIX.png. Values after the last
  complete window are counted, not analysed.

Examples:
  gyrochar-analyze --type phase --tau0 1 --stats adev,oadev,mdev,tdev PHASE.DAT
  gyrochar-analyze --type freq --tau0 1 --nominal-hz 10e6 --taus all --stats mdev ocxo.txt
  gyrochar-analyze --type counts --tau0 0.001 --pulse-weight 1.5arcsec --rate-unit deg/h \
                   --fit ieee952 --format json run.txt.gz
  gyrochar-analyze --type phase --unit deg --tau0 0.01 --column 2 --stats oadev,mdev angle.csv
  gyrochar-analyze --type phase --tau0 1 --stats oadev,mdev --format stable32 PHASE.DAT
  gyrochar-analyze --type counts --tau0 0.01 --pulse-weight 1arcsec --fit ieee952 --kalibr imu.yaml run.txt
  gyrochar-analyze --type counts --tau0 0.1 --pulse-weight 1arcsec --stats oadev,totdev,theoh run120h.txt
  gyrochar-analyze --type counts --tau0 0.1 --pulse-weight 1arcsec --fit ieee952 --fit-long-tau totdev run120h.txt
  zcat run.txt.gz | gyrochar-analyze --type counts --tau0 0.001 --pulse-weight 1.5arcsec -
  gyrochar-analyze --type freq --unit deg/s --tau0 0.01 --fit ieee952 --psd psd.csv --plot imu imu.txt.gz
  gyrochar-analyze --type counts --tau0 0.01 --pulse-weight 1arcsec --dynamic 600,60 --format csv \
                   --plot warmup run.txt > surface.csv

)";

std::vector<std::string> split(const std::string& text, char separator) {
  std::vector<std::string> items;
  std::stringstream ss(text);
  for (std::string item; std::getline(ss, item, separator);) items.push_back(item);
  return items;
}

std::vector<std::uint64_t> parse_tau_list(const std::string& text) {
  std::vector<std::uint64_t> m;
  for (const std::string& item : split(text, ',')) {
    std::uint64_t v = 0;
    const auto [end, ec] = std::from_chars(item.data(), item.data() + item.size(), v);
    if (ec != std::errc() || end != item.data() + item.size() || v == 0)
      bad("--taus", "'" + item + "' is not octave, decade, all or a positive averaging factor");
    if (!m.empty() && v <= m.back()) bad("--taus", "averaging factors must increase");
    m.push_back(v);
  }
  if (m.empty()) bad("--taus", "empty list");
  return m;
}

std::vector<DevStat> parse_stats(const std::string& text) {
  std::vector<DevStat> stats;
  for (const std::string& item : split(text, ',')) {
    const auto s = parse_dev_stat(item);
    if (!s)
      bad("--stats", "unknown statistic '" + item +
                         "' (adev, oadev, mdev, tdev, hdev, ohdev, totdev, mtotdev, ttotdev, htotdev, theo1, theoh)");
    if (std::find(stats.begin(), stats.end(), *s) != stats.end()) bad("--stats", "'" + item + "' is asked twice");
    stats.push_back(*s);
  }
  if (stats.empty()) bad("--stats", "empty list");
  return stats;
}

// What the values say about numerical collapse, as they are read: --nominal-hz's conversion
// y = (f - F0) / F0, refused where it loses the values, and whether the input is constant
// (frequency, counts) or a straight line (phase), whose deviations are all 0 by right.
class InputShape {
 public:
  InputShape(DataType type, double nominal_hz) : phase_(type == DataType::phase), f0_(nominal_hz) {}

  /// Converts `values` in place (--nominal-hz) and takes note of them. Throws BadValue for a value
  /// f != F0 that the conversion takes to 0 or below the smallest normal double. O(n).
  void add(std::span<double> values) {
    for (std::size_t i = 0; i < values.size(); ++i) {
      double& v = values[i];
      if (f0_ > 0) {
        const double f = v;
        v = (f - f0_) / f0_;
        if (f != f0_ && !std::isnormal(v))
          throw BadValue(i, fmt::format("(f - F0) / F0 of {:g} Hz with F0 = {:g} Hz is {:g}, below the smallest "
                                        "normal double (2.2e-308)", f, f0_, v));
        raw_lo_ = n_ == 0 ? f : std::min(raw_lo_, f);
        raw_hi_ = n_ == 0 ? f : std::max(raw_hi_, f);
        converted_vary_ |= n_ > 0 && v != first_;
      }
      if (n_ == 0) first_ = lo_ = hi_ = v;
      lo_ = std::min(lo_, v);
      hi_ = std::max(hi_, v);
      // Phase: every step equal to the first; frequency and counts: every value equal to the first.
      if (phase_ && n_ == 1) step_ = v - last_;
      bent_ |= phase_ ? n_ > 1 && v - last_ != step_ : v != first_;
      last_ = v;
      ++n_;
    }
  }
  /// bad() when --nominal-hz made values that vary all equal: f - F0 rounded them away (values
  /// far below F0 given as Hz: fractional frequency, whose analysis needs no --nominal-hz).
  void check_conversion() const {
    if (f0_ > 0 && raw_lo_ != raw_hi_ && !converted_vary_)
      bad("--nominal-hz", fmt::format("the values vary from {:g} to {:g} Hz, but (f - F0) / F0 with F0 = {:g} Hz makes "
                                      "every one {:g}: their differences are below the resolution of a double at F0 "
                                      "({:.2g} Hz). Are they fractional frequency already (then without --nominal-hz)?",
                                      raw_lo_, raw_hi_, f0_, first_, std::nextafter(f0_, HUGE_VAL) - f0_));
  }
  /// Every deviation of such an input is 0: a constant (frequency, counts), a straight line (phase).
  bool straight() const { return !bent_; }
  const char* shape() const { return phase_ ? "a straight line (a constant frequency)" : "constant"; }
  double lowest() const { return lo_; }
  double highest() const { return hi_; }

 private:
  bool phase_;
  double f0_;
  std::uint64_t n_ = 0;
  double first_ = 0, last_ = 0, step_ = 0, lo_ = 0, hi_ = 0;
  double raw_lo_ = 0, raw_hi_ = 0;
  bool bent_ = false, converted_vary_ = false;
};

// After a whole analysis whose every deviation is 0 (all_zero): a note for a constant or straight
// input, a collapse otherwise (the squares of the differences underflowed to exactly 0).
void check_zeros(bool all_zero, const InputShape& shape, const std::string& source) {
  if (!all_zero) return;
  if (!shape.straight())
    bad(source, fmt::format("every deviation is 0, but the values (from {:g} to {:g}) are not {}: the squares of their "
                            "differences underflow a double (smallest normal 2.2e-308): the values are too small; "
                            "scale them", shape.lowest(), shape.highest(), shape.shape()));
  print_error(program, "note", fmt::format("every deviation is 0: the values are {}", shape.shape()));
}
bool all_zero(const std::vector<AnalysisRow>& rows) {
  return std::all_of(rows.begin(), rows.end(), [](const AnalysisRow& r) { return r.dev == 0; });
}

// Prints how far the reading got, about every 2^20 values, when enabled; nothing for short inputs.
class Progress {
 public:
  Progress(bool enabled, const DataFile& file) : enabled_(enabled), file_(file) {}
  ~Progress() {
    if (progress_line_open) std::fputc('\n', stderr);
    progress_line_open = false;
  }
  void values(std::size_t n) {
    values_ += n;
    if (!enabled_ || values_ < next_) return;
    next_ = values_ + (1u << 20);
    progress_line_open = true;
    const std::uint64_t size = file_.size_bytes();
    if (size > 0)
      std::fprintf(stderr, "\rgyrochar-analyze: reading: %5.1f %%",
                   100.0 * static_cast<double>(file_.bytes_read()) / static_cast<double>(size));
    else
      std::fprintf(stderr, "\rgyrochar-analyze: reading: %llu values", static_cast<unsigned long long>(values_));
  }

 private:
  bool enabled_;
  const DataFile& file_;
  std::uint64_t values_ = 0, next_ = 1u << 20;
};

[[noreturn]] void bad_data(const std::string& source, const DataFileError& e) {
  bad(source, e.line() ? fmt::format("line {}: {}", e.line(), e.what()) : e.what());
}

// The longest window or step of --dynamic, in values: longer than any file (10^15 values are
// petabytes of text), and exact as an integer in a double.
constexpr double max_dynamic_values = 1e15;

// --dynamic WINDOW[,STEP]: one pass over the file, the surface on stdout, the heat maps to --plot.
int analyze_dynamic(AnalysisOptions o, const ReportUnits& units, const std::string& dynamic_text,
                    const std::string& taus_text, const std::string& path, unsigned column, double nominal_hz,
                    const std::string& format, const std::string& plot_prefix, bool show_progress) {
  const std::vector<std::string> parts = split(dynamic_text, ',');
  double window_s = 0, step_s = 0;
  const auto seconds = [](const std::string& t, double& v) {
    const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
    return ec == std::errc() && end == t.data() + t.size() && v > 0 && std::isfinite(v);
  };
  if (parts.empty() || parts.size() > 2 || !seconds(parts[0], window_s) || (parts.size() == 2 && !seconds(parts[1], step_s)))
    bad("--dynamic", "'" + dynamic_text + "' is not WINDOW or WINDOW,STEP in positive seconds");
  if (parts.size() == 1) step_s = window_s;
  const double window_values = std::round(window_s / o.tau0_s), step_values = std::round(step_s / o.tau0_s);
  if (window_values < 4)
    bad("--dynamic", fmt::format("a window of {} s holds {} values of tau0: at least 4 are needed", window_s, window_values));
  if (step_values < 1) bad("--dynamic", fmt::format("a step of {} s is shorter than tau0", step_s));
  for (const auto& [what, seconds_asked, values] : {std::tuple{"window", window_s, window_values}, std::tuple{"step", step_s, step_values}})
    if (values > max_dynamic_values)
      bad("--dynamic", fmt::format("a {} of {:g} s is {:g} values of tau0 = {:g} s, more than the {:g} a window or step "
                                   "may span", what, seconds_asked, values, o.tau0_s, max_dynamic_values));
  const auto window = static_cast<std::uint64_t>(window_values), step = static_cast<std::uint64_t>(step_values);
  // The windows' taus: --taus over the phase points of one window, those with 4 m <= its values.
  const std::uint64_t window_phase = o.type == DataType::phase ? window : window + 1;
  std::vector<std::uint64_t> m_list = taus_text == "octave"   ? octave_taus(window_phase)
                                      : taus_text == "decade" ? decade_taus(window_phase)
                                      : taus_text == "all"
                                          ? all_taus(window_phase, resolve_stride_factor(o.stride_factor, window_phase / 2))
                                          : parse_tau_list(taus_text);
  const std::size_t asked = m_list.size();
  m_list = window_taus(m_list, window);
  if (m_list.empty()) bad("--taus", fmt::format("no tau with 4 m <= the window's {} values", window));
  if (m_list.size() != asked && taus_text != "octave" && taus_text != "decade" && taus_text != "all")
    bad("--taus", fmt::format("averaging factors above {} do not fit a quarter of the window", window / 4));
  o.m_list = m_list;

  std::unique_ptr<DynamicAnalyzer> analyzer;
  try {
    analyzer = std::make_unique<DynamicAnalyzer>(o, window, step);
  } catch (const std::invalid_argument& e) {
    bad("--dynamic", e.what());
  }
  const std::string source = path == "-" ? "standard input" : path;
  std::vector<WindowAnalysis> windows;
  InputShape shape(o.type, nominal_hz);
  try {
    DataFile file(path, column);
    Progress p(show_progress, file);
    std::vector<double> block(1 << 14);
    while (const std::size_t n = file.read(block)) {
      const std::span<double> values(block.data(), n);
      try {
        shape.add(values);
        analyzer->add(values);
      } catch (const BadValue& e) {
        bad(source, fmt::format("line {}: {}", file.line_of(e.index()), e.what()));
      } catch (const std::range_error& e) {
        bad(source, fmt::format("by line {}: {}", file.line_of(n - 1), e.what()));
      }
      for (WindowAnalysis& w : analyzer->take_completed()) windows.push_back(std::move(w));
      p.values(n);
    }
  } catch (const DataFileError& e) {
    bad_data(source, e);
  }
  shape.check_conversion();
  if (windows.empty())
    bad(source, fmt::format("{} values are fewer than one window of {} values", analyzer->values(), window));
  check_zeros(std::all_of(windows.begin(), windows.end(), [](const WindowAnalysis& w) { return all_zero(w.analysis.rows); }),
              shape, source);
  const DynamicReport report{windows, o.type, o.tau0_s, o.confidence, units, window, step, analyzer->values(), o.stats};
  const std::string text = format == "json" ? dynamic_to_json(report).dump(2) + "\n"
                           : format == "csv" ? format_dynamic_csv(report)
                                             : format_dynamic_table(report);
  std::fwrite(text.data(), 1, text.size(), stdout);
  if (!plot_prefix.empty()) {
    std::string why;
    if (!write_heat_maps(plot_prefix, dynamic_heat_maps(report), why)) fail(exit_code::output_failed, "--plot", why);
  }
  return finish(program, exit_code::ok);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"gyrochar-analyze: ADEV, OADEV, MDEV, TDEV, HDEV, OHDEV (streamed, any length) and TOTDEV,\n"
               "MTOTDEV, TTOTDEV, HTOTDEV, Theo1, TheoH (held in memory) of a recorded file, with EDF,\n"
               "confidence intervals, noise identification and the IEEE-952 gyro fit.",
               "gyrochar-analyze"};
  app.footer(std::string(footer) + exit_code::help +
             "\nWith --limits: 5 a limit is undecided (none failed); 6 a limit failed (the analysis is written).");
  std::string path, type_text, value_unit, pulse_weight_text, pulse_unit = "arcsec", rate_text = "deg/h";
  std::string taus_text = "octave", stats_text = "oadev,mdev", stride_text = "full", alpha_text = "auto";
  std::string format = "table", fit_text, kalibr_path, dynamic_text, plot_prefix;
  double tau0_s = 0, nominal_hz = 0, confidence = 0.683;
  unsigned column = 0;  // 0: the reader chooses
  bool progress = false, theo_decimated = false, total_decimated = false;
  app.add_option("file", path, "data file (plain or gzip), '-' for standard input")->required();
  app.add_option("--type", type_text, "phase, freq or counts")->required();
  app.add_option("--tau0", tau0_s, "sample interval in seconds")->required();
  app.add_option("--unit", value_unit, "unit of phase (s or an angle) or freq (1, Hz or a rate) values");
  app.add_option("--pulse-weight", pulse_weight_text, "angle of one pulse, with its unit (counts)");
  app.add_option("--pulse-unit", pulse_unit, "unit of --pulse-weight when it has none")->capture_default_str();
  app.add_option("--rate-unit", rate_text, "output unit of gyro data: deg/h, deg/s, rad/s")->capture_default_str();
  app.add_option("--nominal-hz", nominal_hz, "freq values are in Hz around this nominal frequency");
  app.add_option("--column", column, "column holding the values (1-based; default: the only one, or the value of time,value)");
  app.add_option("--taus", taus_text, "octave, decade, all, or averaging factors m (1,10,100)")->capture_default_str();
  app.add_option("--stats", stats_text, "any of adev,oadev,mdev,tdev,hdev,ohdev,totdev,mtotdev,ttotdev,htotdev,theo1,theoh")
      ->capture_default_str();
  app.add_option("--stride-factor", stride_text, "S, a power of two, or full")->capture_default_str();
  std::string total_stride_text = "16";
  app.add_option("--total-stride-factor", total_stride_text,
                 "S of the decimated total/Theo estimators (a power of two from 2 to 2^20), or exact")
      ->capture_default_str();
  app.add_flag("--theo-decimated", theo_decimated,
              "Theo1/TheoBR rows by the decimated estimator beyond 2^26 operations (the exact lag-sum one otherwise)");
  app.add_flag("--total-decimated", total_decimated,
               "MTOTDEV/TTOTDEV/HTOTDEV rows by the decimated estimator beyond 2^26 operations (the exact lag-sum one otherwise)");
  app.add_option("--confidence", confidence, "confidence level of the intervals")->capture_default_str();
  app.add_option("--alpha", alpha_text, "noise exponent for the EDF: auto (identified per tau) or -4..2")->capture_default_str();
  app.add_option("--fit", fit_text, "ieee952: fit Q, N, B, K, R to the oadev and mdev curves (both computed)");
  std::string long_tau_text = "oadev";
  app.add_option("--fit-long-tau", long_tau_text,
                 "the fit's Allan curve at long tau: oadev, totdev or theoh (docs/metrology.md)")
      ->capture_default_str();
  app.add_option("--format", format, "table, csv, json or stable32 (Stable32's result table, one per statistic)")
      ->capture_default_str();
  app.add_option("--kalibr", kalibr_path, "with --fit ieee952 on gyro data: also write N and K as a Kalibr imu.yaml")
      ->option_text("FILE");
  app.add_option("--dynamic", dynamic_text, "dynamic Allan deviation: windows of WINDOW s, one every STEP s")
      ->option_text("WINDOW[,STEP]");
  app.add_option("--plot", plot_prefix,
                 "draw ADEV, MDEV (with the fit's terms) and the PSD to PREFIX.svg and PREFIX.png; with --dynamic, "
                 "the heat maps")
      ->option_text("PREFIX");
  std::string psd_path;
  std::size_t psd_segment = 0;
  bool no_sinusoid_search = false;
  std::vector<double> sinusoid_hz;
  app.add_option("--psd", psd_path, "write the rate's Welch PSD with its confidence band (CSV: freq,psd,ci_low,ci_high)")
      ->option_text("FILE");
  app.add_option("--psd-segment", psd_segment, "values per Welch segment (even; default: largest power of two <= N/16)");
  app.add_flag("--no-sinusoid-search", no_sinusoid_search, "do not search the PSD for sinusoids to offer the fit");
  app.add_option("--sinusoid-hz", sinusoid_hz, "offer the fit a sinusoid at this frequency in Hz (repeatable, up to 2)")
      ->option_text("F");
  unsigned threads = 0;
  app.add_option("--threads", threads, "threads summing the taus of counts at --stride-factor full and of --taus all (default: one per core)")
      ->check(CLI::Range(1u, 1024u));
  std::string limits_path, summary_path, report_path;
  app.add_option("--limits", limits_path, "acceptance limits: a verdict per limit (see below)")->option_text("FILE");
  app.add_option("--summary", summary_path, "with --limits: append the file's production summary row to FILE.csv")
      ->option_text("FILE.csv");
  app.add_option("--report", report_path, "write a self-contained HTML report (plots, tables, fit, verdicts)")
      ->option_text("FILE.html");
  app.add_flag("--progress", progress, "show progress on stderr (default: when stderr is a terminal)");
  if (const auto code = parse_command_line(app, argc, argv, program)) return finish(program, *code);
  std::vector<NamedPath> outputs = plot_outputs("--plot", plot_prefix);
  outputs.insert(outputs.begin(), {"--kalibr", kalibr_path});
  outputs.insert(outputs.begin(), {"--psd", psd_path});
  outputs.push_back({"--summary", summary_path});
  outputs.push_back({"--report", report_path});
  if (!report_path.empty()) outputs.push_back({"--report", report_path + ".part"});
  if (const auto conflict = output_conflict({{"file", path}, {"--limits", limits_path}}, outputs))
    bad(conflict->what, conflict->why);
  std::string command;  // for the report's provenance
  for (int i = 0; i < argc; ++i)
    command += (i ? " " : "") + (std::string(argv[i]).find_first_of(" '\"") == std::string::npos
                                     ? std::string(argv[i])
                                     : "'" + std::string(argv[i]) + "'");

  try {
    // Options, checked before any data is read.
    AnalysisOptions o;
    o.theo_decimated = theo_decimated;
    o.total_decimated = total_decimated;
    if (type_text == "phase") o.type = DataType::phase;
    else if (type_text == "freq") o.type = DataType::freq;
    else if (type_text == "counts") o.type = DataType::counts;
    else bad("--type", "must be phase, freq or counts, not '" + type_text + "'");
    if (!(tau0_s > 0) || !std::isfinite(tau0_s)) bad("--tau0", "must be a positive number of seconds");
    o.tau0_s = tau0_s;
    if (app.count("--column") && column == 0) bad("--column", "columns are numbered from 1");
    if (!(confidence > 0 && confidence < 1)) bad("--confidence", "must be between 0 and 1");
    o.confidence = confidence;
    o.stats = parse_stats(stats_text);
    if (stride_text != "full") {
      const auto [end, ec] = std::from_chars(stride_text.data(), stride_text.data() + stride_text.size(), o.stride_factor);
      if (ec != std::errc() || end != stride_text.data() + stride_text.size() || o.stride_factor < 2 ||
          (o.stride_factor & (o.stride_factor - 1)) != 0 || o.stride_factor > (1u << 24))
        bad("--stride-factor", "must be a power of two from 2 to 2^24, or full");
    }
    if (total_stride_text == "exact") {
      o.total_stride_factor = 0;
    } else {
      const auto [end, ec] =
          std::from_chars(total_stride_text.data(), total_stride_text.data() + total_stride_text.size(), o.total_stride_factor);
      if (ec != std::errc() || end != total_stride_text.data() + total_stride_text.size() || o.total_stride_factor < 2 ||
          (o.total_stride_factor & (o.total_stride_factor - 1)) != 0 || o.total_stride_factor > (1u << 20))
        bad("--total-stride-factor", "must be a power of two from 2 to 2^20, or exact");
    }
    if (alpha_text != "auto") {
      int a = 0;
      const auto [end, ec] = std::from_chars(alpha_text.data(), alpha_text.data() + alpha_text.size(), a);
      if (ec != std::errc() || end != alpha_text.data() + alpha_text.size() || a < -4 || a > 2)
        bad("--alpha", "must be auto or an integer from -4 to 2");
      o.alpha = a;
    }
    if (format != "table" && format != "csv" && format != "json" && format != "stable32")
      bad("--format", "must be table, csv, json or stable32");
    if (!plot_prefix.empty()) {
      if (const std::string missing = plot_devices_missing(); !missing.empty()) bad("--plot", missing);
    }
    if (!fit_text.empty() && fit_text != "ieee952") bad("--fit", "the only model is ieee952");
    if (!kalibr_path.empty() && fit_text.empty()) bad("--kalibr", "needs --fit ieee952 (the file holds fitted terms)");
    LongTau long_tau = LongTau::oadev;
    if (long_tau_text == "totdev") long_tau = LongTau::totdev;
    else if (long_tau_text == "theoh") long_tau = LongTau::theoh;
    else if (long_tau_text != "oadev") bad("--fit-long-tau", "must be oadev, totdev or theoh, not '" + long_tau_text + "'");
    if (long_tau != LongTau::oadev && fit_text.empty()) bad("--fit-long-tau", "only applies with --fit ieee952");
    o.keep_record = long_tau != LongTau::oadev;
    // Acceptance limits: read and checked before any data.
    std::vector<Limit> limits;
    if (!limits_path.empty()) {
      try {
        limits = read_limits_file(limits_path);
      } catch (const LimitsError& e) {
        bad("--limits", limits_path + ": " + e.what());
      }
      for (const Limit& l : limits)
        if (l.kind == Limit::Kind::term && fit_text.empty())
          bad("--limits", fmt::format("{}: line {}: {} is a fitted term: add --fit ieee952", limits_path, l.line,
                                      l.quantity()));
    }
    if (!summary_path.empty()) {
      if (limits.empty()) bad("--summary", "needs --limits (the row holds the verdicts)");
      std::string why;
      if (!summary_compatible(summary_path, limits, why)) bad("--summary", summary_path + ": " + why);
    }
    // The fit uses both curves, whatever the table shows: compute them, show what was asked.
    const std::vector<DevStat> shown = o.stats;
    for (const Limit& l : limits) {  // limited deviations are computed, shown or not
      const DevStat st = l.kind == Limit::Kind::adev ? DevStat::oadev : DevStat::mdev;
      if (l.kind != Limit::Kind::term && std::find(o.stats.begin(), o.stats.end(), st) == o.stats.end())
        o.stats.push_back(st);
    }
    if (!fit_text.empty())
      for (const DevStat s : {DevStat::oadev, DevStat::mdev})
        if (std::find(o.stats.begin(), o.stats.end(), s) == o.stats.end()) o.stats.push_back(s);

    // Units: what the values are, and the output unit of gyro data (input_units.hpp).
    ReportUnits units;
    try {
      UnitOptions uo;
      uo.type = o.type;
      uo.unit = value_unit;
      uo.pulse_weight = pulse_weight_text;
      uo.pulse_unit = pulse_unit;
      uo.pulse_unit_given = app.count("--pulse-unit") > 0;
      if (app.count("--nominal-hz")) uo.nominal_hz = nominal_hz;
      uo.rate_unit = rate_text;
      uo.rate_unit_given = app.count("--rate-unit") > 0;
      units = resolve_units(uo);
    } catch (const UnitError& e) {
      bad(e.option(), e.what());
    }
    if (!kalibr_path.empty() && !units.gyro)
      bad("--kalibr", "needs gyro data: counts, or --unit with an angle or a rate");
    if (!limits.empty() && !units.gyro)
      bad("--limits", "limits are in gyro units: needs gyro data (counts, or --unit with an angle or a rate)");

    const bool show_progress = progress || isatty(STDERR_FILENO);
    const std::string source = path == "-" ? "standard input" : path;
    if (psd_segment != 0 && (psd_segment < 8 || psd_segment % 2 != 0)) bad("--psd-segment", "must be even and at least 8");
    if (sinusoid_hz.size() > max_sinusoids) bad("--sinusoid-hz", fmt::format("at most {} frequencies", max_sinusoids));
    for (const double f : sinusoid_hz)
      if (!(f > 0 && f < 0.5 / tau0_s)) bad("--sinusoid-hz", fmt::format("{} Hz is not between 0 and the Nyquist frequency {} Hz", f, 0.5 / tau0_s));
    if (!sinusoid_hz.empty() && fit_text.empty()) bad("--sinusoid-hz", "offers sinusoids to --fit ieee952");
    // The PSD: asked for (--psd, the static --plot) or searched for sinusoids to offer the fit.
    const bool want_psd = !psd_path.empty() || (!plot_prefix.empty() && dynamic_text.empty()) ||
                          (!fit_text.empty() && !no_sinusoid_search);
    if (!plot_prefix.empty() && dynamic_text.empty())  // the static plot draws ADEV and MDEV
      for (const DevStat st : {DevStat::oadev, DevStat::mdev})
        if (std::find(o.stats.begin(), o.stats.end(), st) == o.stats.end()) o.stats.push_back(st);
    if (!dynamic_text.empty()) {
      if (!fit_text.empty()) bad("--fit", "fits the whole run's curves: not with --dynamic");
      if (!limits.empty() || !report_path.empty())
        bad(limits.empty() ? "--report" : "--limits", "is about the whole run: not with --dynamic");
      if (!psd_path.empty() || psd_segment != 0) bad("--psd", "the PSD is of the whole run: not with --dynamic");
      return analyze_dynamic(o, units, dynamic_text, taus_text, path, column, nominal_hz, format, plot_prefix,
                             show_progress);
    }

    // One pass over the data. The taus are chosen before it from the file's length, an upper
    // bound on the values (rows the data does not reach are left out); --taus all reads the
    // values into memory first, to know N.
    const auto phase_points = [&](std::uint64_t values) { return o.type == DataType::phase ? values : values + 1; };
    std::unique_ptr<DataFile> file;
    std::vector<double> kept;           // --taus all: every value, and its line
    std::vector<std::uint64_t> kept_lines;
    std::uint64_t n_phase = 0;          // phase points: exact (all), an upper bound, or 0 (unknown)
    try {
      file = std::make_unique<DataFile>(path, column);
      if (taus_text == "all") {
        std::vector<double> block(1 << 14);
        while (const std::size_t n = file->read(block)) {
          kept.insert(kept.end(), block.begin(), block.begin() + static_cast<std::ptrdiff_t>(n));
          for (std::size_t i = 0; i < n; ++i) kept_lines.push_back(file->line_of(i));
        }
        if (kept.empty()) bad(source, "no data (empty, or only comments and blank lines)");
        n_phase = phase_points(kept.size());
      } else if (file->values_bound() > 0) {
        n_phase = phase_points(file->values_bound());
      }
    } catch (const DataFileError& e) {
      bad_data(source, e);
    }
    // The taus, the stride factor "full" resolves to and the held record (plan.hpp).
    o.values_hint = taus_text == "all" ? kept.size() : file->values_bound();
    o.threads = threads;
    if (show_progress)
      o.on_summed = [shown = std::size_t{0}](std::size_t done, std::size_t total) mutable {
        if (done < total && 1000 * done / total == 1000 * shown / total) return;  // every 0.1 %
        shown = done;
        progress_line_open = done < total;
        std::fprintf(stderr, "\rgyrochar-analyze: summing: %zu of %zu taus%s", done, total, done < total ? "" : "\n");
      };
    const std::uint64_t budget = memory_budget();
    const bool generated = taus_text == "octave" || taus_text == "decade" || taus_text == "all";
    const TauPlan plan = plan_taus(o, taus_text, generated ? std::vector<std::uint64_t>{} : parse_tau_list(taus_text),
                                   n_phase, budget);
    const std::vector<std::uint64_t>& not_formed = plan.not_formed;
    const bool held = plan.held;
    const std::uint64_t cut_above = plan.cut_above;
    const std::uint32_t s = o.stride_factor;
    if (o.m_list.empty()) bad(source, fmt::format("{} phase points are too few for any tau", n_phase));
    for (const Limit& l : limits) {  // a limited tau joins the taus when the pyramid can form it
      const std::uint64_t m = limit_m(l, o.tau0_s);
      if (m == 0 || std::binary_search(o.m_list.begin(), o.m_list.end(), m)) continue;
      if ((n_phase == 0 || m <= n_phase / 2) && (held || tau_representable(m, o.stride_factor)))
        o.m_list.insert(std::upper_bound(o.m_list.begin(), o.m_list.end(), m), m);
    }
    // More memory than the process may use, or an allocation that failed: a stride factor given is
    // the user's choice (bad input); under the default the cause is the memory limit (exit 1).
    const auto too_big = [&] {
      const std::uint64_t bytes = o.hold_counts  ? 12 * o.values_hint
                                  : o.hold_phase ? 24 * o.values_hint
                                                 : history_bytes(o.type, s, o.m_list.back());
      if (stride_text != "full")
        bad("--stride-factor", fmt::format("{} with taus up to {} needs {} MiB of history, more than the {} MiB this "
                                           "process may use: give a smaller stride factor or fewer taus",
                                           s, o.m_list.back(), bytes >> 20, budget >> 20));
      fail(exit_code::internal, source,
           fmt::format("{} values{} need {} MiB of memory with every tau up to N/4 fully overlapped (--stride-factor "
                       "full, the default), more than the {} MiB this process may use ({}): raise the limit, or give "
                       "--stride-factor 8 (a few MiB whatever the length)", o.values_hint,
                       taus_text == "all" ? "" : " (at most, from the file's size)", std::max<std::uint64_t>(bytes >> 20, 1),
                       budget >> 20, memory_budget_reason()));
    };
    if (!held && history_bytes(o.type, s, o.m_list.back()) > budget) too_big();

    std::unique_ptr<Analyzer> analyzer;
    try {
      analyzer = std::make_unique<Analyzer>(o);
    } catch (const std::invalid_argument& e) {
      bad("--taus", e.what());
    } catch (const std::bad_alloc&) {
      too_big();
    }
    DataRange range;
    std::optional<RateRecord> rates;  // the rate, held for the PSD (8 bytes a value)
    if (want_psd) rates.emplace(o.type == DataType::phase, o.type == DataType::counts, o.tau0_s);
    InputShape shape(o.type, nominal_hz);
    const auto add = [&](std::span<double> values, auto line_of) {
      try {
        shape.add(values);
        range.add(values);
        if (rates) rates->add(values);
        analyzer->add(values);
      } catch (const BadValue& e) {
        bad(source, fmt::format("line {}: {}", line_of(e.index()), e.what()));
      } catch (const std::range_error& e) {
        bad(source, fmt::format("by line {}: {}", line_of(values.size() - 1), e.what()));
      }
    };
    try {
      Progress p(show_progress, *file);
      if (taus_text == "all") {
        for (std::size_t i = 0; i < kept.size(); i += 1 << 14) {
          const std::size_t n = std::min<std::size_t>(kept.size() - i, 1 << 14);
          add({kept.data() + i, n}, [&](std::size_t k) { return kept_lines[i + k]; });
        }
      } else {
        std::vector<double> block(1 << 14);
        while (const std::size_t n = file->read(block)) {
          add({block.data(), n}, [&](std::size_t k) { return file->line_of(k); });
          p.values(n);
        }
      }
    } catch (const DataFileError& e) {
      bad_data(source, e);
    }
    shape.check_conversion();
    Analysis a = [&] {
      try {
        return analyzer->result();
      } catch (const std::range_error& e) {  // a deviation that is not a finite number, and why
        bad(source, e.what());
      }
    }();
    if (a.n_values == 0) bad(source, "no data (empty, or only comments and blank lines)");
    for (const std::uint64_t m : not_formed)
      if (m <= a.n_phase / 2)
        bad("--taus", fmt::format("averaging factor {} cannot be formed with stride factor {}: above S it must be a "
                                  "multiple of its stride (m/S rounded up to a power of two)", m, s));
    if (a.rows.empty()) bad(source, fmt::format("{} values are too few for any of the taus asked", a.n_values));
    check_zeros(all_zero(a.rows), shape, source);
    if (!file->layout_note().empty()) print_error(program, source, "values from " + file->layout_note());
    if (cut_above > 0 && cut_above <= a.n_phase / 2)
      print_error(program, source, fmt::format("taus stop below m = {}: with stride factor {} more would need more than "
                                               "{} MiB of history", cut_above, s, budget >> 20));
    const std::vector<std::string>& header = file->header();

    std::optional<Spectrum> spectrum;
    if (rates) {
      const std::vector<double>& rate = rates->rate();
      const std::size_t segment = psd_segment ? psd_segment : default_psd_segment(rate.size());
      if (segment > rate.size() || segment == 0) {
        if (!psd_path.empty() || psd_segment != 0)
          bad(psd_segment ? "--psd-segment" : "--psd",
              fmt::format("{} rate values are too few for a segment of {}", rate.size(), segment ? segment : 16));
        print_error(program, "note", fmt::format("no PSD: {} rate values are too few for a spectrum", rate.size()));
      } else {
        Spectrum sp = spectrum_of(*rates, o.tau0_s, segment, o.confidence, !no_sinusoid_search);
        if (sp.searched) {
          std::vector<std::pair<double, double>> oadev;  // the Allan curve's nulls at tau = 1/f, on dense taus
          for (const AnalysisRow& r : a.rows)
            if (r.stat == DevStat::oadev) oadev.emplace_back(r.tau_s, r.dev);
          check_adev_nulls(sp.search, oadev);
        }
        sp.given_hz = sinusoid_hz;
        sp.factor = units.factor();
        sp.unit = units.unit(DevStat::oadev);
        spectrum = std::move(sp);
      }
      rates.reset();
    }
    std::array<double, max_sinusoids> offered_hz{};
    for (std::size_t k = 0; k < sinusoid_hz.size(); ++k) offered_hz[k] = sinusoid_hz[k];
    if (spectrum) offered_hz = spectrum->fit_hz();
    std::vector<CurveFit> fits;
    if (!fit_text.empty())
      fits = fit_curves(a, units, o.tau0_s, o.type == DataType::counts ? units.phase_unit_si / std::sqrt(12.0) : 0.0,
                        long_tau, analyzer->record(), offered_hz);
    std::optional<Readoff> readoff = readoff_of(a, units);  // every OADEV row, shown or computed for the fit
    std::vector<AnalysisRow> plotted;  // --plot and --report draw OADEV and MDEV, shown or not; limits read them
    if (!plot_prefix.empty() || !report_path.empty() || !limits.empty())
      std::copy_if(a.rows.begin(), a.rows.end(), std::back_inserter(plotted),
                   [](const AnalysisRow& r) { return r.stat == DevStat::oadev || r.stat == DevStat::mdev; });
    Analysis displayed = std::move(a);  // (a --taus all run has millions of rows: not copied)
    std::erase_if(displayed.rows, [&](const AnalysisRow& r) { return std::find(shown.begin(), shown.end(), r.stat) == shown.end(); });
    // A tau asked for by number but too long for the data has no row: say so. (The octave,
    // decade and all lists stop where the data end by design.)
    const bool taus_listed = taus_text != "octave" && taus_text != "decade" && taus_text != "all";
    for (const std::uint64_t m : taus_listed ? o.m_list : std::vector<std::uint64_t>{}) {
      std::string missing;
      for (const DevStat stat : shown)
        if (std::none_of(displayed.rows.begin(), displayed.rows.end(),
                         [&](const AnalysisRow& r) { return r.stat == stat && r.m == m; }))
          missing += (missing.empty() ? "" : ", ") + std::string(name(stat));
      if (!missing.empty())
        print_error(program, "note",
                    fmt::format("m = {} (tau = {:g} s) left out of {}: {} phase points are too few for a term", m,
                                static_cast<double>(m) * o.tau0_s, missing, displayed.n_phase));
    }
    for (const AnalysisRow& r : displayed.rows) {  // the output unit must not take a value out of range
      if (!std::isfinite(r.dev * units.factor()) || (r.ci.valid && !std::isfinite(r.ci.high * units.factor())))
        bad(source, fmt::format("{} at tau = {:g} s (m = {}): {:g} times the unit factor {:g} ({}) overflows a double",
                                name(r.stat), r.tau_s, r.m, r.ci.valid ? r.ci.high : r.dev, units.factor(),
                                units.unit(r.stat)));
      if (r.dev != 0 && !(r.dev * units.factor() >= DBL_MIN))
        bad(source, fmt::format("{} at tau = {:g} s (m = {}): {:g} times the unit factor {:g} ({}) underflows a double "
                                "(smallest normal 2.2e-308)", name(r.stat), r.tau_s, r.m, r.dev, units.factor(),
                                units.unit(r.stat)));
    }
    Report report{displayed, o.type, o.tau0_s, o.confidence, units, std::move(fits), std::nullopt, source, range,
                  std::move(readoff), std::nullopt};
    if (!report.fits.empty()) report.truth = truth_of(header, o.type, o.tau0_s, units.phase_unit_si);
    report.spectrum = std::move(spectrum);
    const double run_s = static_cast<double>(report.analysis.n_values) * o.tau0_s;
    const std::vector<Decision> decisions = decide_limits(limits, report, plotted, run_s);
    std::string yaml;  // made before anything is written: a refusal loses no output
    if (!kalibr_path.empty()) {
      std::string why;
      const auto text = kalibr_yaml(report, why);
      if (!text) bad("--kalibr", why);
      if (!why.empty()) print_error(program, "note", kalibr_path + ": " + why);
      yaml = *text;
      if (const std::string beyond = kalibr_left_out(report.fits.front().fit); !beyond.empty())
        print_error(program, "note", "--kalibr: gyroscope_noise_density is the fitted white-rate N, gyroscope_random_walk the "
                                     "fitted rate random walk K; Kalibr's model has no place for the model's " + beyond);
    }
    const auto json_text = [&] {
      nlohmann::json j = to_json(report);
      if (!limits.empty()) j["acceptance"] = acceptance_json(limits, decisions);
      return j.dump(2) + "\n";
    };
    const std::string verdicts = limits.empty() ? std::string() : acceptance_table(limits, decisions);
    const std::string text = format == "json"       ? json_text()
                             : format == "csv"      ? format_csv(report) + (limits.empty() ? "" : acceptance_csv(limits, decisions))
                             : format == "stable32" ? format_stable32(report)
                                                    : format_table(report) + verdicts;
    if (format == "stable32" && !limits.empty()) std::fputs(verdicts.c_str(), stderr);  // its format has no place
    std::fwrite(text.data(), 1, text.size(), stdout);
    if (!psd_path.empty()) {
      std::FILE* f = std::fopen(psd_path.c_str(), "w");
      if (f == nullptr) fail(exit_code::output_failed, psd_path, std::strerror(errno));
      std::fputs(spectrum_csv(*report.spectrum).c_str(), f);
      if (!close_output(f, program, psd_path)) return finish(program, exit_code::output_failed);
    }
    if (!plot_prefix.empty()) {
      std::string why;
      if (!write_static_plot(plot_prefix, report, plotted, why)) fail(exit_code::output_failed, "--plot", why);
    }
    if (!kalibr_path.empty()) {
      std::FILE* f = std::fopen(kalibr_path.c_str(), "w");
      if (f == nullptr) fail(exit_code::output_failed, kalibr_path, std::strerror(errno));
      std::fputs(yaml.c_str(), f);
      if (!close_output(f, program, kalibr_path)) return finish(program, exit_code::output_failed);
    }
    if (!report_path.empty()) {
      std::string why;
      const std::string page = analysis_html(report, plotted, {command, limits_path}, limits, decisions);
      if (!html::write_file_atomically(report_path, page, why)) fail(exit_code::output_failed, "--report", why);
    }
    if (!summary_path.empty()) {
      GyroSummary g{source, "", run_s, report.analysis.n_values, "", 0, {}, decisions};
      if (!report.fits.empty()) {
        const Ieee952Fit& fit = report.fits.front().fit;
        g.fit_status = name(fit.status);
        g.chi2_per_dof = fit.chi2_per_dof();
        for (std::size_t k = 0; k < 5; ++k) {
          const Ieee952Parameter& p = fit.p[k];
          g.terms[k] = {p.fitted, p.value / units::ieee952[k].si, p.uncertainty / units::ieee952[k].si,
                        !p.fitted ? "not in model" : p.resolved ? "resolved" : "not resolved"};
        }
      }
      std::string why;
      if (!append_summary(summary_path, limits, {g}, why)) fail(exit_code::output_failed, "--summary", summary_path + ": " + why);
    }
    if (!limits.empty()) {  // a lost output (4) comes before the verdict
      const int code = finish(program, exit_code::ok);
      return code != exit_code::ok ? code : exit_code_of(overall(decisions));
    }
  } catch (const std::bad_alloc&) {  // beyond the plan's own check (too_big): say what limits memory
    fail(exit_code::internal, "out of memory",
         fmt::format("an allocation failed: this process may use {} MiB ({})", memory_budget() >> 20, memory_budget_reason()));
  } catch (const std::exception& e) {
    fail(exit_code::internal, "internal error", e.what());
  }
  return finish(program, exit_code::ok);
}
