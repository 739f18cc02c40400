#include "decode_output.hpp"

#include <fmt/compile.h>
#include <fmt/format.h>

#include <cmath>
#include <iterator>
#include <nlohmann/json.hpp>
#include <numbers>
#include <type_traits>

#include "gyrochar/ieee952.hpp"

namespace gyrochar::decoding {

using namespace protocol;
using Json = nlohmann::ordered_json;

namespace {

constexpr std::array<const char*, 5> term_letters{"Q", "N", "B", "K", "R"};

double degrees_per(AngleUnit u) {
  switch (u) {
    case AngleUnit::rad:
      return 180.0 / std::numbers::pi;
    case AngleUnit::urad:
      return 180.0e-6 / std::numbers::pi;
    case AngleUnit::deg:
      return 1.0;
    case AngleUnit::arcsec:
      return 1.0 / 3600.0;
    case AngleUnit::pulse:
      break;
  }
  return 0.0;  // pulses have no angle: never converted
}

// Value or nothing: CSV leaves the field empty, JSON writes null.
template <class T>
Json json_or_null(bool known, T value) {
  return known ? Json(value) : Json(nullptr);
}
template <class T>
Json json_or_null(const std::optional<T>& value) {
  return value ? Json(*value) : Json(nullptr);
}

/// Wire value (the node's angle unit) per SI value (rad): the same factor for every IEEE-952 term,
/// whose other dimensions are seconds on both sides. Nothing for pulses or an unknown unit.
std::optional<double> wire_per_si(const NodeView& node) {
  if (!node.scale || node.scale->angle_unit == AngleUnit::pulse) return std::nullopt;
  const double deg = degrees_per(node.scale->angle_unit);
  if (!(deg > 0)) return std::nullopt;
  return 180.0 / std::numbers::pi / deg;
}

/// A term is in the node's model when fitted (a version-1 node: when resolved).
bool in_model(const Ieee952View& t) { return t.received && (t.fitted || t.resolved); }

}  // namespace

std::optional<double> fit_excluded_below_tau_s(const NodeView& node, std::size_t k) {
  if (!node.ieee952_summary || k > 1) return std::nullopt;
  const std::uint8_t c = node.ieee952_summary->excluded_below_log2_m[k];
  if (c == 0) return 0.0;
  if (!node.sampling) return std::nullopt;
  return static_cast<double>(node.sampling->tau0_s) * std::ldexp(1.0, c);
}

// ---------------------------------------------------------------------------------------------
// Units

std::optional<RateUnit> parse_rate_unit(std::string_view text) {
  if (text == "deg/h") return RateUnit::deg_per_h;
  if (text == "deg/s") return RateUnit::deg_per_s;
  if (text == "rad/s") return RateUnit::rad_per_s;
  if (text == "native") return RateUnit::native;
  return std::nullopt;
}

Units units_for(const NodeView& node, RateUnit choice) {
  Units u;
  if (!node.scale) {
    u.rate_name = "unknown";
    u.ieee_name.fill("unknown");
    return u;
  }
  u.known = true;
  const AngleUnit angle = node.scale->angle_unit;
  u.pulses = angle == AngleUnit::pulse;
  if (u.pulses || choice == RateUnit::native) {
    const std::string a = name(angle);
    u.rate_name = a + "/s";
    u.ieee_name = {a, a + "/sqrt(s)", a + "/s", a + "/s/sqrt(s)", a + "/s/s"};
    return u;
  }
  const double deg = degrees_per(angle);
  const bool per_h = choice == RateUnit::deg_per_h, in_rad = choice == RateUnit::rad_per_s;
  u.rate_name = per_h ? "deg/h" : in_rad ? "rad/s" : "deg/s";
  u.rate = per_h ? deg * 3600.0 : in_rad ? deg * std::numbers::pi / 180.0 : deg;
  // Q [arcsec], N [deg/sqrt(h)] = 60 N [deg/sqrt(s)], B [deg/h], K [deg/h/sqrt(h)] = 3600^1.5 K [deg/s^1.5],
  // R [deg/h/h] = 3600^2 R [deg/s^2].
  u.ieee_name = {"arcsec", "deg/sqrt(h)", "deg/h", "deg/h/sqrt(h)", "deg/h/h"};
  u.ieee = {deg * 3600.0, deg * 60.0, deg * 3600.0, deg * 3600.0 * 60.0, deg * 3600.0 * 3600.0};
  return u;
}

// ---------------------------------------------------------------------------------------------
// Confidence intervals

Interval ConfidenceIntervals::operator()(double dev, double edf) {
  if (!(edf > 0) || !std::isfinite(edf)) return {};
  auto it = unit_intervals_.find(edf);
  if (it == unit_intervals_.end()) it = unit_intervals_.emplace(edf, confidence_interval(1.0, edf, confidence_)).first;
  const Interval& unit = it->second;
  return unit.valid ? Interval{dev * unit.low, dev * unit.high, true} : Interval{};
}

// ---------------------------------------------------------------------------------------------
// Report tracker

void ReportTracker::note(const CanFrame& frame, double t_s) {
  const Decoded d = decode(frame);
  if (d.error != ProtocolError::none) return;
  std::visit(
      [&](const auto& msg) {
        using M = std::decay_t<decltype(msg)>;
        if constexpr (!std::is_same_v<M, CounterInputMsg>) {
          Report& r = reports_[d.node];
          if (!r.open || r.seq != msg.seq) r = Report{true, msg.seq, t_s, {}, {}};
          if constexpr (std::is_same_v<M, TauDevMsg>)
            (msg.kind == DevKind::adev ? r.adev : r.mdev)[msg.tau_index] = true;
        }
      },
      d.message);
}

// ---------------------------------------------------------------------------------------------
// Rows

const char* name(DevCell::Status s) {
  switch (s) {
    case DevCell::Status::ok:
      return "ok";
    case DevCell::Status::invalid:
      return "invalid";
    case DevCell::Status::missing:
      return "missing";
  }
  return "invalid";
}

namespace {

DevCell dev_cell(const TauView::Dev& d, bool received, double rate, ConfidenceIntervals& intervals) {
  DevCell c;
  if (!received) return c;  // missing: nothing from this report
  c.edf = d.edf;
  c.noise = d.noise;
  if (!d.valid) {
    c.status = DevCell::Status::invalid;
    return c;
  }
  c.status = DevCell::Status::ok;
  c.value = static_cast<double>(d.dev) * rate;
  c.ci = intervals(c.value, d.edf);
  return c;
}

}  // namespace

void tau_rows(const NodeView& node, const ReportTracker::Report& report, const Units& units,
              ConfidenceIntervals& intervals, std::vector<TauRow>& out) {
  for (std::uint8_t i = 0; i < node.status.tau_count && i < max_taus; ++i) {
    const TauView& t = node.taus[i];
    TauRow r;
    r.time_s = report.start_s;
    r.node = node.address;
    r.session = node.session;
    r.seq = report.seq;
    r.tau_index = i;
    r.m = t.m;
    r.tau_s = node.tau_s(i);
    r.n = t.n;
    r.adev = dev_cell(t.adev, report.adev[i], units.rate, intervals);
    r.mdev = dev_cell(t.mdev, report.mdev[i], units.rate, intervals);
    r.fit = node.ieee952_summary;
    r.fit_excluded_below_tau_s = {fit_excluded_below_tau_s(node, 0), fit_excluded_below_tau_s(node, 1)};
    out.push_back(r);
  }
}

namespace {

DevCell window_cell(double dev, bool received, double rate) {
  DevCell c;
  if (!received) return c;
  c.status = dev > 0 ? DevCell::Status::ok : DevCell::Status::invalid;
  c.value = dev * rate;
  return c;
}

}  // namespace

void window_rows(const NodeView& node, const WindowView& w, double time_s, std::uint8_t seq, const Units& units,
                 std::vector<WindowRow>& out) {
  const double tau0_s = node.sampling ? static_cast<double>(node.sampling->tau0_s) : 0.0;
  for (std::size_t i = 0; i < w.adev.size() && i < max_taus; ++i) {
    WindowRow r;
    r.time_s = time_s;
    r.node = node.address;
    r.session = node.session;
    r.seq = seq;
    r.window = w.window;
    r.length = node.window_length;
    if (tau0_s > 0 && node.window_length != 0) {
      const double length_s = static_cast<double>(node.window_length) * tau0_s;
      r.start_s = static_cast<double>(w.window) * length_s;
      r.end_s = r.start_s + length_s;
    }
    r.gaps = w.gaps;
    r.tau_index = static_cast<std::uint8_t>(i);
    r.m = node.taus[i].m;
    r.tau_s = node.tau_s(i);
    r.adev = window_cell(w.adev[i], w.received[i], units.rate);
    r.mdev = window_cell(w.mdev[i], w.received[i], units.rate);
    out.push_back(r);
  }
}

// ---------------------------------------------------------------------------------------------
// CSV

CsvWriter::CsvWriter(std::FILE* out, double confidence) : out_(out), confidence_(confidence) {
  std::fputs(
      "time_s,node,seq,tau_index,m,tau_s,n,"
      "adev,adev_low,adev_high,adev_edf,adev_noise,adev_status,"
      "mdev,mdev_low,mdev_high,mdev_edf,mdev_noise,mdev_status,"
      "rate_unit,ci_level,session,"
      "fit_status,fit_chi2_per_dof,fit_points,fit_quantization_white,"
      "fit_avar_excluded_below_tau_s,fit_mvar_excluded_below_tau_s,"
      "type,window,window_start_s,window_end_s,window_gaps\n",
      out_);
}

template <class T>
void CsvWriter::field(bool known, T value) {
  if (known) fmt::format_to(fmt::appender(line_), FMT_COMPILE("{}"), value);
  line_.push_back(',');
}

void CsvWriter::begin(double time_s, std::uint8_t node, std::uint8_t seq, std::uint8_t tau_index, std::uint64_t m,
                      double tau_s) {
  line_.clear();
  fmt::format_to(fmt::appender(line_), FMT_COMPILE("{:.6f},{},{},{},"), time_s, node, seq, tau_index);
  field(m != 0, m);
  field(tau_s > 0, static_cast<float>(tau_s));  // tau0 is a float32 on the wire
}

void CsvWriter::row(const WindowRow& r, const Units& units) {
  begin(r.time_s, r.node, r.seq, r.tau_index, r.m, r.tau_s);
  const auto out = fmt::appender(line_);
  line_.push_back(',');  // n: a window's terms are not sent
  for (const DevCell* c : {&r.adev, &r.mdev}) {
    field(c->status == DevCell::Status::ok, c->value);
    fmt::format_to(out, FMT_COMPILE(",,,,{},"), name(c->status));  // no interval, EDF or noise type
  }
  fmt::format_to(out, FMT_COMPILE("{},,{},,,,,,,window,{},"), units.rate_name, r.session, r.window);
  field(r.end_s > 0, r.start_s);
  field(r.end_s > 0, r.end_s);
  fmt::format_to(out, FMT_COMPILE("{}\n"), r.gaps);
  std::fwrite(line_.data(), 1, line_.size(), out_);
}

void CsvWriter::row(const TauRow& r, const Units& units) {
  begin(r.time_s, r.node, r.seq, r.tau_index, r.m, r.tau_s);
  const auto out = fmt::appender(line_);
  field(r.n != 0, r.n);
  for (const DevCell* c : {&r.adev, &r.mdev}) {
    field(c->status == DevCell::Status::ok, c->value);
    field(c->ci.valid, c->ci.low);
    field(c->ci.valid, c->ci.high);
    field(c->edf > 0, c->edf);
    field(c->status != DevCell::Status::missing, name(c->noise));
    field(true, name(c->status));
  }
  fmt::format_to(out, FMT_COMPILE("{},{},{},"), units.rate_name, confidence_, r.session);
  const bool fit = r.fit.has_value();
  field(fit, fit ? name(r.fit->status) : "");
  field(fit, fit ? r.fit->chi2_per_dof : 0.0f);
  field(fit, fit ? r.fit->points : 0u);
  field(fit, fit && r.fit->quantization_white ? "true" : "false");
  field(r.fit_excluded_below_tau_s[0].has_value(), r.fit_excluded_below_tau_s[0].value_or(0.0));
  field(r.fit_excluded_below_tau_s[1].has_value(), r.fit_excluded_below_tau_s[1].value_or(0.0));
  fmt::format_to(out, FMT_COMPILE("tau,,,,\n"));
  std::fwrite(line_.data(), 1, line_.size(), out_);
}

// ---------------------------------------------------------------------------------------------
// JSON lines

void JsonlWriter::line(const std::string& text) {
  std::fwrite(text.data(), 1, text.size(), out_);
  std::fputc('\n', out_);
}

namespace {

Json health_json(const LinkHealth& h) {
  Json rejected = Json::object();
  for (const auto& [reason, count] : h.rejected) rejected[name(reason)] = count;
  return Json{{"frames", h.frames},
              {"reports_complete", h.reports_complete},
              {"reports_incomplete", h.reports_incomplete},
              {"reports_lost", h.reports_lost},
              {"frames_missing", h.frames_missing},
              {"restarts", h.restarts},
              {"offline_events", h.offline_events},
              {"duplicates", h.duplicates},
              {"not_decoded", h.not_decoded},
              {"window_frames_unplaced", h.window_frames_unplaced},
              {"rejected", rejected}};
}

const char* name(DecoderEvent e) {
  switch (e) {
    case DecoderEvent::report_closed:
      return "report_closed";
    case DecoderEvent::restart:
      return "restart";
    case DecoderEvent::offline:
      return "offline";
    case DecoderEvent::online:
      return "online";
    case DecoderEvent::rejected_frame:
      return "rejected_frame";
    case DecoderEvent::duplicate:
      return "duplicate";
    case DecoderEvent::unknown_version:
      return "unknown_version";
    case DecoderEvent::window_complete:
      return "window_complete";
  }
  return "invalid";
}

}  // namespace

template <class T>
void JsonlWriter::member(const char* key, bool known, T value) {
  if (known)
    fmt::format_to(fmt::appender(line_), FMT_COMPILE(",\"{}\":{}"), key, value);
  else
    fmt::format_to(fmt::appender(line_), FMT_COMPILE(",\"{}\":null"), key);
}

// The tau rows are the bulk of a recording: written with fmt, not built as JSON objects (5x faster).
// Every string in them is an enumeration or unit name (plain ASCII, nothing to escape) and every
// number is finite; fmt's shortest round-trip form of a double is a valid JSON number.
void JsonlWriter::row(const TauRow& r, const Units& units) {
  line_.clear();
  const auto out = fmt::appender(line_);
  fmt::format_to(
      out, FMT_COMPILE("{{\"type\":\"tau\",\"time_s\":{:.6f},\"node\":{},\"session\":{},\"seq\":{},\"tau_index\":{}"),
      r.time_s, r.node, r.session, r.seq, r.tau_index);
  member("m", r.m != 0, r.m);
  member("tau_s", r.tau_s > 0, static_cast<float>(r.tau_s));  // as in the CSV
  member("n", r.n != 0, r.n);
  fmt::format_to(out, FMT_COMPILE(",\"rate_unit\":\"{}\",\"ci_level\":{}"), units.rate_name, confidence_);
  for (const auto& [key, c] : {std::pair{"adev", &r.adev}, std::pair{"mdev", &r.mdev}}) {
    fmt::format_to(out, FMT_COMPILE(",\"{}\":{{\"status\":\"{}\""), key, name(c->status));
    member("value", c->status == DevCell::Status::ok, c->value);
    member("low", c->ci.valid, c->ci.low);
    member("high", c->ci.valid, c->ci.high);
    member("edf", c->edf > 0, c->edf);
    if (c->status != DevCell::Status::missing)
      fmt::format_to(out, FMT_COMPILE(",\"noise\":\"{}\"}}"), name(c->noise));
    else
      fmt::format_to(out, FMT_COMPILE(",\"noise\":null}}"));
  }
  fmt::format_to(out, FMT_COMPILE("}}\n"));
  std::fwrite(line_.data(), 1, line_.size(), out_);
}

void JsonlWriter::row(const WindowRow& r, const Units& units) {
  line_.clear();
  const auto out = fmt::appender(line_);
  fmt::format_to(out,
                 FMT_COMPILE("{{\"type\":\"window\",\"time_s\":{:.6f},\"node\":{},\"session\":{},\"seq\":{},"
                             "\"window\":{},\"window_gaps\":{}"),
                 r.time_s, r.node, r.session, r.seq, r.window, r.gaps);
  member("window_length", r.length != 0, r.length);
  member("window_start_s", r.end_s > 0, r.start_s);
  member("window_end_s", r.end_s > 0, r.end_s);
  fmt::format_to(out, FMT_COMPILE(",\"tau_index\":{}"), r.tau_index);
  member("m", r.m != 0, r.m);
  member("tau_s", r.tau_s > 0, static_cast<float>(r.tau_s));
  fmt::format_to(out, FMT_COMPILE(",\"rate_unit\":\"{}\""), units.rate_name);
  for (const auto& [key, c] : {std::pair{"adev", &r.adev}, std::pair{"mdev", &r.mdev}}) {
    fmt::format_to(out, FMT_COMPILE(",\"{}\":{{\"status\":\"{}\""), key, name(c->status));
    member("value", c->status == DevCell::Status::ok, c->value);
    line_.push_back('}');
  }
  fmt::format_to(out, FMT_COMPILE("}}\n"));
  std::fwrite(line_.data(), 1, line_.size(), out_);
}

void JsonlWriter::report(double time_s, const NodeView& node, std::uint8_t seq, const Units& units) {
  const StatusFaultsMsg& f = node.faults;
  // A metadata field, null until its page has arrived.
  const auto meta_field = [](const auto& page, auto field) { return page ? Json(field(*page)) : Json(nullptr); };
  const Json meta{{"tau0_s", meta_field(node.sampling, [](const auto& m) { return m.tau0_s; })},
                  {"stride_factor", meta_field(node.sampling, [](const auto& m) { return m.stride_factor; })},
                  {"uptime_ms", meta_field(node.clock, [](const auto& m) { return m.uptime_ms; })},
                  {"protocol_version", meta_field(node.clock, [](const auto& m) { return m.protocol_version; })},
                  {"angle_unit", meta_field(node.scale, [](const auto& m) { return name(m.angle_unit); })},
                  {"angle_per_pulse", meta_field(node.scale, [](const auto& m) { return m.angle_per_pulse; })},
                  {"input_source", meta_field(node.scale, [](const auto& m) { return name(m.input_source); })},
                  {"config_hash", meta_field(node.config, [](const auto& m) { return m.config_hash; })},
                  {"report_period_ms", meta_field(node.config, [](const auto& m) { return m.report_period_ms; })}};
  Json ieee = Json::object();
  for (std::size_t k = 0; k < 5; ++k) {
    const Ieee952View& p = node.ieee952[k];
    const bool fitted = in_model(p);
    ieee[term_letters[k]] = !p.received ? Json(nullptr)
                                        : Json{{"fitted", fitted},
                                               {"resolved", p.resolved},
                                               {"value", json_or_null(fitted, p.value * units.ieee[k])},
                                               {"unit", units.ieee_name[k]},
                                               {"rel_uncertainty", json_or_null(fitted, p.rel_uncertainty)}};
  }
  Json fit(nullptr);
  if (const auto& f = node.ieee952_summary) {
    fit = Json{{"curve", "both"},
               {"status", name(f->status)},
               {"chi2_per_dof", f->chi2_per_dof},
               {"points", f->points},
               {"quantization_white", f->quantization_white},
               {"avar_excluded_below_tau_s", json_or_null(fit_excluded_below_tau_s(node, 0))},
               {"mvar_excluded_below_tau_s", json_or_null(fit_excluded_below_tau_s(node, 1))}};
  }
  const Json j{{"type", "report"},
               {"time_s", time_s},
               {"node", node.address},
               {"session", node.session},
               {"seq", seq},
               {"online", node.online},
               {"state", json_or_null(node.have_status, name(node.status.state))},
               {"tau_count", node.status.tau_count},
               {"sample_count", node.status.sample_count},
               {"faults",
                {{"lost_edges", f.lost_edges},
                 {"sample_gaps", f.sample_gaps},
                 {"tx_dropped_frames", f.tx_dropped_frames},
                 {"bus_off_events", f.bus_off_events}}},
               {"health", health_json(node.health)},
               {"metadata", meta},
               {"rate_unit", units.rate_name},
               {"ieee952", ieee},
               {"ieee952_fit", fit}};
  line(j.dump());
}

void JsonlWriter::event(double time_s, DecoderEvent e, const NodeView& node) {
  line(
      Json{{"type", "event"}, {"time_s", time_s}, {"node", node.address}, {"event", name(e)}, {"session", node.session}}
          .dump());
}

void JsonlWriter::summary(const Decoder& decoder, const InputCounters& input, const NodeFilter& shown) {
  Json nodes = Json::array();
  for (const auto& [address, v] : decoder.nodes()) {
    if (!shown[address]) continue;
    nodes.push_back(
        Json{{"node", address}, {"online", v.online}, {"session", v.session}, {"health", health_json(v.health)}});
  }
  line(Json{{"type", "summary"},
            {"source", input.source},
            {"lines", input.lines},
            {"malformed_lines", input.malformed_lines},
            {"frames", input.frames},
            {"other_frames", decoder.other_frames()},
            {"rejected_frames", decoder.rejected_frames()},
            {"time_backwards", input.time_backwards},
            {"first_s", json_or_null(input.started, input.first_s)},
            {"last_s", json_or_null(input.started, input.now_s)},
            {"nodes", nodes}}
           .dump());
}

// ---------------------------------------------------------------------------------------------
// Terminal view and summary

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
      h.frames, h.reports_complete, h.reports_incomplete, h.reports_lost, h.frames_missing, h.restarts,
      h.offline_events, h.duplicates, rejected_text(h),
      h.not_decoded ? fmt::format("; not decoded {} (unknown protocol version)", h.not_decoded) : "",
      h.window_frames_unplaced ? fmt::format("; window frames without their window page {}", h.window_frames_unplaced)
                               : "");
}

std::string input_text(const Decoder& decoder, const InputCounters& in) {
  std::string s = fmt::format("{}: ", in.source);
  if (in.lines > 0) s += fmt::format("{} lines, {} malformed line(s); ", in.lines, in.malformed_lines);
  s += fmt::format("{} frames: {} other traffic, {} rejected frames", in.frames, decoder.other_frames(),
                   decoder.rejected_frames());
  if (in.time_backwards > 0) s += fmt::format(", {} timestamps backwards", in.time_backwards);
  if (in.started) s += fmt::format(", {:.1f} s", in.now_s - in.first_s);
  return s;
}

std::string dev_text(const TauView::Dev& d, double rate, ConfidenceIntervals& intervals) {
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
      fmt::format_to(out, "  {} -", term_letters[k]);
    } else if (in_model(p)) {
      fmt::format_to(out, "  {} {:.4g} {} ({}+-{:.1f}%)", term_letters[k], p.value * shown, u.ieee_name[k],
                     p.resolved ? "" : "not resolved, ", 100.0 * p.rel_uncertainty);
    } else if (k == 0 && fit && !fit->quantization_white) {
      if (v.scale)
        fmt::format_to(out, "  Q held at {:.4g} {} (pulse weight/sqrt(12))",
                       static_cast<double>(v.scale->angle_per_pulse) / std::sqrt(12.0) * shown, u.ieee_name[k]);
      else
        s += "  Q held at pulse weight/sqrt(12)";
    } else {
      fmt::format_to(out, "  {} {}", term_letters[k], fit ? "not fitted" : "not resolved");
    }
    if (si_to_wire) fmt::format_to(out, ", simulated {:.4g}", (*truth)[k] * *si_to_wire * shown);
  }
  s += '\n';
  if (fit && fit->status == Ieee952Status::rejected)
    s += "  MODEL REJECTED: the IEEE-952 terms do not describe this curve\n";
  if (fit && !fit->quantization_white) {
    const auto [avar, mvar] = fit->excluded_below_log2_m;
    s += "  quantization not white: short taus left out";
    if (avar != 0) fmt::format_to(out, " (AVAR below {}", seconds_text(fit_excluded_below_tau_s(v, 0), avar));
    if (mvar != 0) fmt::format_to(out, "{}MVAR below {}", avar != 0 ? ", " : " (", seconds_text(fit_excluded_below_tau_s(v, 1), mvar));
    if (avar != 0 || mvar != 0) s += ')';
    s += ", Q held at pulse weight/sqrt(12)\n";
  }
}

/// The dynamic Allan deviation's line: the window, and the latest window's ADEV at each window tau.
void window_view(std::string& s, const NodeView& v, const Units& u) {
  if (v.window_taus == 0) return;
  auto out = std::back_inserter(s);
  const double length_s = v.sampling ? static_cast<double>(v.window_length) * static_cast<double>(v.sampling->tau0_s) : 0.0;
  fmt::format_to(out, "  dynamic ADEV: {} window taus, ", v.window_taus);
  if (length_s > 0)
    fmt::format_to(out, "windows of {:.4g} s", length_s);
  else
    s += "window length not received yet";
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

void node_view(std::string& s, const NodeView& v, RateUnit rate_unit, ConfidenceIntervals& intervals,
               const TrueTerms* truth) {
  const Units u = units_for(v, rate_unit);
  auto out = std::back_inserter(s);
  fmt::format_to(out, "\nnode 0x{:02X}  {}  {}  session {}", v.address, v.online ? "online" : "OFFLINE",
                 v.have_status ? name(v.status.state) : "no status yet", v.session);
  if (v.have_status) fmt::format_to(out, "  samples {}", v.status.sample_count);
  if (v.clock)
    fmt::format_to(out, "  uptime {:.1f} s  protocol {}", static_cast<double>(v.clock->uptime_ms) / 1000.0,
                   v.clock->protocol_version);
  if (v.config)
    fmt::format_to(out, "  config 0x{:08X}  report {} ms", v.config->config_hash, v.config->report_period_ms);
  if (v.unknown_version != 0)
    fmt::format_to(out, "\n  NOT DECODED: the node speaks protocol version {}, this decoder knows 1 to {} "
                   "(values below are from before)", v.unknown_version, protocol::version);
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
  fmt::format_to(out, "  {:>11} {:>13}  {:>11}  {:24}  {:>11}  {:24}  {:>9}  {}\n", "tau [s]", "n", "ADEV", level,
                 "MDEV", level, "EDF MDEV", "noise");
  for (std::size_t i = 0; i < v.status.tau_count && i < max_taus; ++i) {
    const TauView& t = v.taus[i];
    const std::string tau = t.m && v.sampling ? fmt::format("{:.4g}", v.tau_s(i)) : fmt::format("#{}", i);
    const std::string n = t.n ? fmt::format("{}", t.n) : "-";
    const std::string edf = t.mdev.received && t.mdev.edf > 0 ? fmt::format("{:.4g}", t.mdev.edf) : "-";
    std::string noise = t.adev.received ? name(t.adev.noise) : "-";
    if (t.mdev.received && t.mdev.noise != t.adev.noise) noise += fmt::format(" / {} (MDEV)", name(t.mdev.noise));
    fmt::format_to(out, "  {:>11} {:>13}  {}  {}  {:>9}  {}\n", tau, n, dev_text(t.adev, u.rate, intervals),
                   dev_text(t.mdev, u.rate, intervals), edf, noise);
  }
  ieee952_view(s, v, u, truth);
  window_view(s, v, u);
}

}  // namespace

std::string format_view(const Decoder& decoder, const InputCounters& input, const NodeFilter& shown, RateUnit rate_unit,
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
    node_view(s, v, rate_unit, intervals, known);
    ++count;
  }
  if (count == 0) s += "\nno gyrochar node seen yet\n";
  return s;
}

std::string format_summary(const Decoder& decoder, const InputCounters& input, const NodeFilter& shown) {
  std::string s = "gyrochar-decode: " + input_text(decoder, input) + "\n";
  if (!input.bus.empty()) s += "gyrochar-decode: " + input.bus + "\n";
  for (const auto& [address, v] : decoder.nodes()) {
    if (!shown[address]) continue;
    s += fmt::format("gyrochar-decode: node 0x{:02X}{}: {}\n", address, v.online ? "" : " (offline)",
                     health_text(v.health));
  }
  return s;
}

// ---------------------------------------------------------------------------------------------
// Plot series

namespace {

constexpr std::size_t line_points = 97;

std::vector<double> log_grid(double lo, double hi) {
  std::vector<double> tau(line_points);
  for (std::size_t k = 0; k < line_points; ++k)
    tau[k] = lo * std::pow(hi / lo, static_cast<double>(k) / static_cast<double>(line_points - 1));
  return tau;
}

// ADEV of the AVAR model with the given terms (wire units: A, s), in display units.
double model_adev(const std::array<double, 5>& qnbkr, double tau_s, double rate) {
  return std::sqrt(ieee952_avar(qnbkr, tau_s)) * rate;
}

}  // namespace

namespace {

// The heat map of the node's window curves: a column per window, a row per window tau (while tau0,
// the window length or a window tau's m is unknown: no columns yet).
HeatMap window_heat_map(const NodeView& node, const Units& u) {
  HeatMap h;
  const double tau0_s = node.sampling ? static_cast<double>(node.sampling->tau0_s) : 0.0;
  const double length_s = static_cast<double>(node.window_length) * tau0_s;
  h.title = length_s > 0 ? fmt::format("node 0x{:02X}, session {}: dynamic ADEV, windows of {:.4g} s", node.address,
                                       node.session, length_s)
                         : fmt::format("node 0x{:02X}, session {}: dynamic ADEV", node.address, node.session);
  h.value_name = "ADEV";
  h.unit = u.rate_name;
  for (std::size_t i = 0; i < node.window_taus; ++i) {
    if (!(node.tau_s(i) > 0)) return h;
    h.tau_s.push_back(node.tau_s(i));
  }
  if (!(length_s > 0)) return h;
  for (const auto& [k, w] : node.windows) {
    HeatMap::Column c{static_cast<double>(k) * length_s, static_cast<double>(k + 1) * length_s, {}};
    for (std::size_t i = 0; i < w.adev.size(); ++i) c.value.push_back(w.received[i] ? w.adev[i] * u.rate : 0.0);
    h.columns.push_back(std::move(c));
  }
  return h;
}

}  // namespace

NodePlot plot_data(const NodeView& node, RateUnit rate_unit, ConfidenceIntervals& intervals, const TrueTerms* truth) {
  const Units u = units_for(node, rate_unit);
  NodePlot p;
  p.title = fmt::format("node 0x{:02X}, session {}", node.address, node.session);
  p.rate_name = u.rate_name;
  if (node.window_taus != 0) p.dynamic = window_heat_map(node, u);
  double lo = INFINITY, hi = 0.0;
  for (std::size_t i = 0; i < node.status.tau_count && i < max_taus; ++i) {
    const double tau = node.tau_s(i);
    if (!(tau > 0)) continue;
    for (auto [dev, series] : {std::pair{&node.taus[i].adev, &p.adev}, std::pair{&node.taus[i].mdev, &p.mdev}}) {
      if (!dev->received || !dev->valid) continue;
      const double value = static_cast<double>(dev->dev) * u.rate;
      series->push_back({tau, value, intervals(value, dev->edf)});
      lo = std::min(lo, tau);
      hi = std::max(hi, tau);
    }
  }
  if (hi == 0.0) return p;
  p.tau_min_s = lo / 2.0;
  p.tau_max_s = hi * 2.0;
  const std::vector<double> grid = log_grid(p.tau_min_s, p.tau_max_s);
  if (truth != nullptr) {
    if (const std::optional<double> to_wire = wire_per_si(node)) {
      std::array<double, 5> wire{};
      for (std::size_t k = 0; k < 5; ++k) wire[k] = (*truth)[k] * *to_wire;
      PlotLine line{std::nullopt, "simulated gyro (truth)", grid, {}};
      for (const double tau : grid) line.dev.push_back(model_adev(wire, tau, u.rate));
      p.truth = std::move(line);
    }
  }

  // What the node's fit says, before any model line is drawn.
  const auto& fit = node.ieee952_summary;
  if (fit && fit->status == Ieee952Status::rejected) {
    p.notes.push_back(fmt::format("IEEE-952 fit REJECTED (chi2/dof {:.3g}):", fit->chi2_per_dof));
    p.notes.push_back("the model does not describe the curve");
    return p;
  }
  if (fit && fit->status != Ieee952Status::ok) {
    p.notes.push_back(fmt::format("no IEEE-952 fit: {}", fit->status == Ieee952Status::too_few_points
                                                              ? "too few points"
                                                              : "singular"));
    return p;
  }
  if (fit && !fit->quantization_white) {
    const auto below = [&](std::size_t k) {
      const std::optional<double> tau = fit_excluded_below_tau_s(node, k);
      return tau ? fmt::format("{:.3g} s", *tau) : std::string("?");
    };
    std::string note = "left out:";
    const auto [avar, mvar] = fit->excluded_below_log2_m;
    if (avar != 0) note += " ADEV < " + below(0);
    if (mvar != 0) note += std::string(avar != 0 ? "," : "") + " MDEV < " + below(1);
    p.notes.push_back("quantization not white, fit");
    p.notes.push_back(note);
  }

  const auto inside = [&](double tau) { return tau >= p.tau_min_s && tau <= p.tau_max_s; };
  // Where each term's ADEV equals its parameter (s); B has its own rule below.
  static constexpr std::array<double, 5> read_tau_s{std::numbers::sqrt3, 1.0, 0.0, 3.0, std::numbers::sqrt2};
  static constexpr std::array<const char*, 5> read_label{"Q at sqrt(3) s", "N at 1 s", "0.664 B", "K at 3 s",
                                                         "R at sqrt(2) s"};
  constexpr auto b_index = static_cast<std::size_t>(Ieee952Term::bias_instability);
  std::array<double, 5> model{};  // the fitted model, wire units
  std::size_t fitted = 0;
  for (std::size_t k = 0; k < 5; ++k) {
    const Ieee952View& t = node.ieee952[k];
    if (!in_model(t)) continue;
    ++fitted;
    model[k] = t.value;
    if (!t.resolved) continue;
    std::array<double, 5> one{};
    one[k] = t.value;
    PlotLine line{static_cast<Ieee952Term>(k),
                  fmt::format("{} {:.3g} {} (±{:.2g}%)", term_letters[k], t.value * u.ieee[k], u.ieee_name[k],
                              100.0 * t.rel_uncertainty),
                  grid,
                  {}};
    for (const double tau : grid) line.dev.push_back(model_adev(one, tau, u.rate));
    p.terms.push_back(std::move(line));
    if (k != b_index && inside(read_tau_s[k]))
      p.read_offs.push_back({read_tau_s[k], model_adev(one, read_tau_s[k], u.rate), read_label[k]});
  }
  if (fitted == 0) return p;
  if (fit && !fit->quantization_white && !in_model(node.ieee952[0]) && node.scale)
    model[0] = static_cast<double>(node.scale->angle_per_pulse) / std::sqrt(12.0);  // Q held there
  PlotLine sum{std::nullopt,
               fit ? fmt::format("IEEE-952 model, chi2/dof {:.2g}", fit->chi2_per_dof) : "IEEE-952 model (sum)",
               grid,
               {}};
  for (const double tau : grid) sum.dev.push_back(model_adev(model, tau, u.rate));
  if (node.ieee952[b_index].resolved && model[b_index] > 0) {  // B: the floor, at the sum's minimum within the points
    std::optional<std::size_t> floor;
    for (std::size_t k = 0; k < grid.size(); ++k) {
      if (grid[k] >= lo && grid[k] <= hi && (!floor || sum.dev[k] < sum.dev[*floor])) floor = k;
    }
    std::array<double, 5> b{};
    b[b_index] = model[b_index];
    if (floor) p.read_offs.push_back({grid[*floor], model_adev(b, grid[*floor], u.rate), read_label[b_index]});
  }
  p.terms.push_back(std::move(sum));
  return p;
}

}  // namespace gyrochar::decoding
