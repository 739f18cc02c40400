#pragma once
// The host side of the gyrochar CAN protocol: follows every node on a bus, assembles their reports
// and applies the loss, restart and offline rules of docs/protocol.md section 5. Frames come from
// anywhere (a live socket, a candump log, a test); time is passed in, never read from a clock.
// Nothing is papered over: every lost frame, lost report, restart, silent node, duplicate and
// rejected frame is counted and, where it happens, reported as an event. Each node's window curves
// (the dynamic Allan deviation, protocol version 3) are kept, one per window, for the heat map.
#include <algorithm>
#include <array>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "gyrochar/wire/can_frame.hpp"
#include "gyrochar/wire/protocol.hpp"

namespace gyrochar {

/// The latest values of one tau of one node.
struct TauView {
  std::uint64_t m = 0;  // averaging factor, 0 while unknown (tau info not yet received)
  std::uint8_t stride_log2 = 0;
  std::uint64_t n = 0;  // overlapping Allan terms (slow cycle), 0 while unknown
  struct Dev {
    bool received = false;  // a value arrived in this session
    float dev = 0.0f;       // angle unit / s
    double edf = 0.0;       // 0: not available
    protocol::NoiseType noise = protocol::NoiseType::not_identified;
    bool valid = false;
    std::uint64_t report = 0;  // NodeView::report of the report it arrived in
  };
  Dev adev, mdev;
};

/// One IEEE-952 term of the node's latest fit.
struct Ieee952View {
  bool received = false;
  bool resolved = false;  // significant and dominating somewhere, in an accepted fit
  float value = 0.0f;     // in the term's unit (protocol::Ieee952Term); 0 unless fitted
  double rel_uncertainty = 0.0;
  bool fitted = false;      // in the fitted model: value and uncertainty are the fit's even when
                            // not resolved (an upper-bound reading). A version-1 node sends no
                            // Fitted flag: there it is the Resolved flag.
  std::uint64_t cycle = 0;  // NodeView::cycle() of the report that carried it
  /// In the node's model: received and fitted (a version-1 node: resolved).
  bool in_model() const { return received && (fitted || resolved); }
};

/// One IEEE-952 term's unconstrained estimate (protocol version 5) and the slow cycle it came in.
/// The node takes its fit at the first report of a cycle, so it belongs with the term frame of the
/// same cycle.
struct UnconstrainedView {
  std::uint64_t cycle = 0;  // NodeView::cycle() of the report that carried it; 0: none
  protocol::Ieee952UnconstrainedMsg msg;
};

/// The selected model of the node's fit beyond the five terms (protocol version 4): the model page
/// and the parameter pages received in one slow cycle. The node takes its fit at the first report
/// of a cycle, so every Ieee952 frame of one cycle describes the same fit.
struct FitModelView {
  std::uint64_t cycle = 0;  // NodeView::cycle() of the slow cycle the pages came in; 0: none
  std::optional<protocol::Ieee952ModelMsg> model;
  std::array<std::optional<protocol::Ieee952ParameterMsg>, protocol::fit_parameter_pages> parameters{};
  /// Parameter page k belongs to the model: a term the model page says it holds (false until the
  /// model page has arrived).
  bool in_model(std::size_t k) const {
    if (!model) return false;
    const protocol::FitParameterSlot s = protocol::fit_parameter_slot(k);
    switch (s.parameter) {
      case protocol::FitParameter::markov_sigma:
      case protocol::FitParameter::markov_tc: return s.index < model->markov;
      case protocol::FitParameter::filter_tf: return model->bandwidth;
      case protocol::FitParameter::sinusoid_amplitude:
      case protocol::FitParameter::sinusoid_frequency: return s.index < model->sinusoids;
    }
    return false;
  }
  /// The model page and every parameter page of a term it holds arrived.
  bool complete() const {
    if (!model) return false;
    for (std::size_t k = 0; k < parameters.size(); ++k)
      if (in_model(k) && !parameters[k]) return false;
    return true;
  }
};

/// One window of the node's dynamic Allan deviation (protocol version 3): the window k covers the
/// node's samples k L .. (k+1) L - 1 (L = NodeView::window_length).
struct WindowView {
  std::uint32_t window = 0;        // k
  std::uint32_t gaps = 0;          // sample gaps inside it
  std::vector<double> adev, mdev;  // per window tau, angle unit / s; 0: no estimate or not received
  std::vector<bool> received;      // per window tau: its frame arrived
  bool complete() const { return !received.empty() && std::find(received.begin(), received.end(), false) == received.end(); }
};

/// Link health of one node: what went missing and what went wrong, since the decoder started.
struct LinkHealth {
  std::uint64_t frames = 0;                                   // frames accepted from this node
  std::uint64_t reports_complete = 0;                         // reports with every expected frame
  std::uint64_t reports_incomplete = 0;                       // reports closed with missing frames
  std::uint64_t reports_lost = 0;                             // whole reports never seen (Seq gaps)
  std::uint64_t frames_missing = 0;                           // expected slots not received in closed reports
  std::uint64_t restarts = 0;                                 // Seq/SampleCount/Uptime backwards, config or tau count change
  std::uint64_t offline_events = 0;                           // silences of 3 s or more
  std::uint64_t duplicates = 0;                               // a slot received twice in one report: address conflict
  std::uint64_t not_decoded = 0;                              // frames of a protocol version this decoder does not know
  std::uint64_t window_frames_unplaced = 0;                   // window tau frames whose window page was not received
  std::map<protocol::ProtocolError, std::uint64_t> rejected;  // frames decode() refused
};

struct NodeView {
  std::uint8_t address = 0;
  bool online = false;
  double last_frame_s = 0.0;
  std::uint32_t session = 0;  // +1 at every restart detected
  /// The node's latest report of this session: its number (1 for the first, 0 before any) and
  /// whether it is still being received. TauView::Dev::report says which report a value is from.
  std::uint64_t report = 0;
  bool report_open = false;
  /// Reports the node made in this session up to its latest, lost ones included, counted from its
  /// first Seq: a multiple of slow_cycle_reports at the first report of each slow cycle.
  std::uint64_t reports_made = 0;
  /// The slow cycle of the latest report (1 for the cycle of the session's first report; 0 before
  /// any report).
  std::uint64_t cycle() const { return report == 0 ? 0 : reports_made / protocol::slow_cycle_reports + 1; }
  // Latest status (fast cycle)
  bool have_status = false;
  protocol::StatusMsg status;
  protocol::StatusFaultsMsg faults;
  // Metadata (slow cycle)
  std::optional<protocol::MetaSamplingMsg> sampling;
  std::optional<protocol::MetaClockMsg> clock;
  std::optional<protocol::MetaScaleMsg> scale;
  std::optional<protocol::MetaConfigMsg> config;
  std::array<TauView, protocol::max_taus> taus{};
  std::array<Ieee952View, 5> ieee952{};
  /// The fit's summary (protocol version 2, slow cycle); empty until received, and always for a
  /// version-1 node, which has none.
  std::optional<protocol::Ieee952SummaryMsg> ieee952_summary;
  std::uint64_t ieee952_summary_cycle = 0;  // cycle() of the report that carried the summary
  /// Each term's unconstrained estimate (protocol version 5) of the latest slow cycle that sent it,
  /// and of the cycle before (a term frame may come after the next cycle's first estimates).
  std::array<UnconstrainedView, 5> unconstrained{}, previous_unconstrained{};
  /// Term k's unconstrained estimate from the fit its term frame describes (the same slow cycle);
  /// null when none came (a node before version 5, or the frame was lost). Only an estimate with an
  /// uncertainty (the term was free in the fit) counts.
  const protocol::Ieee952UnconstrainedMsg* unconstrained_estimate(std::size_t k) const {
    const std::uint64_t c = ieee952[k].received ? ieee952[k].cycle : 0;
    for (const UnconstrainedView* u : {&unconstrained[k], &previous_unconstrained[k]})
      if (c != 0 && u->cycle == c && u->msg.uncertainty > 0) return &u->msg;
    return nullptr;
  }
  /// The fit's model pages (protocol version 4) of the latest slow cycle that sent one, and of the
  /// cycle before (the summary of a cycle may come after the next cycle's first model pages).
  FitModelView fit_model, previous_fit_model;
  // The dynamic Allan deviation (protocol version 3, slow cycle): 0 until the window pages arrive.
  std::uint8_t window_taus = 0;     // WindowTauCount; window tau i is tau i
  std::uint64_t window_length = 0;  // samples per window
  /// Every window received in this session, by number: the columns of the heat map. A window is
  /// added when a window page names it and filled as its window tau frames arrive.
  std::map<std::uint32_t, WindowView> windows;
  /// The latest window page: the window the frames of the current slow cycle describe (none while
  /// the node has no completed window); empty until one arrives in this session.
  std::optional<protocol::WindowMsg> window_page;
  /// The window the window tau frames now arriving belong to, if any.
  std::optional<std::uint32_t> current_window() const {
    return window_page && window_page->complete ? std::optional<std::uint32_t>(window_page->window) : std::nullopt;
  }
  LinkHealth health;
  /// Non-zero: the ProtocolVersion the node announced, newer than this decoder's; its frames are no
  /// longer decoded (counted in health.not_decoded) until it announces a known version again.
  std::uint8_t unknown_version = 0;

  /// The protocol version whose schedule the node follows: the clock page's; before it arrives 4
  /// once a model page came (from version 4), 3 once a window page came (from version 3), 2 once a
  /// summary page came (from version 2), else 1. An unconstrained estimate (version 5) says nothing
  /// here: it may come after parameter pages of its report that a version-1 layout did not count,
  /// which a version-5 layout would then call missing; it is used, not counted, until the clock page. A version-1 report then misses nothing, and a newer report opened before the
  /// clock page only leaves its newer frames uncounted.
  std::uint8_t schedule_version() const {
    return clock             ? clock->protocol_version
           : fit_model.model ? std::uint8_t{4}
           : window_taus     ? std::uint8_t{3}
           : ieee952_summary ? std::uint8_t{2}
                             : std::uint8_t{1};
  }

  /// tau in seconds of tau index i, 0 while tau0 or m is unknown.
  double tau_s(std::size_t i) const {
    return sampling && taus[i].m ? static_cast<double>(sampling->tau0_s) * static_cast<double>(taus[i].m) : 0.0;
  }
};

/// window_complete: the last window tau of `node.current_window()` arrived (once per window).
enum class DecoderEvent {
  report_closed,
  restart,
  offline,
  online,
  rejected_frame,
  duplicate,
  unknown_version,
  window_complete
};
/// "report_closed", "restart", ...: the enumerator's name. A static string.
const char* name(DecoderEvent e);

class Decoder {
 public:
  /// The report being received from a node: its sequence number, when its first frame came, and
  /// its slot table (which frames of the report's schedule arrived). Inside a report_closed
  /// listener, the report just closed.
  struct Report {
    bool open = false;
    bool seen = false;  // a report of this session was opened: `seq` is the last Seq heard, also after offline
    std::uint8_t seq = 0;
    double start_s = 0.0;           // time of the report's first frame
    std::uint8_t lost_at_open = 0;  // reports counted lost when the current report opened
    std::uint8_t tau_count = 0;
    std::uint8_t version = 1;         // the schedule's protocol version (NodeView::schedule_version())
    std::uint8_t window_taus = 0;     // the node's window taus (version 3), 0 while unknown
    std::array<bool, 512> arrived{};  // by slot position in the report
    std::array<std::int16_t, protocol::slot_kinds * protocol::max_taus>
        position{};  // (slot, index) -> position, -1: not in this report

    /// True when the frame of (slot, index) arrived in this report; false for a frame the report's
    /// schedule does not have. O(1).
    bool received(protocol::Slot slot, std::uint8_t index) const {
      const std::int16_t k = position[static_cast<std::size_t>(slot) * protocol::max_taus + index];
      return k >= 0 && arrived[static_cast<std::size_t>(k)];
    }
  };

  /// Called for every event; `node` is the view after the event (for report_closed: with the
  /// closed report's values, and report(node.address) its slot table). May be empty.
  using Listener = std::function<void(DecoderEvent, const NodeView& node, std::uint8_t seq)>;
  explicit Decoder(Listener listener = {}, double offline_after_s = 3.0)
      : listener_(std::move(listener)), offline_after_s_(offline_after_s) {}

  /// Feeds one frame received at time t_s (seconds, any epoch, non-decreasing). Frames that are not
  /// gyrochar report frames (counter input, other traffic) are ignored and counted in other_frames().
  void feed(const CanFrame& frame, double t_s);
  /// Advances time without a frame: nodes silent for offline_after_s become offline.
  void tick(double t_s);
  /// Closes every open report (end of a log).
  void flush();

  const std::map<std::uint8_t, NodeView>& nodes() const { return nodes_; }
  /// The report of `node` (see Report); nullptr for a node never heard. O(log nodes).
  const Report* report(std::uint8_t node) const {
    const auto it = assembly_.find(node);
    return it == assembly_.end() ? nullptr : &it->second;
  }
  std::uint64_t other_frames() const { return other_frames_; }
  std::uint64_t rejected_frames() const { return rejected_; }

 private:
  using Assembly = Report;
  static void layout(Assembly& a);
  static void relayout_if_schedule_changed(const NodeView& v, Assembly& a);

  void accept(NodeView& v, Assembly& a, const protocol::Message& message);
  void accept_window_dev(NodeView& v, Assembly& a, const protocol::WindowDevMsg& msg);
  /// The node's model pages of the current slow cycle (a new, empty one at its first page).
  static FitModelView& fit_model_of_cycle(NodeView& v);
  void open_report(NodeView& v, Assembly& a, std::uint8_t seq);
  void close_report(NodeView& v, Assembly& a);
  void restart(NodeView& v, Assembly& a);
  void mark_slot(NodeView& v, Assembly& a, protocol::Slot slot, std::uint8_t index);
  void emit(DecoderEvent e, const NodeView& v, std::uint8_t seq) {
    if (listener_) listener_(e, v, seq);
  }

  Listener listener_;
  double offline_after_s_;
  std::map<std::uint8_t, NodeView> nodes_;
  std::map<std::uint8_t, Assembly> assembly_;  // the report being received, per node
  double now_s_ = 0.0;                         // time of the frame being fed
  std::uint64_t other_frames_ = 0;
  std::uint64_t rejected_ = 0;
};

}  // namespace gyrochar
