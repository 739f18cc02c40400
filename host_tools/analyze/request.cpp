// gyrochar-analyze's command line (request.hpp): the options, their --help, and the checks every
// option passes before any data is read, in one place and one order.
#include "request.hpp"

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <charconv>
#include <cmath>
#include <sstream>
#include <tuple>

#include "figure.hpp"
#include "input_units.hpp"
#include "output_paths.hpp"
#include "psd.hpp"
#include "verdict_output.hpp"
#include "hal/program/command_line.hpp"
#include "hal/program/exit_codes.hpp"

namespace gyrochar {

void bad(const std::string& what, const std::string& why) { fail(exit_code::bad_input, what, why); }
void fail(int code, const std::string& what, const std::string& why) { throw ToolError{code, what, why}; }

namespace {

constexpr const char* footer =
    R"(Data type and units (the type is required: for a gyro "frequency" is rate and "phase" is angle):
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
  then grows with N, up to S = 2^24 (3S points of 24 bytes); a file's record held in memory
  needs no history, and there S has no such limit; on standard input, whose length is
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
4 N + 2 fft_length(2 N) doubles, 0.9 GB at 10^7 points, or the decimated estimator below when
that passes the memory budget); --theo-decimated takes the decimated estimator instead where the
direct one costs over 2^26 operations. Mtotdev, ttotdev and htotdev rows are exact at every tau
the same way (lag sums, about O(m log m) per tau, holding 4 N doubles more than Theo1;
--total-decimated takes the plan below instead). Totdev rows are exact at every tau (O(N) a tau;
for counts O(m), the overlapping AVAR's exact sum standing for the terms it shares). TheoBR's bias
ratio (and mtotdev, ttotdev, htotdev under --total-decimated) is exact where that costs at most
2^26 operations at its tau and decimated beyond (blocks or sub-sequences every m/S samples, S from
--total-stride-factor, 16 by default; 'exact' never decimates), except that for counts mtotdev,
ttotdev and htotdev rows up to m = 128 stay exact (one pass over the record's differences, then
O(m^3) a tau): the stride column says which. Where the noise is identified the deviations carry Stable32's bias
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
// The options as CLI11 reads them, before they are checked: text where the analyzer parses it.
struct OptionText {
  std::string type, value_unit, pulse_weight, pulse_unit = "arcsec", rate = "deg/h";
  std::string taus = "octave", stats = "oadev,mdev", stride = "full", alpha = "auto";
  std::string format = "table", fit, dynamic, total_stride = "16", long_tau = "oadev";
  double tau0_s = 0, nominal_hz = 0, confidence = 0.683;
  bool progress = false, theo_decimated = false, total_decimated = false, no_sinusoid_search = false;
  unsigned threads = 0;
};

void add_options(CLI::App& app, OptionText& t, Request& r) {
  app.add_option("file", r.path, "data file (plain or gzip), '-' for standard input")->required();
  app.add_option("--type", t.type, "phase, freq or counts")->required();
  app.add_option("--tau0", t.tau0_s, "sample interval in seconds")->required();
  app.add_option("--unit", t.value_unit, "unit of phase (s or an angle) or freq (1, Hz or a rate) values");
  app.add_option("--pulse-weight", t.pulse_weight, "angle of one pulse, with its unit (counts)");
  app.add_option("--pulse-unit", t.pulse_unit, "unit of --pulse-weight when it has none")->capture_default_str();
  app.add_option("--rate-unit", t.rate, "output unit of gyro data: deg/h, deg/s, rad/s")->capture_default_str();
  app.add_option("--nominal-hz", t.nominal_hz, "freq values are in Hz around this nominal frequency");
  app.add_option("--column", r.column,
                 "column holding the values (1-based; default: the only one, or the value of time,value)");
  app.add_option("--taus", t.taus, "octave, decade, all, or averaging factors m (1,10,100)")->capture_default_str();
  app.add_option("--stats", t.stats, "any of " + dev_stat_names(","))->capture_default_str();
  app.add_option("--stride-factor", t.stride, "S, a power of two, or full")->capture_default_str();
  app.add_option("--total-stride-factor", t.total_stride,
                 "S of the decimated total/Theo estimators (a power of two from 2 to 2^20), or exact")
      ->capture_default_str();
  app.add_flag("--theo-decimated", t.theo_decimated,
               "Theo1/TheoBR rows by the decimated estimator beyond 2^26 operations (the exact lag-sum one otherwise)");
  app.add_flag(
      "--total-decimated", t.total_decimated,
      "MTOTDEV/TTOTDEV/HTOTDEV rows by the decimated estimator beyond 2^26 operations (the exact lag-sum one otherwise)");
  app.add_option("--confidence", t.confidence, "confidence level of the intervals")->capture_default_str();
  app.add_option("--alpha", t.alpha, "noise exponent for the EDF: auto (identified per tau) or -4..2")
      ->capture_default_str();
  app.add_option("--fit", t.fit, "ieee952: fit Q, N, B, K, R to the oadev and mdev curves (both computed)");
  app.add_option("--fit-long-tau", t.long_tau,
                 "the fit's Allan curve at long tau: oadev, totdev or theoh (docs/metrology.md)")
      ->capture_default_str();
  app.add_option("--format", t.format, "table, csv, json or stable32 (Stable32's result table, one per statistic)")
      ->capture_default_str();
  app.add_option("--kalibr", r.kalibr_path, "with --fit ieee952 on gyro data: also write N and K as a Kalibr imu.yaml")
      ->option_text("FILE");
  app.add_option("--dynamic", t.dynamic, "dynamic Allan deviation: windows of WINDOW s, one every STEP s")
      ->option_text("WINDOW[,STEP]");
  app.add_option("--plot", r.plot_prefix,
                 "draw ADEV, MDEV (with the fit's terms) and the PSD to PREFIX.svg and PREFIX.png; with --dynamic, "
                 "the heat maps")
      ->option_text("PREFIX");
  app.add_option("--psd", r.psd_path, "write the rate's Welch PSD with its confidence band (CSV: freq,psd,ci_low,ci_high)")
      ->option_text("FILE");
  app.add_option("--psd-segment", r.psd_segment, "values per Welch segment (even; default: largest power of two <= N/16)");
  app.add_flag("--no-sinusoid-search", t.no_sinusoid_search, "do not search the PSD for sinusoids to offer the fit");
  app.add_option("--sinusoid-hz", r.sinusoid_hz, "offer the fit a sinusoid at this frequency in Hz (repeatable, up to 2)")
      ->option_text("F");
  app.add_option(
         "--threads", t.threads,
         "threads summing the taus of counts at --stride-factor full and of --taus all, and (up to 2) the total and Theo "
         "family's taus and TheoBR's bias ratio; from 2, the PSD beside the analysis; the same results on any number "
         "(default: one per core)")
      ->check(CLI::Range(1u, 1024u));
  app.add_option("--limits", r.limits_path, "acceptance limits: a verdict per limit (see below)")->option_text("FILE");
  app.add_option("--summary", r.summary_path, "with --limits: append the file's production summary row to FILE.csv")
      ->option_text("FILE.csv");
  app.add_option("--report", r.report_path, "write a self-contained HTML report (plots, tables, fit, verdicts)")
      ->option_text("FILE.html");
  app.add_flag("--progress", t.progress,
               "show progress on stderr: the file read, the taus summed, then each total-family statistic's taus "
               "(TheoH's bias ratio apart) (default: when stderr is a terminal)");
}

// No output may overwrite an input or another output (output_paths.hpp).
void check_output_paths(const Request& r) {
  std::vector<NamedPath> outputs = plot_outputs("--plot", r.plot_prefix);
  outputs.insert(outputs.begin(), {"--kalibr", r.kalibr_path});
  outputs.insert(outputs.begin(), {"--psd", r.psd_path});
  outputs.push_back({"--summary", r.summary_path});
  outputs.push_back({"--report", r.report_path});
  if (!r.report_path.empty()) outputs.push_back({"--report", r.report_path + ".part"});
  if (const auto conflict = output_conflict({{"file", r.path}, {"--limits", r.limits_path}}, outputs))
    bad(conflict->what, conflict->why);
}

std::string quoted_command(int argc, const char* const* argv) {
  std::string command;
  for (int i = 0; i < argc; ++i) {
    const std::string_view arg = argv[i];
    if (i) command += ' ';
    const bool quote = arg.find_first_of(" '\"") != std::string_view::npos;
    if (quote) command += '\'';
    command += arg;
    if (quote) command += '\'';
  }
  return command;
}

std::vector<DevStat> parse_stats(const std::string& text) {
  std::vector<DevStat> stats;
  std::stringstream ss(text);
  for (std::string item; std::getline(ss, item, ',');) {
    const auto s = parse_dev_stat(item);
    if (!s) bad("--stats", "unknown statistic '" + item + "' (" + dev_stat_names(", ") + ")");
    if (std::find(stats.begin(), stats.end(), *s) != stats.end()) bad("--stats", "'" + item + "' is asked twice");
    stats.push_back(*s);
  }
  if (stats.empty()) bad("--stats", "empty list");
  return stats;
}

// A power of two in [2, max] or `word` (returned as 0) for option `what`; bad() with `accepted`.
std::uint32_t parse_power_of_two(const std::string& text, const char* word, std::uint32_t max, const char* what,
                                 const char* accepted) {
  if (text == word) return 0;
  std::uint32_t v = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (ec != std::errc() || end != text.data() + text.size() || v < 2 || !std::has_single_bit(v) || v > max)
    bad(what, accepted);
  return v;
}

// The engine's options of the data and its statistics: type, tau0, confidence, stats, stride
// factors, alpha. In the order they are checked.
void check_engine_options(const OptionText& t, const CLI::App& app, Request& r) {
  AnalysisOptions& o = r.options;
  o.theo_decimated = t.theo_decimated;
  o.total_decimated = t.total_decimated;
  if (t.type == "phase") o.type = DataType::phase;
  else if (t.type == "freq") o.type = DataType::freq;
  else if (t.type == "counts") o.type = DataType::counts;
  else bad("--type", "must be phase, freq or counts, not '" + t.type + "'");
  if (!(t.tau0_s > 0) || !std::isfinite(t.tau0_s)) bad("--tau0", "must be a positive number of seconds");
  o.tau0_s = t.tau0_s;
  if (app.count("--column") && r.column == 0) bad("--column", "columns are numbered from 1");
  if (!(t.confidence > 0 && t.confidence < 1)) bad("--confidence", "must be between 0 and 1");
  o.confidence = t.confidence;
  o.stats = parse_stats(t.stats);
  const std::optional<StrideFactor> stride = StrideFactor::parse(t.stride);
  if (!stride) bad("--stride-factor", std::string("must be ") + StrideFactor::accepted);
  r.stride = *stride;
  o.total_stride_factor = parse_power_of_two(t.total_stride, "exact", 1u << 20, "--total-stride-factor",
                                             "must be a power of two from 2 to 2^20, or exact");
  if (t.alpha != "auto") {
    int a = 0;
    const auto [end, ec] = std::from_chars(t.alpha.data(), t.alpha.data() + t.alpha.size(), a);
    if (ec != std::errc() || end != t.alpha.data() + t.alpha.size() || a < -4 || a > 2)
      bad("--alpha", "must be auto or an integer from -4 to 2");
    o.alpha = a;
  }
  o.threads = t.threads;
}

// --format, --plot, --fit, --kalibr, --fit-long-tau.
void check_output_options(const OptionText& t, Request& r) {
  if (t.format == "table") r.format = OutputFormat::table;
  else if (t.format == "csv") r.format = OutputFormat::csv;
  else if (t.format == "json") r.format = OutputFormat::json;
  else if (t.format == "stable32") r.format = OutputFormat::stable32;
  else bad("--format", "must be table, csv, json or stable32");
  if (!r.plot_prefix.empty()) {
    if (const std::string missing = plot_devices_missing(); !missing.empty()) bad("--plot", missing);
  }
  if (!t.fit.empty() && t.fit != "ieee952") bad("--fit", "the only model is ieee952");
  r.fit = !t.fit.empty();
  if (!r.kalibr_path.empty() && !r.fit) bad("--kalibr", "needs --fit ieee952 (the file holds fitted terms)");
  if (t.long_tau == "totdev") r.long_tau = LongTau::totdev;
  else if (t.long_tau == "theoh") r.long_tau = LongTau::theoh;
  else if (t.long_tau != "oadev") bad("--fit-long-tau", "must be oadev, totdev or theoh, not '" + t.long_tau + "'");
  if (r.long_tau != LongTau::oadev && !r.fit) bad("--fit-long-tau", "only applies with --fit ieee952");
  r.options.keep_record = r.long_tau != LongTau::oadev;
}

// Acceptance limits and the production summary: read and checked before any data.
void read_limits(Request& r) {
  if (!r.limits_path.empty()) {
    try {
      r.limits = read_limits_file(r.limits_path);
    } catch (const LimitsError& e) {
      bad("--limits", r.limits_path + ": " + e.what());
    }
    for (const Limit& l : r.limits)
      if (l.kind == Limit::Kind::term && !r.fit)
        bad("--limits",
            fmt::format("{}: line {}: {} is a fitted term: add --fit ieee952", r.limits_path, l.line, l.quantity()));
  }
  if (!r.summary_path.empty()) {
    if (r.limits.empty()) bad("--summary", "needs --limits (the row holds the verdicts)");
    std::string why;
    if (!summary_compatible(r.summary_path, r.limits, why)) bad("--summary", r.summary_path + ": " + why);
  }
}

void compute_too(std::vector<DevStat>& stats, DevStat st) {
  if (std::find(stats.begin(), stats.end(), st) == stats.end()) stats.push_back(st);
}

// Units: what the values are, and the output unit of gyro data (input_units.hpp).
void resolve_request_units(const OptionText& t, const CLI::App& app, Request& r) {
  try {
    UnitOptions uo;
    uo.type = r.options.type;
    uo.unit = t.value_unit;
    uo.pulse_weight = t.pulse_weight;
    uo.pulse_unit = t.pulse_unit;
    uo.pulse_unit_given = app.count("--pulse-unit") > 0;
    if (app.count("--nominal-hz")) uo.nominal_hz = t.nominal_hz;
    uo.rate_unit = t.rate;
    uo.rate_unit_given = app.count("--rate-unit") > 0;
    r.units = resolve_units(uo);
  } catch (const UnitError& e) {
    bad(e.option(), e.what());
  }
  r.nominal_hz = t.nominal_hz;
  if (!r.kalibr_path.empty() && !r.units.gyro) bad("--kalibr", "needs gyro data: counts, or --unit with an angle or a rate");
  if (!r.limits.empty() && !r.units.gyro)
    bad("--limits", "limits are in gyro units: needs gyro data (counts, or --unit with an angle or a rate)");
}

// The longest window or step of --dynamic, in values: longer than any file (10^15 values are
// petabytes of text), and exact as an integer in a double.
constexpr double max_dynamic_values = 1e15;

// --dynamic WINDOW[,STEP] in seconds, as values of tau0.
DynamicSpec parse_dynamic(const std::string& text, double tau0_s) {
  std::vector<std::string> parts;
  std::stringstream ss(text);
  for (std::string item; std::getline(ss, item, ',');) parts.push_back(item);
  double window_s = 0, step_s = 0;
  const auto seconds = [](const std::string& t, double& v) {
    const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
    return ec == std::errc() && end == t.data() + t.size() && v > 0 && std::isfinite(v);
  };
  if (parts.empty() || parts.size() > 2 || !seconds(parts[0], window_s) || (parts.size() == 2 && !seconds(parts[1], step_s)))
    bad("--dynamic", "'" + text + "' is not WINDOW or WINDOW,STEP in positive seconds");
  if (parts.size() == 1) step_s = window_s;
  const double window_values = std::round(window_s / tau0_s), step_values = std::round(step_s / tau0_s);
  if (window_values < 4)
    bad("--dynamic",
        fmt::format("a window of {} s holds {} values of tau0: at least 4 are needed", window_s, window_values));
  if (step_values < 1) bad("--dynamic", fmt::format("a step of {} s is shorter than tau0", step_s));
  for (const auto& [what, seconds_asked, values] :
       {std::tuple{"window", window_s, window_values}, std::tuple{"step", step_s, step_values}})
    if (values > max_dynamic_values)
      bad("--dynamic", fmt::format("a {} of {:g} s is {:g} values of tau0 = {:g} s, more than the {:g} a window or step "
                                   "may span",
                                   what, seconds_asked, values, tau0_s, max_dynamic_values));
  return {static_cast<std::uint64_t>(window_values), static_cast<std::uint64_t>(step_values)};
}

// The PSD, the sinusoids offered to the fit, and what --dynamic excludes.
void check_spectrum_and_dynamic(const OptionText& t, Request& r) {
  const double tau0_s = r.options.tau0_s;
  if (r.psd_segment != 0 && (r.psd_segment < 8 || r.psd_segment % 2 != 0))
    bad("--psd-segment", "must be even and at least 8");
  if (r.sinusoid_hz.size() > max_sinusoids) bad("--sinusoid-hz", fmt::format("at most {} frequencies", max_sinusoids));
  for (const double f : r.sinusoid_hz)
    if (!(f > 0 && f < 0.5 / tau0_s))
      bad("--sinusoid-hz", fmt::format("{} Hz is not between 0 and the Nyquist frequency {} Hz", f, 0.5 / tau0_s));
  if (!r.sinusoid_hz.empty() && !r.fit) bad("--sinusoid-hz", "offers sinusoids to --fit ieee952");
  r.sinusoid_search = !t.no_sinusoid_search;
  // The PSD: asked for (--psd, the static --plot) or searched for sinusoids to offer the fit.
  r.want_psd = !r.psd_path.empty() || (!r.plot_prefix.empty() && t.dynamic.empty()) || (r.fit && r.sinusoid_search);
  if (!r.plot_prefix.empty() && t.dynamic.empty())  // the static plot draws ADEV and MDEV
    for (const DevStat st : {DevStat::oadev, DevStat::mdev}) compute_too(r.options.stats, st);
  if (t.dynamic.empty()) return;
  if (r.fit) bad("--fit", "fits the whole run's curves: not with --dynamic");
  if (!r.limits.empty() || !r.report_path.empty())
    bad(r.limits.empty() ? "--report" : "--limits", "is about the whole run: not with --dynamic");
  if (!r.psd_path.empty() || r.psd_segment != 0) bad("--psd", "the PSD is of the whole run: not with --dynamic");
  r.dynamic = parse_dynamic(t.dynamic, tau0_s);
}

}  // namespace

std::optional<int> parse_request(int argc, const char* const* argv, Request& r) {
  CLI::App app{
      "gyrochar-analyze: ADEV, OADEV, MDEV, TDEV, HDEV, OHDEV (streamed, any length) and TOTDEV,\n"
      "MTOTDEV, TTOTDEV, HTOTDEV, Theo1, TheoH (held in memory) of a recorded file, with EDF,\n"
      "confidence intervals, noise identification and the IEEE-952 gyro fit.",
      "gyrochar-analyze"};
  app.footer(std::string(footer) + exit_code::help +
             "\nWith --limits: 5 a limit is undecided (none failed); 6 a limit failed (the analysis is written).");
  OptionText t;
  add_options(app, t, r);
  if (const auto code = parse_command_line(app, argc, argv, analyze_program)) return code;
  check_output_paths(r);
  r.command = quoted_command(argc, argv);
  check_engine_options(t, app, r);
  check_output_options(t, r);
  read_limits(r);
  // The fit uses both curves, whatever the table shows: compute them, show what was asked.
  r.shown = r.options.stats;
  for (const Limit& l : r.limits)  // limited deviations are computed, shown or not
    if (l.kind != Limit::Kind::term)
      compute_too(r.options.stats, l.kind == Limit::Kind::adev ? DevStat::oadev : DevStat::mdev);
  if (r.fit)
    for (const DevStat s : {DevStat::oadev, DevStat::mdev}) compute_too(r.options.stats, s);
  resolve_request_units(t, app, r);
  r.show_progress = t.progress || isatty(STDERR_FILENO);
  r.source = r.path == "-" ? "standard input" : r.path;
  check_spectrum_and_dynamic(t, r);
  r.taus = tau_rule(t.taus);
  if (r.taus == TauRule::list) {
    std::string why;
    r.listed = parse_tau_list(t.taus, why);
    if (r.listed.empty()) bad("--taus", why);
  }
  return std::nullopt;
}

}  // namespace gyrochar
