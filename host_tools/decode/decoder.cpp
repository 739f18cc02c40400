#include "decoder.hpp"

#include <algorithm>
#include <type_traits>

namespace gyrochar {

using namespace protocol;

const char* name(DecoderEvent e) {
  switch (e) {
    case DecoderEvent::report_closed: return "report_closed";
    case DecoderEvent::restart: return "restart";
    case DecoderEvent::offline: return "offline";
    case DecoderEvent::online: return "online";
    case DecoderEvent::rejected_frame: return "rejected_frame";
    case DecoderEvent::duplicate: return "duplicate";
    case DecoderEvent::unknown_version: return "unknown_version";
    case DecoderEvent::window_complete: return "window_complete";
  }
  return "invalid";
}

void Decoder::feed(const CanFrame& frame, double t_s) {
  tick(t_s);
  now_s_ = t_s;
  const Decoded d = decode(frame);
  if (d.error == ProtocolError::unknown_id || d.error == ProtocolError::not_extended ||
      d.error == ProtocolError::error_frame || std::holds_alternative<CounterInputMsg>(d.message)) {
    ++other_frames_;  // not a report frame of this protocol: other traffic on the bus
    return;
  }
  NodeView& v = nodes_[d.node];
  v.address = d.node;
  Assembly& a = assembly_[d.node];
  if (!v.online) {
    v.online = true;
    emit(DecoderEvent::online, v, a.seq);
  }
  v.last_frame_s = t_s;
  if (const auto* clock = std::get_if<MetaClockMsg>(&d.message); clock && d.error == ProtocolError::none) {
    // docs/protocol.md 2.2: a version this decoder does not know stops the node's decoding (its
    // frames may mean something else); a known one announced again starts a new session.
    if (clock->protocol_version > protocol::version && v.unknown_version == 0) {
      close_report(v, a);
      v.unknown_version = clock->protocol_version;
      emit(DecoderEvent::unknown_version, v, a.seq);
    } else if (clock->protocol_version <= protocol::version && v.unknown_version != 0) {
      restart(v, a);
    }
  }
  if (v.unknown_version != 0) {
    ++v.health.not_decoded;
    return;
  }
  if (d.error != ProtocolError::none) {
    ++rejected_;
    ++v.health.rejected[d.error];
    emit(DecoderEvent::rejected_frame, v, a.seq);
    return;
  }
  ++v.health.frames;
  accept(v, a, d.message);
}

void Decoder::tick(double t_s) {
  for (auto& [address, v] : nodes_) {
    if (v.online && t_s - v.last_frame_s >= offline_after_s_) {
      close_report(v, assembly_[address]);
      v.online = false;
      ++v.health.offline_events;
      emit(DecoderEvent::offline, v, assembly_[address].seq);
    }
  }
}

void Decoder::flush() {
  for (auto& [address, v] : nodes_) close_report(v, assembly_[address]);
}

void Decoder::accept(NodeView& v, Assembly& a, const Message& message) {
  std::visit(
      [&](const auto& msg) {
        using M = std::decay_t<decltype(msg)>;
        if constexpr (!std::is_same_v<M, CounterInputMsg>) {
          if (!a.open || msg.seq != a.seq) open_report(v, a, msg.seq);
        }
        if constexpr (std::is_same_v<M, StatusMsg>) {
          const bool went_back = v.have_status && msg.sample_count < v.status.sample_count;
          const bool tau_count_changed = v.have_status && msg.tau_count != v.status.tau_count;
          if (went_back || tau_count_changed) {
            restart(v, a);
            open_report(v, a, msg.seq);
          }
          v.status = msg;
          v.have_status = true;
          if (a.tau_count != msg.tau_count) {
            a.tau_count = msg.tau_count;
            layout(a);
          }
          mark_slot(v, a, Slot::status, 0);
        } else if constexpr (std::is_same_v<M, StatusFaultsMsg>) {
          v.faults = msg;
          mark_slot(v, a, Slot::faults, 0);
        } else if constexpr (std::is_same_v<M, TauDevMsg>) {
          TauView::Dev& dev = msg.kind == DevKind::adev ? v.taus[msg.tau_index].adev : v.taus[msg.tau_index].mdev;
          dev = {true, msg.dev_angle_per_s, msg.edf, msg.noise, msg.valid, v.report};
          mark_slot(v, a, msg.kind == DevKind::adev ? Slot::adev : Slot::mdev, msg.tau_index);
        } else if constexpr (std::is_same_v<M, TauTermsMsg>) {
          v.taus[msg.tau_index].n = msg.n;
          mark_slot(v, a, Slot::terms, msg.tau_index);
        } else if constexpr (std::is_same_v<M, TauInfoMsg>) {
          v.taus[msg.tau_index].m = msg.m;
          v.taus[msg.tau_index].stride_log2 = msg.stride_log2;
          mark_slot(v, a, Slot::tau_info, msg.tau_index);
        } else if constexpr (std::is_same_v<M, MetaSamplingMsg>) {
          v.sampling = msg;
          mark_slot(v, a, Slot::sampling, 0);
        } else if constexpr (std::is_same_v<M, MetaClockMsg>) {
          if (v.clock && msg.uptime_ms < v.clock->uptime_ms) {
            restart(v, a);
            open_report(v, a, msg.seq);
          }
          v.clock = msg;
          relayout_if_schedule_changed(v, a);
          mark_slot(v, a, Slot::clock, 0);
        } else if constexpr (std::is_same_v<M, MetaScaleMsg>) {
          v.scale = msg;
          mark_slot(v, a, Slot::scale, 0);
        } else if constexpr (std::is_same_v<M, MetaConfigMsg>) {
          if (v.config && msg.config_hash != v.config->config_hash) {
            restart(v, a);
            open_report(v, a, msg.seq);
          }
          v.config = msg;
          mark_slot(v, a, Slot::config, 0);
        } else if constexpr (std::is_same_v<M, Ieee952Msg>) {
          v.ieee952[static_cast<std::size_t>(msg.term)] = {
              true, msg.resolved, msg.value, msg.rel_uncertainty, msg.fitted || msg.resolved, v.cycle()};
          mark_slot(v, a, Slot::ieee952, static_cast<std::uint8_t>(msg.term));
        } else if constexpr (std::is_same_v<M, Ieee952SummaryMsg>) {
          v.ieee952_summary = msg;
          v.ieee952_summary_cycle = v.cycle();
          relayout_if_schedule_changed(v, a);
          mark_slot(v, a, Slot::ieee952, ieee952_summary_page);
        } else if constexpr (std::is_same_v<M, Ieee952ModelMsg>) {
          fit_model_of_cycle(v).model = msg;
          relayout_if_schedule_changed(v, a);
          mark_slot(v, a, Slot::fit_model, 0);
        } else if constexpr (std::is_same_v<M, Ieee952ParameterMsg>) {
          const std::size_t k = fit_parameter_position(msg.parameter, msg.index);
          fit_model_of_cycle(v).parameters[k] = msg;
          mark_slot(v, a, Slot::fit_parameter, static_cast<std::uint8_t>(k));
        } else if constexpr (std::is_same_v<M, Ieee952UnconstrainedMsg>) {
          const auto k = static_cast<std::size_t>(msg.term);
          if (v.unconstrained[k].cycle != v.cycle()) v.previous_unconstrained[k] = v.unconstrained[k];
          v.unconstrained[k] = {v.cycle(), msg};
          mark_slot(v, a, Slot::unconstrained, static_cast<std::uint8_t>(k));
        } else if constexpr (std::is_same_v<M, WindowMsg>) {
          if (v.window_taus != 0 && msg.tau_count != v.window_taus) {  // reconfigured, like TauCount
            restart(v, a);
            open_report(v, a, msg.seq);
          }
          v.window_taus = msg.tau_count;
          relayout_if_schedule_changed(v, a);
          v.window_page = msg;
          if (msg.complete) {
            WindowView& w = v.windows[msg.window];
            w.window = msg.window;
            w.gaps = msg.gaps;
            w.adev.resize(msg.tau_count);
            w.mdev.resize(msg.tau_count);
            w.received.resize(msg.tau_count);
          }
          mark_slot(v, a, Slot::window, 0);
        } else if constexpr (std::is_same_v<M, WindowLengthMsg>) {
          v.window_length = msg.length;
          mark_slot(v, a, Slot::window_length, 0);
        } else if constexpr (std::is_same_v<M, WindowDevMsg>) {
          accept_window_dev(v, a, msg);
          mark_slot(v, a, Slot::window_dev, msg.tau_index);
        }
      },
      message);
}

FitModelView& Decoder::fit_model_of_cycle(NodeView& v) {
  // A page of a new cycle starts that cycle's model; the one before stays for a summary that
  // belongs to it.
  if (v.fit_model.cycle != v.cycle()) {
    v.previous_fit_model = v.fit_model;
    v.fit_model = FitModelView{};
    v.fit_model.cycle = v.cycle();
  }
  return v.fit_model;
}

void Decoder::accept_window_dev(NodeView& v, Assembly& a, const WindowDevMsg& msg) {
  // The frame belongs to the window its cycle's window page named; WindowMod16 says whether it is
  // that one (the page may have been lost, and the node moved on to another window). While the
  // node has no completed window its frames carry nothing.
  if (v.window_page && !v.window_page->complete && msg.adev_angle_per_s == 0 && msg.mdev_angle_per_s == 0) return;
  const std::optional<std::uint32_t> k = v.current_window();
  const auto current = k ? v.windows.find(*k) : v.windows.end();
  if (current == v.windows.end() || (current->first & 15u) != msg.window || msg.tau_index >= v.window_taus) {
    ++v.health.window_frames_unplaced;
    return;
  }
  WindowView& w = current->second;
  const bool was_complete = w.complete();
  w.adev[msg.tau_index] = msg.adev_angle_per_s;
  w.mdev[msg.tau_index] = msg.mdev_angle_per_s;
  w.received[msg.tau_index] = true;
  if (!was_complete && w.complete()) emit(DecoderEvent::window_complete, v, a.seq);
}

void Decoder::open_report(NodeView& v, Assembly& a, std::uint8_t seq) {
  // Rule 2 holds across an offline period too (rule 4 closed the report, the last Seq stays): the
  // reports a node made while none of its frames arrived (its bus down, the decoder's link cut)
  // are lost reports, whatever the reason they did not arrive.
  std::uint8_t lost = 0;
  if (a.seen) {
    const auto d = static_cast<std::uint8_t>(seq - a.seq);
    close_report(v, a);
    if (d >= 128) {
      restart(v, a);  // Seq went backwards
    } else if (d > 1) {
      lost = static_cast<std::uint8_t>(d - 1u);
      v.health.reports_lost += lost;
    }
  }
  v.reports_made = v.report == 0 ? seq : v.reports_made + static_cast<std::uint8_t>(seq - a.seq);
  ++v.report;
  v.report_open = true;
  a.open = true;
  a.seen = true;
  a.seq = seq;
  a.start_s = now_s_;
  a.lost_at_open = lost;
  a.tau_count = v.have_status ? v.status.tau_count : 0;
  a.version = v.schedule_version();
  a.window_taus = v.window_taus;
  a.arrived.fill(false);
  layout(a);
}

void Decoder::relayout_if_schedule_changed(const NodeView& v, Assembly& a) {
  // Every version, with or without window taus, puts the frames it shares with the others at the
  // same position (protocol.hpp): what was received stays.
  if (a.version == v.schedule_version() && a.window_taus == v.window_taus) return;
  a.version = v.schedule_version();
  a.window_taus = v.window_taus;
  layout(a);
}

void Decoder::layout(Assembly& a) {
  a.position.fill(-1);
  const std::size_t frames = report_frame_count(a.seq, a.tau_count, a.version, a.window_taus);
  for (std::size_t k = 0; k < frames && k < a.arrived.size(); ++k) {
    const ReportSlot s = report_slot(a.seq, a.tau_count, k, a.version, a.window_taus);
    a.position[static_cast<std::size_t>(s.slot) * max_taus + s.index] = static_cast<std::int16_t>(k);
  }
}

void Decoder::close_report(NodeView& v, Assembly& a) {
  if (!a.open) return;
  a.open = false;
  v.report_open = false;
  const std::size_t frames = report_frame_count(a.seq, a.tau_count, a.version, a.window_taus);
  std::uint64_t missing = 0;
  for (std::size_t k = 0; k < frames && k < a.arrived.size(); ++k) missing += a.arrived[k] ? 0 : 1;
  v.health.frames_missing += missing;
  if (missing == 0) {
    ++v.health.reports_complete;
  } else {
    ++v.health.reports_incomplete;
  }
  emit(DecoderEvent::report_closed, v, a.seq);
}

void Decoder::restart(NodeView& v, Assembly& a) {
  const std::uint8_t address = v.address;
  LinkHealth health = v.health;
  // A restart found in the report that opened with a Seq jump (its Status, Clock or Config): the
  // jump was the node starting again, not reports lost (rule 3 before rule 2).
  health.reports_lost -= a.open ? a.lost_at_open : 0u;
  const std::uint32_t session = v.session;
  const double last_frame_s = v.last_frame_s;
  v = NodeView{};
  v.address = address;
  v.online = true;
  v.last_frame_s = last_frame_s;  // the node is heard now: not offline at the next tick
  v.health = health;
  ++v.health.restarts;
  v.session = session + 1;
  a = Assembly{};
  emit(DecoderEvent::restart, v, a.seq);
}

void Decoder::mark_slot(NodeView& v, Assembly& a, Slot slot, std::uint8_t index) {
  const std::int16_t k = a.position[static_cast<std::size_t>(slot) * max_taus + index];
  if (k < 0) return;  // not expected in this report (e.g. a tau beyond TauCount)
  if (a.arrived[static_cast<std::size_t>(k)]) {
    ++v.health.duplicates;
    emit(DecoderEvent::duplicate, v, a.seq);
  }
  a.arrived[static_cast<std::size_t>(k)] = true;
}

}  // namespace gyrochar
