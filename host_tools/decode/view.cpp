#include "view.hpp"

#include <fmt/format.h>

#include <cmath>
#include <iterator>

#include "confidence.hpp"

namespace gyrochar::decoding {

using namespace protocol;

namespace {

std::string rejected_text(const LinkHealth& h) {
  std::uint64_t total = 0;
  std::string reasons;
  for (const auto& [reason, count] : h.rejected) {
    total += count;
    reasons += fmt::format("{}{} {}", reasons.empty() ? "" : ", ", name(reason), count);
  }
  return total == 0 ? "0" : fmt::format("{} ({})", total, reasons);
}

std::string health_text(const LinkHealth& h) {
  return fmt::format(
      "frames {}; reports {} complete, {} incomplete, {} lost; frames missing {}; restarts {}; "
      "offline {}; duplicates {}; rejected {}{}{}",
      h.frames, h.reports_complete, h.reports_incomplete, h.reports_lost, h.frames_missing, h.restarts, h.offline_events,
      h.duplicates, rejected_text(h),
      h.not_decoded ? fmt::format("; not decoded {} (unknown protocol version)", h.not_decoded) : "",
      h.window_frames_unplaced ? fmt::format("; window frames without their window page {}", h.window_frames_unplaced) : "");
}

std::string input_text(const Decoder& decoder, const InputCounters& in) {
  std::string s = fmt::format("{}: ", in.source);
  if (in.lines > 0) s += fmt::format("{} lines, {} malformed line(s); ", in.lines, in.malformed_lines);
  s += fmt::format("{} frames: {} other traffic, {} rejected frames", in.frames, decoder.other_frames(),
                   decoder.rejected_frames());
  if (in.remote_frames > 0) s += fmt::format(", {} remote requests (RTR: no data, not decoded)", in.remote_frames);
  if (in.time_backwards > 0) s += fmt::format(", {} timestamps backwards", in.time_backwards);
  if (in.started) s += fmt::format(", {:.1f} s", in.now_s - in.first_s);
  return s;
}

std::string dev_text(const TauView::Dev& d, Viewed viewed, double rate, ConfidenceIntervals& intervals) {
  if (viewed != Viewed::shown) return fmt::format("{:>11}  {:24}", name(viewed), "");
  if (!d.received || !d.valid) return fmt::format("{:>11}  {:24}", "-", "");
  const double value = static_cast<double>(d.dev) * rate;
  const Interval ci = intervals(value, d.edf);
  return ci.valid ? fmt::format("{:>11.4e}  [{:.3e}, {:.3e}]", value, ci.low, ci.high)
                  : fmt::format("{:>11.4e}  {:24}", value, "(no EDF)");
}

std::string seconds_text(const std::optional<double>& tau_s, std::uint8_t log2_m) {
  return tau_s ? fmt::format("{:.4g} s", *tau_s) : fmt::format("m < 2^{}", log2_m);
}

/// The IEEE-952 part of a node's view: the summary's headline, then the terms, then what the
/// reader must not miss (a rejected model, short taus left out), each on its own line.
void ieee952_view(std::string& s, const NodeView& v, const Units& u, const TrueTerms* truth) {
  auto out = std::back_inserter(s);
  const auto& fit = v.ieee952_summary;
  const bool made = !fit || fit->status == Ieee952Status::ok || fit->status == Ieee952Status::rejected;
  if (!fit) {
    s += "  IEEE-952 (node's fit):";  // a version-1 node, or its summary has not arrived yet
  } else if (made) {
    fmt::format_to(out, "  IEEE-952 (node's fit of both curves, chi2/dof {:.3g} on {} points):", fit->chi2_per_dof,
                   fit->points);
  } else {
    fmt::format_to(out, "  IEEE-952 (node's fit of both curves): no fit: {} ({} points)",
                   fit->status == Ieee952Status::too_few_points ? "too few points" : "singular", fit->points);
  }
  const std::optional<double> si_to_wire = truth ? wire_per_si(v) : std::nullopt;
  for (std::size_t k = 0; k < 5 && made; ++k) {
    const Ieee952View& p = v.ieee952[k];
    const double shown = u.ieee[k];
    if (!p.received) {
      fmt::format_to(out, "  {} -", units::ieee952[k].letter);
    } else if (p.in_model()) {
      fmt::format_to(out, "  {} {:.4g} {} ({}+-{:.1f}%)", units::ieee952[k].letter, p.value * shown, u.ieee_name[k],
                     p.resolved ? "" : "not resolved, ", 100.0 * p.rel_uncertainty);
    } else if (k == 0 && fit && !fit->quantization_white) {
      if (v.scale)
        fmt::format_to(out, "  Q held at {:.4g} {} (pulse weight/sqrt(12))",
                       static_cast<double>(v.scale->angle_per_pulse) / std::sqrt(12.0) * shown, u.ieee_name[k]);
      else s += "  Q held at pulse weight/sqrt(12)";
    } else {
      fmt::format_to(out, "  {} {}", units::ieee952[k].letter, fit ? "not fitted" : "not resolved");
    }
    if (si_to_wire) fmt::format_to(out, ", simulated {:.4g}", truth->qnbkr[k] * *si_to_wire * shown);
  }
  s += '\n';
  if (fit && fit->status == Ieee952Status::rejected)
    s += "  MODEL REJECTED: the IEEE-952 terms do not describe this curve\n";
  if (fit && !fit->quantization_white) {
    const auto [avar, mvar] = fit->excluded_below_log2_m;
    s += "  quantization not white: short taus left out";
    if (avar != 0) fmt::format_to(out, " (AVAR below {}", seconds_text(fit_excluded_below_tau_s(v, 0), avar));
    if (mvar != 0)
      fmt::format_to(out, "{}MVAR below {}", avar != 0 ? ", " : " (", seconds_text(fit_excluded_below_tau_s(v, 1), mvar));
    if (avar != 0 || mvar != 0) s += ')';
    s += ", Q held at pulse weight/sqrt(12)\n";
  }
}

/// A parameter of the model beyond the five terms: its value with the relative uncertainty.
std::string parameter_text(const FitModelRow::Parameter& p, const char* unit, bool with_resolved) {
  std::string s = fmt::format("{:.4g} {}", p.value, unit);
  if (p.rel_uncertainty > 0 || (with_resolved && !p.resolved))
    s += fmt::format(" ({}+-{:.1f}%)", with_resolved && !p.resolved ? "not resolved, " : "", 100.0 * p.rel_uncertainty);
  return s;
}

/// A correlation time with its 68 % interval, "170 s (68 %: 101 .. 286 s)" (the relative
/// uncertainty sent is sd(ln Tc)).
std::string time_text(const FitModelRow::Parameter& p) {
  const std::string interval = correlation_time_interval(p.value, p.rel_uncertainty * p.value);
  return fmt::format("{:.4g} s", p.value) + (interval.empty() ? "" : " (" + interval + ")");
}

/// The model's line (protocol version 4): the Markov terms, the sensor's filter and the sinusoids
/// of the fit the summary above describes, or why they are not shown.
void model_view(std::string& s, const NodeView& v, const Units& u) {
  const std::optional<FitModelRow> m = fit_model_row(v, u);
  if (!m || !v.ieee952_summary) return;
  const Ieee952Status status = v.ieee952_summary->status;
  if (status != Ieee952Status::ok && status != Ieee952Status::rejected) return;
  auto out = std::back_inserter(s);
  s += "  model:";
  if (m->state != Viewed::shown) {
    fmt::format_to(out, " {} (this fit's model pages {})\n", name(m->state),
                   m->state == Viewed::pending ? "are still arriving" : "were lost");
    return;
  }
  const auto page = [&](FitParameter p, std::uint8_t j) { return m->parameters[fit_parameter_position(p, j)]; };
  const std::string rate = u.rate_name;
  if (m->markov == 0 && m->sinusoids == 0 && !m->bandwidth) s += " the five terms";
  for (std::uint8_t j = 0; j < m->markov; ++j)
    fmt::format_to(out, "  Markov {}: sigma {}, Tc {}", j + 1,
                   parameter_text(page(FitParameter::markov_sigma, j), rate.c_str(), true),
                   time_text(page(FitParameter::markov_tc, j)));
  if (m->bandwidth) fmt::format_to(out, "  sensor filter: Tf {}", time_text(page(FitParameter::filter_tf, 0)));
  for (std::uint8_t j = 0; j < m->sinusoids; ++j)
    fmt::format_to(out, "  sinusoid {}: amplitude {} at {:.4g} Hz", j + 1,
                   parameter_text(page(FitParameter::sinusoid_amplitude, j), rate.c_str(), true),
                   page(FitParameter::sinusoid_frequency, j).value);
  if (m->bandwidth_excluded_below_tau_s && *m->bandwidth_excluded_below_tau_s > 0)
    fmt::format_to(out, "; taus below {:.4g} s left out (sensor filter)", *m->bandwidth_excluded_below_tau_s);
  if (const auto& r = m->runner_up)
    fmt::format_to(out, "; runner-up: {} Markov, {} sinusoids{}, criterion {:+.3g}", r->runner_up_markov,
                   r->runner_up_sinusoids, r->runner_up_bandwidth ? ", filter" : "", r->criterion_margin);
  s += '\n';
}

/// The dynamic Allan deviation's line: the window, and the latest window's ADEV at each window tau.
void window_view(std::string& s, const NodeView& v, const Units& u) {
  if (v.window_taus == 0) return;
  auto out = std::back_inserter(s);
  const double length_s = v.sampling ? static_cast<double>(v.window_length) * static_cast<double>(v.sampling->tau0_s) : 0.0;
  fmt::format_to(out, "  dynamic ADEV: {} window taus, ", v.window_taus);
  if (length_s > 0) fmt::format_to(out, "windows of {:.4g} s", length_s);
  else s += "window length not received yet";
  std::size_t complete = 0;
  for (const auto& [k, w] : v.windows) complete += w.complete() ? 1 : 0;
  fmt::format_to(out, "; {} windows received, {} complete", v.windows.size(), complete);
  if (!v.windows.empty()) {
    const WindowView& w = v.windows.rbegin()->second;
    fmt::format_to(out, "; window {}{} [{}]:", w.window, w.gaps ? fmt::format(" ({} gaps)", w.gaps) : "", u.rate_name);
    for (std::size_t i = 0; i < w.adev.size(); ++i)
      s += w.received[i] && w.adev[i] > 0 ? fmt::format(" {:.3e}", w.adev[i] * u.rate) : " -";
  }
  s += '\n';
}

void node_view(std::string& s, const NodeView& v, const DisplayRate& rate, ConfidenceIntervals& intervals,
               const TrueTerms* truth) {
  const Units u = units_for(v, rate);
  auto out = std::back_inserter(s);
  fmt::format_to(out, "\nnode 0x{:02X}  {}  {}  session {}", v.address, v.online ? "online" : "OFFLINE",
                 v.have_status ? name(v.status.state) : "no status yet", v.session);
  if (v.have_status) fmt::format_to(out, "  samples {}", v.status.sample_count);
  if (v.clock)
    fmt::format_to(out, "  uptime {:.1f} s  protocol {}", static_cast<double>(v.clock->uptime_ms) / 1000.0,
                   v.clock->protocol_version);
  if (v.config) fmt::format_to(out, "  config 0x{:08X}  report {} ms", v.config->config_hash, v.config->report_period_ms);
  if (v.unknown_version != 0)
    fmt::format_to(out,
                   "\n  NOT DECODED: the node speaks protocol version {}, this decoder knows 1 to {} "
                   "(values below are from before)",
                   v.unknown_version, protocol::version);
  s += "\n ";
  if (v.sampling) fmt::format_to(out, " tau0 {} s  S {} ", v.sampling->tau0_s, v.sampling->stride_factor);
  if (v.scale) {
    fmt::format_to(out, " angle unit {} ({} {}/pulse)  input {}", name(v.scale->angle_unit), v.scale->angle_per_pulse,
                   name(v.scale->angle_unit), name(v.scale->input_source));
  } else {
    s += " angle unit not received yet: values as sent";
  }
  fmt::format_to(out, "  rates [{}]", u.rate_name);
  if (u.pulses) s += " (pulses: not converted)";
  fmt::format_to(out, "\n  link: {}\n", health_text(v.health));
  fmt::format_to(out, "  node faults: lost edges {}, sample gaps {}, tx dropped frames {}, bus-off events {}\n",
                 v.faults.lost_edges, v.faults.sample_gaps, v.faults.tx_dropped_frames, v.faults.bus_off_events);
  const std::string level = fmt::format("({:.1f}% CI)", 100.0 * intervals.confidence());
  fmt::format_to(out, "  {:>11} {:>13}  {:>11}  {:24}  {:>11}  {:24}  {:>9}  {}\n", "tau [s]", "n", "ADEV", level, "MDEV",
                 level, "EDF MDEV", "noise");
  for (std::size_t i = 0; i < v.status.tau_count && i < max_taus; ++i) {
    const TauView& t = v.taus[i];
    const ViewedRow viewed = viewed_row(v, i);
    const std::string tau = t.m && v.sampling ? fmt::format("{:.4g}", v.tau_s(i)) : fmt::format("#{}", i);
    const std::string n = t.n ? fmt::format("{}", t.n) : "-";
    const bool adev = t.adev.received && viewed.adev == Viewed::shown;
    const bool mdev = t.mdev.received && viewed.mdev == Viewed::shown;
    const std::string edf = mdev && t.mdev.edf > 0 ? fmt::format("{:.4g}", t.mdev.edf) : "-";
    std::string noise = adev ? name(t.adev.noise) : "-";
    if (mdev && (!adev || t.mdev.noise != t.adev.noise)) noise += fmt::format(" / {} (MDEV)", name(t.mdev.noise));
    fmt::format_to(out, "  {:>11} {:>13}  {}  {}  {:>9}  {}\n", tau, n, dev_text(t.adev, viewed.adev, u.rate, intervals),
                   dev_text(t.mdev, viewed.mdev, u.rate, intervals), edf, noise);
  }
  ieee952_view(s, v, u, truth);
  model_view(s, v, u);
  window_view(s, v, u);
}

}  // namespace

std::string format_view(const Decoder& decoder, const InputCounters& input, const NodeFilter& shown, const DisplayRate& rate,
                        ConfidenceIntervals& intervals, const TrueTermsByNode* truth) {
  std::string s = "gyrochar-decode: " + input_text(decoder, input) + "\n";
  if (!input.bus.empty()) s += "  " + input.bus + "\n";
  std::size_t count = 0;
  for (const auto& [address, v] : decoder.nodes()) {
    if (!shown[address]) continue;
    const TrueTerms* known = nullptr;
    if (truth != nullptr) {
      const auto it = truth->find(address);
      if (it != truth->end()) known = &it->second;
    }
    node_view(s, v, rate, intervals, known);
    ++count;
  }
  if (count == 0) s += "\nno gyrochar node seen yet\n";
  return s;
}

std::string format_summary(const Decoder& decoder, const InputCounters& input, const NodeFilter& shown,
                           std::string_view program) {
  std::string s = fmt::format("{}: {}\n", program, input_text(decoder, input));
  if (!input.bus.empty()) s += fmt::format("{}: {}\n", program, input.bus);
  for (const auto& [address, v] : decoder.nodes()) {
    if (!shown[address]) continue;
    s += fmt::format("{}: node 0x{:02X}{}: {}\n", program, address, v.online ? "" : " (offline)", health_text(v.health));
  }
  return s;
}

}  // namespace gyrochar::decoding
