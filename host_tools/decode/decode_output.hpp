#pragma once
// What gyrochar-decode makes of the Decoder's node views: display units, confidence intervals, one
// row per tau per closed report, and the formats built from them: CSV and JSON lines for recording
// (columns in host_tools/decode/README.md), a text table for the terminal, and the series of the
// ADEV/MDEV plot with the IEEE-952 model lines. The node's IEEE-952 fit is shown with its summary
// (protocol version 2: status, chi2/dof, points, quantization); where a gyro's true parameters are
// known (a simulation), they are shown beside the fit.
//
// Units. Deviations arrive in the node's angle unit A per second (metadata AngleUnit). They are
// shown in the chosen rate unit, the IEEE-952 terms in gyro units (Q arcsec, N deg/sqrt(h), B deg/h,
// K deg/h/sqrt(h), R deg/h/h). Nothing is converted from pulses: a node reporting pulses is shown in
// pulse/s and pulse units; with RateUnit::native every node is shown in its own unit. Before a
// node's AngleUnit has arrived its values are shown as sent and the unit is "unknown".
#include <fmt/format.h>

#include <array>
#include <bitset>
#include <cstdint>
#include <cstdio>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "confidence.hpp"
#include "decoder.hpp"
#include "heat_map.hpp"

namespace gyrochar::decoding {

// ---------------------------------------------------------------------------------------------
// Units

enum class RateUnit : std::uint8_t { deg_per_h, deg_per_s, rad_per_s, native };

/// "deg/h", "deg/s", "rad/s" or "native"; nullopt for anything else. O(1), no allocation.
std::optional<RateUnit> parse_rate_unit(std::string_view text);

/// How the values of one node are shown: displayed value = wire value x factor.
struct Units {
  bool known = false;                                   // the node's AngleUnit has arrived
  bool pulses = false;                                  // the node reports pulses: never converted
  std::string rate_name;                                // "deg/h", "pulse/s", "arcsec/s" (native), "unknown"
  double rate = 1.0;                                    // display rate per (A/s)
  std::array<std::string, 5> ieee_name;                 // units of Q, N, B, K, R
  std::array<double, 5> ieee{1.0, 1.0, 1.0, 1.0, 1.0};  // display value per wire value
};

/// The units of `node` for the rate unit `choice`. O(1); allocates the unit names.
Units units_for(const NodeView& node, RateUnit choice);

// ---------------------------------------------------------------------------------------------
// The IEEE-952 fit

/// The true IEEE-952 parameters of a node's gyro, where known (a simulation's), in SI: Q rad,
/// N rad/sqrt(s), B rad/s, K rad/s/sqrt(s), R rad/s^2. Shown beside the node's fit; never for a
/// node reporting pulses (no angle to convert to).
using TrueTerms = std::array<double, 5>;
using TrueTermsByNode = std::map<std::uint8_t, TrueTerms>;

/// The tau below which the node's fit left out the AVAR (k = 0) or MVAR (k = 1) points (periodic
/// quantization): tau0 2^c, in s; 0 when none were; nullopt while the summary or tau0 is unknown.
/// O(1).
std::optional<double> fit_excluded_below_tau_s(const NodeView& node, std::size_t k);

// ---------------------------------------------------------------------------------------------
// Confidence intervals

/// Confidence intervals from the EDF (confidence.hpp, Boost.Math chi-squared), memoized per EDF:
/// the interval is proportional to the deviation and the wire carries at most 4095 distinct EDFs,
/// so the quantiles are computed once per distinct EDF, then looked up in O(1).
class ConfidenceIntervals {
 public:
  /// `confidence` in (0, 1), e.g. 0.683.
  explicit ConfidenceIntervals(double confidence) : confidence_(confidence) {}
  /// The interval of deviation `dev` (any unit) with `edf` degrees of freedom; invalid when edf <= 0.
  /// Allocates a table entry at the first meeting of an EDF; never throws.
  Interval operator()(double dev, double edf);
  double confidence() const { return confidence_; }

 private:
  double confidence_;
  std::unordered_map<double, Interval> unit_intervals_;  // by edf, for dev = 1
};

// ---------------------------------------------------------------------------------------------
// Which values arrived in which report

/// Follows, per node, which ADEV and MDEV frames of the report being received arrived and when the
/// report began. The Decoder's view keeps the latest value of every tau, which is the previous
/// report's when this report's frame was lost; this tracker tells the two apart.
class ReportTracker {
 public:
  struct Report {
    bool open = false;
    std::uint8_t seq = 0;
    double start_s = 0.0;                                 // time of the report's first frame
    std::array<bool, protocol::max_taus> adev{}, mdev{};  // received in this report
  };
  /// Call after Decoder::feed() with the same frame and time. Decodes the frame again with the
  /// codec (the Decoder's slot table is private). O(1), no allocation.
  void note(const CanFrame& frame, double t_s);
  /// Call at DecoderEvent::report_closed and restart: the node's next frame opens a new report.
  void close(std::uint8_t node) { reports_[node].open = false; }
  /// The node's current (or just closed) report.
  const Report& report(std::uint8_t node) const { return reports_[node]; }

 private:
  std::array<Report, 256> reports_{};
};

// ---------------------------------------------------------------------------------------------
// Rows

/// One deviation of one tau in one closed report, in display units.
struct DevCell {
  enum class Status : std::uint8_t {
    ok,       // received in this report, Valid = 1
    invalid,  // received, Valid = 0: no estimate (do not use)
    missing,  // this report's frame was lost: no value
  };
  Status status = Status::missing;
  double value = 0.0;  // display rate unit (status ok only)
  Interval ci;         // display rate unit; invalid when the EDF is not available
  double edf = 0.0;    // 0: not available
  protocol::NoiseType noise = protocol::NoiseType::not_identified;
};
const char* name(DevCell::Status s);

struct TauRow {
  double time_s = 0.0;  // time of the report's first frame (log timestamp or clock)
  std::uint8_t node = 0;
  std::uint32_t session = 0;  // +1 at every restart the decoder detected
  std::uint8_t seq = 0;
  std::uint8_t tau_index = 0;
  std::uint64_t m = 0;  // 0 while unknown (slow cycle)
  double tau_s = 0.0;   // 0 while unknown
  std::uint64_t n = 0;  // latest AVAR term count received (slow cycle, every 4 reports); 0 unknown
  DevCell adev, mdev;
  // The node's latest IEEE-952 fit summary (empty: a version-1 node, or not received yet) and the
  // taus below which it left points out (fit_excluded_below_tau_s()).
  std::optional<protocol::Ieee952SummaryMsg> fit;
  std::array<std::optional<double>, 2> fit_excluded_below_tau_s{};
};

/// The rows of the report of `node` that has just closed (one per tau of its TauCount), from the
/// Decoder's view and the tracker's record of what arrived. Appends to `out` (reuse it to avoid
/// allocating). O(TauCount).
void tau_rows(const NodeView& node, const ReportTracker::Report& report, const Units& units,
              ConfidenceIntervals& intervals, std::vector<TauRow>& out);

/// One window tau of one window of the node's dynamic Allan deviation (protocol version 3), in
/// display units, written once, when the window's last frame arrives. No interval travels with a
/// window curve (docs/protocol.md 2.5).
struct WindowRow {
  double time_s = 0.0;  // time of the frame that completed the window
  std::uint8_t node = 0;
  std::uint32_t session = 0;
  std::uint8_t seq = 0;  // the report that carried that frame
  std::uint32_t window = 0;
  std::uint64_t length = 0;          // samples per window, 0 while unknown
  double start_s = 0.0, end_s = 0.0;  // the window in the node's run: k L tau0, (k+1) L tau0; 0, 0
                                      // while tau0 or L is unknown
  std::uint32_t gaps = 0;
  std::uint8_t tau_index = 0;
  std::uint64_t m = 0;  // 0 while unknown
  double tau_s = 0.0;   // 0 while unknown
  DevCell adev, mdev;   // ok or invalid (the node had no estimate), without interval
};

/// The window's rows of `node` (one per window tau), at time `time_s`. Appends to `out`.
/// O(window taus).
void window_rows(const NodeView& node, const WindowView& window, double time_s, std::uint8_t seq, const Units& units,
                 std::vector<WindowRow>& out);

// ---------------------------------------------------------------------------------------------
// What came in

struct InputCounters {
  std::string source;                 // what is decoded: a log's path, "stdin", an interface
  std::uint64_t lines = 0;            // log lines read (a live interface has none)
  std::uint64_t malformed_lines = 0;  // lines that are not candump log lines (skipped)
  std::uint64_t frames = 0;           // frames given to the decoder
  std::uint64_t time_backwards = 0;   // timestamps earlier than the latest (decoded at the latest)
  bool started = false;               // a frame has arrived
  double first_s = 0.0, now_s = 0.0;  // time of the first frame and the latest time
  std::string bus;                    // live interface: bus state and socket counters; else empty
};

/// Nodes to show and record (by address); all by default.
using NodeFilter = std::bitset<256>;

// ---------------------------------------------------------------------------------------------
// Recording formats. The writers write to a FILE* they do not own; the caller checks ferror().
// Each call writes whole lines; O(size of the line); no allocation once the line buffer has grown
// (the JSON report, event and summary records are built with nlohmann::json and do allocate).

/// CSV, one row per tau per closed report, header first. Empty fields for unknown values. The
/// window rows of the dynamic Allan deviation share the columns and fill the window_ ones; the
/// column `type` tells them apart (tau, window).
class CsvWriter {
 public:
  /// Writes the header. `confidence` is the level of the intervals (column ci_level).
  CsvWriter(std::FILE* out, double confidence);
  void row(const TauRow& r, const Units& units);
  void row(const WindowRow& r, const Units& units);

 private:
  template <class T>
  void field(bool known, T value);  // the value (or nothing) and a comma
  void begin(double time_s, std::uint8_t node, std::uint8_t seq, std::uint8_t tau_index, std::uint64_t m, double tau_s);
  std::FILE* out_;
  double confidence_;
  fmt::memory_buffer line_;
};

/// JSON lines, one object per line, told apart by "type": "tau" (the CSV row but its fit_ columns),
/// "window" (a window row), "report" (one per closed report: status, node faults, link health,
/// metadata, IEEE-952 terms and the fit's summary), "event" (restart, offline, online, duplicate)
/// and "summary" (once, at the end: input counters and every node's link health).
class JsonlWriter {
 public:
  /// `confidence` is the level of the intervals ("ci_level").
  JsonlWriter(std::FILE* out, double confidence) : out_(out), confidence_(confidence) {}
  void row(const TauRow& r, const Units& units);
  void row(const WindowRow& r, const Units& units);
  void report(double time_s, const NodeView& node, std::uint8_t seq, const Units& units);
  void event(double time_s, DecoderEvent e, const NodeView& node);
  void summary(const Decoder& decoder, const InputCounters& input, const NodeFilter& shown);

 private:
  template <class T>
  void member(const char* key, bool known, T value);  // ,"key":value (or null) into line_
  void line(const std::string& text);
  std::FILE* out_;
  double confidence_;
  fmt::memory_buffer line_;
};

// ---------------------------------------------------------------------------------------------
// For people

/// The terminal view: input counters, then per shown node its state, metadata, link health, node
/// faults, the tau table (tau, ADEV and MDEV with confidence intervals, n, EDF, noise) and the
/// IEEE-952 fit (its summary, and each term: value and uncertainty, whether resolved; with `truth`,
/// the true value of the nodes it names beside). Plain text, no terminal control codes.
/// O(nodes x taus).
std::string format_view(const Decoder& decoder, const InputCounters& input, const NodeFilter& shown, RateUnit rate_unit,
                        ConfidenceIntervals& intervals, const TrueTermsByNode* truth = nullptr);

/// The end-of-run summary for stderr: one line for the input, one per node with its link health.
/// Each line starts with "gyrochar-decode: ".
std::string format_summary(const Decoder& decoder, const InputCounters& input, const NodeFilter& shown);

// ---------------------------------------------------------------------------------------------
// The plot's series, in display units (host_tools/decode/plot.cpp draws them)

struct PlotPoint {
  double tau_s = 0.0, dev = 0.0;
  Interval ci;  // invalid: no error bar
};
struct PlotLine {
  std::optional<protocol::Ieee952Term> term;  // the term drawn; empty: the model's sum
  std::string label;                          // e.g. "N 0.00212 deg/sqrt(h) (±13%)" (UTF-8)
  std::vector<double> tau_s, dev;             // log-spaced over the plot's tau range
};
struct ReadOffPoint {
  double tau_s = 0.0, dev = 0.0;
  std::string label;  // e.g. "N at 1 s"
};
struct NodePlot {
  std::string title;                  // "node 0x10, session 0"
  std::string rate_name;              // unit of every deviation
  std::vector<PlotPoint> adev, mdev;  // valid values with a known tau
  std::vector<PlotLine> terms;        // resolved IEEE-952 terms, then the fitted model ("sum")
  std::optional<PlotLine> truth;      // the true model (simulation), drawn dashed beside the fit
  std::vector<std::string> notes;     // legend lines without a symbol: the fit rejected, short taus
                                      // left out (quantization not white), no fit
  std::vector<ReadOffPoint> read_offs;
  double tau_min_s = 0.0, tau_max_s = 0.0;  // the tau axis: the points' range widened by 2 on each
                                            // side (0, 0 when there are no points)
  std::optional<HeatMap> dynamic;           // the window curves' ADEV (protocol version 3): a node
                                            // with window taus has one, empty until a window comes
};

/// The plot of one node. Each resolved IEEE-952 term is drawn as the ADEV of its own AVAR term
/// (design brief section 3): Q sqrt(3)/tau, N/sqrt(tau), sqrt(2 ln2/pi) B, K sqrt(tau/3),
/// R tau/sqrt(2), and read off where the term equals its parameter: Q at tau = sqrt(3) s, N at 1 s,
/// K at 3 s, R at sqrt(2) s, and B as the floor 0.664 B at the minimum of the model's sum within
/// the points' taus. The sum is the fitted model: every fitted term, resolved or not, and Q at
/// pulse weight / sqrt(12) where the node held it there (quantization not white). A fit the node
/// rejected, or could not make, draws no model line and says so in `notes`. With `truth` (SI), its
/// model is drawn too (`truth`, the same closed form). Lines span the tau axis; read-off points
/// outside it are left out. A node with window taus also gets the heat map of its windows' ADEV
/// (`dynamic`: one column per window, placed at its samples times tau0). O(taus + line points +
/// windows x window taus); allocates.
NodePlot plot_data(const NodeView& node, RateUnit rate_unit, ConfidenceIntervals& intervals,
                   const TrueTerms* truth = nullptr);

}  // namespace gyrochar::decoding
