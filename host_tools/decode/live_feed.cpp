#include "live_feed.hpp"

#include <nlohmann/json.hpp>

#include <cmath>

#include "display_units.hpp"
#include "node_report.hpp"
#include "plot_data.hpp"

namespace gyrochar::decoding {

using Json = nlohmann::ordered_json;

double wall_ms() {
  return std::chrono::duration<double, std::milli>(std::chrono::system_clock::now().time_since_epoch()).count();
}

namespace {

// A finite number, else null (a line's sampled value can leave a double's range: never "inf").
Json number(double v) { return std::isfinite(v) ? Json(v) : Json(nullptr); }

Json numbers(const std::vector<double>& values) {
  Json a = Json::array();
  for (const double v : values) a.push_back(number(v));
  return a;
}

Json line_json(const PlotLine& l, const char* kind) {
  return Json{{"kind", kind}, {"label", l.label}, {"tau_s", numbers(l.tau_s)}, {"dev", numbers(l.dev)}};
}

Json plot_json(const NodePlot& p) {
  Json lines = Json::array();
  for (const PlotLine& l : p.terms)
    lines.push_back(line_json(l, l.term     ? units::ieee952[static_cast<std::size_t>(*l.term)].letter
                                 : l.markov ? "markov"
                                            : "model"));
  if (p.truth) lines.push_back(line_json(*p.truth, "truth"));
  Json read_offs = Json::array();
  for (const ReadOffPoint& r : p.read_offs)
    read_offs.push_back(Json{{"tau_s", r.tau_s}, {"dev", number(r.dev)}, {"label", r.label}});
  Json heat(nullptr);
  if (p.dynamic) {
    Json columns = Json::array();
    for (const HeatMap::Column& c : p.dynamic->columns)
      columns.push_back(Json{{"start_s", c.start_s}, {"end_s", c.end_s}, {"value", numbers(c.value)}});
    heat = Json{{"title", p.dynamic->title}, {"unit", p.dynamic->unit}, {"tau_s", p.dynamic->tau_s}, {"columns", columns}};
  }
  return Json{{"title", p.title}, {"rate_unit", p.rate_name}, {"tau_min_s", p.tau_min_s}, {"tau_max_s", p.tau_max_s},
              {"lines", lines},   {"notes", p.notes},         {"read_offs", read_offs},   {"heat", heat}};
}

// The simulated gyro's terms in the units the node's fit is shown in; null where unknown.
Json truth_json(const NodeView& v, const Units& u, const TrueTerms* t) {
  const std::optional<double> per_si = t ? wire_per_si(v) : std::nullopt;
  if (!per_si) return nullptr;
  Json j = Json::object();
  for (std::size_t k = 0; k < 5; ++k) j[units::ieee952[k].letter] = number(t->qnbkr[k] * *per_si * u.ieee[k]);
  Json markov = Json::array();
  for (const auto& [sigma, tc] : t->markov)
    markov.push_back(Json{{"sigma", number(sigma * *per_si * u.rate)}, {"tc_s", tc}});
  j["markov"] = markov;
  return j;
}

}  // namespace

LiveFeed::LiveFeed(std::string program, double refresh_s, double confidence, const TrueTermsByNode* truth)
    : program_(std::move(program)),
      refresh_s_(refresh_s),
      truth_(truth),
      memory_(open_memstream(&buffer_, &size_)),
      jsonl_(memory_, confidence) {
  if (memory_ == nullptr) throw std::bad_alloc();
}

LiveFeed::~LiveFeed() {
  std::fclose(memory_);
  std::free(buffer_);
}

std::string LiveFeed::capture() {
  std::fflush(memory_);
  std::string text(buffer_, size_);
  std::rewind(memory_);
  if (!text.empty() && text.back() == '\n') text.pop_back();
  return text;
}

void LiveFeed::report_closed(const NodeView& node, const std::vector<TauRow>& rows, const Units& units) {
  for (const TauRow& r : rows) jsonl_.row(r, units);
  std::string lines = capture();
  for (char& c : lines)
    if (c == '\n') c = ',';  // one record a line: records separated by commas
  Latest& l = latest_[node.address];
  l.rows = "[" + lines + "]";
  l.received_ms = wall_ms();
}

std::string LiveFeed::snapshot(Session& session) {
  const Decoder& decoder = session.decoder();
  const InputCounters& in = session.input();
  const SessionOptions& o = session.options();
  std::string nodes;
  for (const auto& [address, v] : decoder.nodes()) {
    if (!o.shown[address]) continue;
    const Units units = units_for(v, o.rate_unit);
    const Decoder::Report* report = decoder.report(address);
    jsonl_.report(report ? report->start_s : in.now_s, v, report ? report->seq : 0, units);
    const std::string record = capture();
    const TrueTerms* truth = nullptr;
    if (truth_ != nullptr)
      if (const auto it = truth_->find(address); it != truth_->end()) truth = &it->second;
    const auto latest = latest_.find(address);
    Json extra{{"rows_received_ms", latest != latest_.end() ? Json(latest->second.received_ms) : Json(nullptr)},
               {"truth", truth_json(v, units, truth)},
               {"plot", plot_json(plot_data(v, o.rate_unit, session.intervals(), truth))},
               {"acceptance", limits_ != nullptr && !limits_->empty()
                                  ? Json(acceptance_record(in.now_s, v, *limits_, node_decisions(v, *limits_)))
                                  : Json(nullptr)}};
    std::string node = extra.dump();  // {"rows_received_ms":...}: the rows and the record go first
    node.erase(0, 1);
    nodes += nodes.empty() ? "{" : ",{";
    nodes += "\"node\":" + std::to_string(address) + ",\"label\":\"" + fmt::format("0x{:02X}", address) + "\"";
    nodes += ",\"rows\":" + (latest != latest_.end() ? latest->second.rows : std::string("[]"));
    nodes += ",\"report\":" + record + "," + node;
  }
  const Json top{{"program", program_},
                 {"source", in.source},
                 {"sent_ms", wall_ms()},
                 {"refresh_s", refresh_s_},
                 {"ci_level", o.confidence},
                 {"elapsed_s", in.started ? Json(in.now_s - in.first_s) : Json(nullptr)},
                 {"input",
                  {{"lines", in.lines},
                   {"malformed_lines", in.malformed_lines},
                   {"frames", in.frames},
                   {"remote_frames", in.remote_frames},
                   {"other_frames", decoder.other_frames()},
                   {"rejected_frames", decoder.rejected_frames()},
                   {"time_backwards", in.time_backwards},
                   {"bus", in.bus}}}};
  std::string text = top.dump();
  text.pop_back();  // the closing brace: the nodes follow
  return text + ",\"nodes\":[" + nodes + "]}";
}

}  // namespace gyrochar::decoding
