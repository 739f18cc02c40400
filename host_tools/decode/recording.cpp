#include "recording.hpp"

#include <fmt/compile.h>

#include <nlohmann/json.hpp>

#include <algorithm>

#include "gyrochar/ieee952.hpp"

namespace gyrochar::decoding {

using namespace protocol;
using Json = nlohmann::ordered_json;

namespace {

// Value or nothing: CSV leaves the field empty, JSON writes null.
template <class T>
Json json_or_null(bool known, T value) {
  return known ? Json(value) : Json(nullptr);
}
template <class T>
Json json_or_null(const std::optional<T>& value) {
  return value ? Json(*value) : Json(nullptr);
}

/// Column name stem of parameter page k: markov1_sigma, markov1_tc_s, filter_tf_s,
/// sinusoid1_amplitude, sinusoid1_frequency_hz, ...
std::string parameter_column(std::size_t k) {
  const FitParameterSlot p = fit_parameter_slot(k);
  const unsigned n = p.index + 1u;
  switch (p.parameter) {
    case FitParameter::markov_sigma: return fmt::format("markov{}_sigma", n);
    case FitParameter::markov_tc: return fmt::format("markov{}_tc_s", n);
    case FitParameter::filter_tf: return "filter_tf_s";
    case FitParameter::sinusoid_amplitude: return fmt::format("sinusoid{}_amplitude", n);
    case FitParameter::sinusoid_frequency: return fmt::format("sinusoid{}_frequency_hz", n);
  }
  return "invalid";
}
/// A frequency is given to the fit, not fitted: no uncertainty column.
bool has_uncertainty(std::size_t k) { return fit_parameter_slot(k).parameter != FitParameter::sinusoid_frequency; }

/// The model's columns after window_gaps (version 4): fit_model (shown, pending, missing),
/// the counts, then each parameter page's value, relative uncertainty and resolved flag.
std::string model_header() {
  std::string h = ",fit_model,fit_markov_terms,fit_sinusoids,fit_filter";
  for (std::size_t k = 0; k < fit_parameter_pages; ++k) {
    const std::string c = parameter_column(k);
    h += "," + c;
    if (has_uncertainty(k)) h += "," + c + "_rel_uncertainty";
    if (has_resolved(fit_parameter_slot(k).parameter)) h += "," + c + "_resolved";
  }
  return h;
}
std::size_t model_columns() {
  std::size_t n = 4;
  for (std::size_t k = 0; k < fit_parameter_pages; ++k)
    n += 1 + (has_uncertainty(k) ? 1 : 0) + (has_resolved(fit_parameter_slot(k).parameter) ? 1 : 0);
  return n;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// CSV

CsvWriter::CsvWriter(std::FILE* out, double confidence, const std::string& extra_header, std::size_t extra_columns)
    : out_(out), confidence_(confidence), extra_columns_(extra_columns) {
  std::fputs(
      "time_s,node,seq,tau_index,m,tau_s,n,"
      "adev,adev_low,adev_high,adev_edf,adev_noise,adev_status,"
      "mdev,mdev_low,mdev_high,mdev_edf,mdev_noise,mdev_status,"
      "rate_unit,ci_level,session,"
      "fit_status,fit_chi2_per_dof,fit_points,fit_quantization_white,"
      "fit_avar_excluded_below_tau_s,fit_mvar_excluded_below_tau_s,"
      "type,window,window_start_s,window_end_s,window_gaps",
      out_);
  std::fputs((model_header() + extra_header + "\n").c_str(), out_);
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
  fmt::format_to(out, FMT_COMPILE("{}"), r.gaps);
  line_.append(std::string(model_columns() + extra_columns_, ','));  // a window row has no fit, no verdict
  line_.push_back('\n');
  std::fwrite(line_.data(), 1, line_.size(), out_);
}

void CsvWriter::row(const TauRow& r, const Units& units, std::string_view extra) {
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
  fmt::format_to(out, FMT_COMPILE("tau,,,,,"));
  model_fields(r.fit_model);
  line_.resize(line_.size() - 1);  // the last field's comma
  line_.append(extra);
  for (std::size_t k = extra.empty() ? extra_columns_ : 0; k > 0; --k) line_.push_back(',');  // none given
  line_.push_back('\n');
  std::fwrite(line_.data(), 1, line_.size(), out_);
}

void CsvWriter::model_fields(const std::optional<FitModelRow>& model) {
  const bool shown = model && model->state == Viewed::shown;
  field(model.has_value(), model ? name(model->state) : "");
  field(shown, shown ? model->markov : 0u);
  field(shown, shown ? model->sinusoids : 0u);
  field(shown, shown && model->bandwidth ? "true" : "false");
  for (std::size_t k = 0; k < fit_parameter_pages; ++k) {
    const FitModelRow::Parameter p = shown ? model->parameters[k] : FitModelRow::Parameter{};
    field(p.known, p.value);
    if (has_uncertainty(k)) field(p.known, p.rel_uncertainty);
    if (has_resolved(fit_parameter_slot(k).parameter)) field(p.known, p.resolved ? "true" : "false");
  }
}

// ---------------------------------------------------------------------------------------------
// JSON lines

void JsonlWriter::line(const std::string& text) {
  std::fwrite(text.data(), 1, text.size(), out_);
  std::fputc('\n', out_);
}

namespace {

Json candidate_json(unsigned markov, unsigned sinusoids, bool bandwidth) {
  return Json{{"markov", markov}, {"sinusoids", sinusoids}, {"bandwidth", bandwidth}};
}

/// A parameter as the analyzer's JSON has it: value, uncertainty (absolute), unit (and resolved).
Json parameter_json(const FitModelRow::Parameter& p, const std::string& unit, bool with_resolved) {
  Json j{{"value", p.value},
         {"uncertainty", p.rel_uncertainty > 0 ? Json(p.rel_uncertainty * p.value) : Json(nullptr)},
         {"unit", unit}};
  if (with_resolved) j["resolved"] = p.resolved;
  return j;
}

/// A correlation time as parameter_json() gives it, with its 68 % interval (ci_low, ci_high:
/// tc_interval(), as the analyzer's; null where the uncertainty is not known).
Json correlation_time_json(const FitModelRow::Parameter& p) {
  Json j = parameter_json(p, "s", false);
  const auto [low, high] = tc_interval(p.value, p.rel_uncertainty * p.value);
  j["ci_low"] = high > 0 ? Json(low) : Json(nullptr);
  j["ci_high"] = high > 0 ? Json(high) : Json(nullptr);
  return j;
}

/// The model beyond the five terms (version 4) in the fit object: "model_status", and when shown
/// "markov", "sinusoids", "bandwidth", "bandwidth_excluded_below_tau_s", "model", "runner_up" in
/// the analyzer's shape (the uncertainty absolute); null when not shown.
void add_model_json(Json& fit, const std::optional<FitModelRow>& model, const Units& units) {
  if (!model) return;
  fit["model_status"] = name(model->state);
  if (model->state != Viewed::shown) {
    for (const char* key : {"markov", "sinusoids", "bandwidth", "bandwidth_excluded_below_tau_s", "model", "runner_up"})
      fit[key] = nullptr;
    return;
  }
  const auto page = [&](FitParameter p, std::uint8_t index) { return model->parameters[fit_parameter_position(p, index)]; };
  Json markov = Json::array(), sinusoids = Json::array();
  for (std::uint8_t j = 0; j < model->markov; ++j)
    markov.push_back({{"sigma", parameter_json(page(FitParameter::markov_sigma, j), units.rate_name, true)},
                      {"tc", correlation_time_json(page(FitParameter::markov_tc, j))}});
  for (std::uint8_t j = 0; j < model->sinusoids; ++j)
    sinusoids.push_back({{"amplitude", parameter_json(page(FitParameter::sinusoid_amplitude, j), units.rate_name, true)},
                         {"frequency", parameter_json(page(FitParameter::sinusoid_frequency, j), "Hz", false)}});
  fit["markov"] = std::move(markov);
  fit["sinusoids"] = std::move(sinusoids);
  fit["bandwidth"] = model->bandwidth ? Json{{"tf", correlation_time_json(page(FitParameter::filter_tf, 0))}}
                                      : Json(nullptr);
  fit["bandwidth_excluded_below_tau_s"] = json_or_null(model->bandwidth_excluded_below_tau_s);
  fit["model"] = candidate_json(model->markov, model->sinusoids, model->bandwidth);
  if (const auto& r = model->runner_up) {
    Json j = candidate_json(r->runner_up_markov, r->runner_up_sinusoids, r->runner_up_bandwidth);
    j["criterion_margin"] = r->criterion_margin;
    fit["runner_up"] = std::move(j);
  } else {
    fit["runner_up"] = nullptr;
  }
}

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

}  // namespace

template <class T>
void JsonlWriter::member(const char* key, bool known, T value) {
  if (known) fmt::format_to(fmt::appender(line_), FMT_COMPILE(",\"{}\":{}"), key, value);
  else fmt::format_to(fmt::appender(line_), FMT_COMPILE(",\"{}\":null"), key);
}

// The tau rows are the bulk of a recording: written with fmt, not built as JSON objects (5x faster).
// Every string in them is an enumeration or unit name (plain ASCII, nothing to escape) and every
// number is finite; fmt's shortest round-trip form of a double is a valid JSON number.
void JsonlWriter::row(const TauRow& r, const Units& units) {
  line_.clear();
  const auto out = fmt::appender(line_);
  fmt::format_to(out,
                 FMT_COMPILE("{{\"type\":\"tau\",\"time_s\":{:.6f},\"node\":{},\"session\":{},\"seq\":{},\"tau_index\":{}"),
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
    if (c->status != DevCell::Status::missing) fmt::format_to(out, FMT_COMPILE(",\"noise\":\"{}\"}}"), name(c->noise));
    else fmt::format_to(out, FMT_COMPILE(",\"noise\":null}}"));
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
    const bool fitted = p.in_model();
    ieee[units::ieee952[k].letter] = !p.received ? Json(nullptr)
                                                 : Json{{"fitted", fitted},
                                                        {"resolved", p.resolved},
                                                        {"value", json_or_null(fitted, p.value * units.ieee[k])},
                                                        {"unit", units.ieee_name[k]},
                                                        {"rel_uncertainty", json_or_null(fitted, p.rel_uncertainty)}};
    // What a verdict judges, as gyrochar-analyze's JSON gives it (protocol version 5): the estimate
    // (0 where the unconstrained square is negative) and, signed, the root the node sent.
    if (const Ieee952UnconstrainedMsg* u = node.unconstrained_estimate(k))
      ieee[units::ieee952[k].letter]["unconstrained"] = {{"value",
                                                          std::max(static_cast<double>(u->value), 0.0) * units.ieee[k]},
                                                         {"uncertainty", u->uncertainty * units.ieee[k]},
                                                         {"signed", static_cast<double>(u->value) * units.ieee[k]}};
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
    add_model_json(fit, fit_model_row(node, units), units);
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
  line(Json{{"type", "event"}, {"time_s", time_s}, {"node", node.address}, {"event", name(e)}, {"session", node.session}}
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
            {"remote_frames", input.remote_frames},
            {"other_frames", decoder.other_frames()},
            {"rejected_frames", decoder.rejected_frames()},
            {"time_backwards", input.time_backwards},
            {"first_s", json_or_null(input.started, input.first_s)},
            {"last_s", json_or_null(input.started, input.now_s)},
            {"nodes", nodes}}
           .dump());
}

}  // namespace gyrochar::decoding
