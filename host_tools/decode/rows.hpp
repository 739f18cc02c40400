#pragma once
// What gyrochar-decode records of a node: one row per tau per closed report, built from the
// Decoder's view of the node and its slot table of that report (which values arrived in it: a
// value the report lost is "missing", never the previous report's); and what it counts of its
// input; and the rows of each window of a node's dynamic Allan deviation. The recording formats
// (recording.hpp) and the view (view.hpp) show these.
#include <array>
#include <bitset>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "confidence.hpp"
#include "decoder.hpp"
#include "display_units.hpp"

namespace gyrochar::decoding {

/// The true IEEE-952 parameters of a node's gyro, where known (a simulation's), in SI: Q rad,
/// N rad/sqrt(s), B rad/s, K rad/s/sqrt(s), R rad/s^2, and the terms beyond them. Shown beside the
/// node's fit; never for a node reporting pulses (no angle to convert to).
struct TrueTerms {
  std::array<double, 5> qnbkr{};
  std::vector<std::array<double, 2>> markov;     // {sigma rad/s, Tc s} of each Gauss-Markov rate
  std::vector<std::array<double, 2>> sinusoids;  // {amplitude rad/s, frequency Hz} of each sinusoid
};
using TrueTermsByNode = std::map<std::uint8_t, TrueTerms>;

/// The tau below which the node's fit left out the AVAR (k = 0) or MVAR (k = 1) points (periodic
/// quantization): tau0 2^c, in s; 0 when none were; nullopt while the summary or tau0 is unknown.
/// O(1).
std::optional<double> fit_excluded_below_tau_s(const NodeView& node, std::size_t k);

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

/// How the views (the table, the plot) show one of tau i's ADEV and MDEV. A tau's row shows the
/// values of one report, never two: the node's latest report once one of the row's values arrived
/// in it, else (that report still being received) the report before. A value that is not from the
/// row's report is not shown: `missing` (its frame was lost, as the CSV says) or, while the row's
/// report is still being received, `pending`. `shown` includes a value never received (nothing
/// to show yet). O(1).
enum class Viewed : std::uint8_t { shown, missing, pending };
struct ViewedRow {
  Viewed adev = Viewed::shown, mdev = Viewed::shown;
};
ViewedRow viewed_row(const NodeView& node, std::size_t i);
const char* name(Viewed v);

/// The node's selected model beyond the five terms (protocol version 4) as the views and
/// recordings show it: the model pages of the slow cycle that carried the fit summary shown, so
/// that its terms and the five are one fit's. `shown` once the model page and every page of a term
/// it holds arrived; `pending` while that cycle is still being received; `missing` when it ended
/// without them (a page was lost): then no value is shown. Sigma and amplitudes in the display rate
/// unit (Units::rate), times in s, frequencies in Hz.
struct FitModelRow {
  Viewed state = Viewed::pending;
  std::uint8_t markov = 0, sinusoids = 0;  // terms in the model (shown only)
  bool bandwidth = false;
  std::optional<double> bandwidth_excluded_below_tau_s;  // 0: none; nullopt while tau0 is unknown
  struct Parameter {
    bool known = false;  // shown, and a term of the model
    double value = 0, rel_uncertainty = 0;
    bool resolved = false;
  };
  std::array<Parameter, protocol::fit_parameter_pages> parameters{};  // protocol::fit_parameter_slot order
  std::optional<protocol::Ieee952ModelMsg> runner_up;                 // the model page, when it names a runner-up
};
/// Empty for a node that follows a schedule before version 4 or whose summary has not arrived.
/// O(1).
std::optional<FitModelRow> fit_model_row(const NodeView& node, const Units& units);

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
  std::optional<FitModelRow> fit_model;  // the fit's model beyond the five terms (version 4)
};

/// The rows of the report of `node` that has just closed (one per tau of its TauCount), from the
/// Decoder's view and `report`, the Decoder's slot table of that report. Appends to `out` (reuse
/// it to avoid allocating). O(TauCount).
void tau_rows(const NodeView& node, const Decoder::Report& report, const Units& units, ConfidenceIntervals& intervals,
              std::vector<TauRow>& out);

/// One window tau of one window of the node's dynamic Allan deviation (protocol version 3), in
/// display units, written once, when the window's last frame arrives. No interval travels with a
/// window curve (docs/protocol.md 2.5).
struct WindowRow {
  double time_s = 0.0;  // time of the frame that completed the window
  std::uint8_t node = 0;
  std::uint32_t session = 0;
  std::uint8_t seq = 0;  // the report that carried that frame
  std::uint32_t window = 0;
  std::uint64_t length = 0;           // samples per window, 0 while unknown
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

/// What came in.
struct InputCounters {
  std::string source;                 // what is decoded: a log's path, "stdin", an interface
  std::uint64_t lines = 0;            // log lines read (a live interface has none)
  std::uint64_t malformed_lines = 0;  // lines that are not candump log lines (skipped)
  std::uint64_t frames = 0;           // frames given to the decoder
  std::uint64_t remote_frames = 0;    // remote requests (RTR) in a log: no data, not decoded
  std::uint64_t time_backwards = 0;   // timestamps earlier than the latest (decoded at the latest)
  bool started = false;               // a frame has arrived
  double first_s = 0.0, now_s = 0.0;  // time of the first frame and the latest time
  std::string bus;                    // live interface: bus state and socket counters; else empty
};

/// Nodes to show and record (by address); all by default.
using NodeFilter = std::bitset<256>;

}  // namespace gyrochar::decoding
