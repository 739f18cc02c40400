#include "node_report.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "confidence.hpp"
#include "html_report.hpp"
#include "plot_data.hpp"

namespace gyrochar::decoding {
namespace {

using html::Cell;
using html::number;

double tau0_of(const NodeView& node) { return node.sampling ? static_cast<double>(node.sampling->tau0_s) : 0.0; }
double run_s_of(const NodeView& node) {
  return node.have_status ? static_cast<double>(node.status.sample_count) * tau0_of(node) : 0.0;
}
bool fit_ok(const NodeView& node) {
  return node.ieee952_summary && node.ieee952_summary->status == protocol::Ieee952Status::ok;
}

// Deviation limit `l` is at tau i of the node: m tau0 is its tau.
bool at_limit_tau(const NodeView& node, const Limit& l, std::size_t i) {
  const double tau0 = tau0_of(node);
  const std::uint64_t m = i < node.taus.size() ? node.taus[i].m : 0;
  return tau0 > 0 && m != 0 && std::abs(static_cast<double>(m) * tau0 - l.tau_s) <= 1e-6 * l.tau_s;
}

LimitEstimate node_estimate(const NodeView& node, const Limit& l) {
  const auto wire_si = wire_per_si(node);  // wire value per SI value
  if (!wire_si) return no_estimate("the node's angle unit is not known (or pulses)");
  const double run_s = run_s_of(node);
  if (l.kind == Limit::Kind::term) {
    const char* letter = units::ieee952[l.term].letter;
    if (!node.ieee952_summary) return no_estimate("no fit summary yet");
    if (!fit_ok(node)) return no_estimate(fmt::format("fit {}", protocol::name(node.ieee952_summary->status)));
    const Ieee952View& t = node.ieee952[l.term];
    if (!t.in_model()) return no_estimate(fmt::format("{} not in the fitted model", letter));
    if (!t.resolved) return no_estimate(fmt::format("{} not resolved", letter));
    // The unconstrained estimate of the same fit where the node sends it (protocol version 5): the
    // shown value leans low where the fit clips another term at zero (docs/metrology.md,
    // "Acceptance limits"). Its square may be negative: the estimate is then 0, as the analyzer's.
    LimitEstimate e;
    if (const protocol::Ieee952UnconstrainedMsg* u = node.unconstrained_estimate(l.term)) {
      e = normal_estimate(std::max(static_cast<double>(u->value), 0.0) / *wire_si, u->uncertainty / *wire_si, run_s);
      e.kind = estimate_unconstrained;
    } else {
      const double v = static_cast<double>(t.value) / *wire_si;
      e = normal_estimate(v, v * t.rel_uncertainty, run_s);
      e.kind = estimate_shown;
    }
    return e;
  }
  if (!(tau0_of(node) > 0)) return no_estimate("tau0 not known yet");
  for (std::size_t i = 0; i < node.taus.size(); ++i) {
    if (!at_limit_tau(node, l, i)) continue;
    const TauView::Dev& d = l.kind == Limit::Kind::adev ? node.taus[i].adev : node.taus[i].mdev;
    if (!d.received || !d.valid) return no_estimate(fmt::format("no estimate at tau = {:g} s yet", l.tau_s));
    return deviation_estimate(static_cast<double>(d.dev) / *wire_si, d.edf, 0, run_s);
  }
  return no_estimate(fmt::format("the node has no tau of {:g} s (its taus are tau0 2^k)", l.tau_s));
}

std::string node_name(const NodeView& node) { return fmt::format("node 0x{:02X}", node.address); }

html::LogPlot node_plot(const NodePlot& p) {
  html::LogPlot plot;
  plot.title = p.title;
  plot.x_label = "tau [s]";
  plot.y_label = "ADEV, MDEV [" + p.rate_name + "]";
  const auto points = [](const std::vector<PlotPoint>& in) {
    std::vector<html::PlotPoint> out;
    for (const PlotPoint& q : in) out.push_back({q.tau_s, q.dev, q.ci});
    return out;
  };
  plot.series.push_back({"ADEV", "#1f5fbf", false, points(p.adev)});
  plot.series.push_back({"MDEV", "#c0602a", true, points(p.mdev)});
  // Q N B K R, a Markov term, the model's sum.
  static constexpr const char* term_colours[] = {"#8c564b", "#2a8a2a", "#9467bd", "#d62728", "#e377c2"};
  for (const PlotLine& l : p.terms)
    plot.lines.push_back({l.label,
                          l.term     ? term_colours[static_cast<int>(*l.term)]
                          : l.markov ? "#17becf"
                                     : "#222222",
                          false, l.tau_s, l.dev});
  if (p.truth) plot.lines.push_back({p.truth->label, "#7a3fa0", true, p.truth->tau_s, p.truth->dev});
  return plot;
}

}  // namespace

std::vector<Decision> node_decisions(const NodeView& node, const std::vector<Limit>& limits) {
  std::vector<Decision> out;
  for (const Limit& l : limits) {
    out.push_back(decide(l, node_estimate(node, l)));
    if (out.back().estimate.kind == estimate_shown)
      out.back().reason += " (judged by the shown value: the node sends no unconstrained estimate)";
  }
  return out;
}

bool limit_applies(const Limit& limit, const NodeView& node, std::size_t tau_index) {
  return limit.kind == Limit::Kind::term || at_limit_tau(node, limit, tau_index);
}

std::string verdict_csv_header(const std::vector<Limit>& limits) {
  std::string h = ",verdict";
  // Appended piece by piece: `"," + std::string` (an insert at the front) makes g++ 12 at -O3 warn
  // of an overlapping memcpy that cannot happen (-Wrestrict).
  for (const Limit& l : limits) {
    h += ',';
    h += csv_field(l.quantity() + " limit [" + l.unit + "]");
    h += decision_columns(l);
    if (l.kind == Limit::Kind::term) {
      h += ',';
      h += csv_field(l.quantity() + " estimate kind");
    }
  }
  return h;
}

std::size_t verdict_csv_columns(const std::vector<Limit>& limits) {
  std::size_t n = 1;
  for (const Limit& l : limits) n += l.kind == Limit::Kind::term ? 6 : 5;
  return n;
}

std::string verdict_csv_fields(const std::vector<Limit>& limits, const std::vector<Decision>& decisions,
                               const NodeView& node, std::size_t tau_index) {
  std::string f = std::string(",") + name(overall(decisions));
  for (std::size_t i = 0; i < limits.size(); ++i) {
    const Limit& l = limits[i];
    const bool applies = i < decisions.size() && limit_applies(l, node, tau_index);
    if (applies) {
      f += fmt::format(",{}", l.value_si / l.unit_si);
      f += decision_fields(l, &decisions[i]);
    } else {
      f += ',';  // as in verdict_csv_header()
      f += decision_fields(l, nullptr);
    }
    if (l.kind == Limit::Kind::term) {
      f += ',';
      if (applies) f += decisions[i].estimate.kind;
    }
  }
  return f;
}

std::string format_verdicts(const Decoder& decoder, const NodeFilter& shown, const std::vector<Limit>& limits) {
  std::string out;
  for (const auto& [address, node] : decoder.nodes())
    if (shown[address])
      out += fmt::format("\n{} (run {}):", node_name(node), format_run_length(run_s_of(node))) +
             acceptance_table(limits, node_decisions(node, limits));
  return out;
}

nlohmann::json acceptance_record(double time_s, const NodeView& node, const std::vector<Limit>& limits,
                                 const std::vector<Decision>& decisions) {
  nlohmann::json j = acceptance_json(limits, decisions);
  j["type"] = "acceptance";
  j["time"] = time_s;
  j["node"] = node.address;
  j["session"] = node.session;
  j["run_s"] = run_s_of(node);
  return j;
}

GyroSummary node_summary(const NodeView& node, const std::string& source, const std::vector<Limit>& limits) {
  GyroSummary g;
  g.source = source;
  g.node = fmt::format("0x{:02X}", node.address);
  g.run_s = run_s_of(node);
  g.samples = node.have_status ? node.status.sample_count : 0;
  if (node.ieee952_summary) {
    g.fit_status = protocol::name(node.ieee952_summary->status);
    g.chi2_per_dof = node.ieee952_summary->chi2_per_dof;
  }
  if (const auto wire_si = wire_per_si(node))
    for (std::size_t k = 0; k < 5; ++k) {
      const Ieee952View& t = node.ieee952[k];
      if (!t.received) continue;
      const double v = static_cast<double>(t.value) / *wire_si / units::ieee952[k].si;
      g.terms[k] = {t.in_model(), v, v * t.rel_uncertainty,
                    !t.in_model() ? "not in model"
                    : t.resolved  ? "resolved"
                                  : "not resolved"};
    }
  g.decisions = node_decisions(node, limits);
  return g;
}

namespace {

// A correlation time's 68 % interval, "68 %: 101 .. 286 s"; empty for the other parameters.
std::string time_note(protocol::FitParameter kind, const FitModelRow::Parameter& q) {
  if (kind != protocol::FitParameter::markov_tc && kind != protocol::FitParameter::filter_tf) return {};
  return correlation_time_interval(q.value, q.rel_uncertainty * q.value);
}

// The model beyond the five terms (protocol version 4: Markov terms, the sensor's filter,
// sinusoids) with each parameter's uncertainty and the runner-up, as the terminal view gives them.
void model_table(html::Document& doc, const NodeView& node, const Units& u, const std::string& id) {
  const std::optional<FitModelRow> m = fit_model_row(node, u);
  if (!m || !node.ieee952_summary) return;
  const protocol::Ieee952Status status = node.ieee952_summary->status;
  if (status != protocol::Ieee952Status::ok && status != protocol::Ieee952Status::rejected) return;
  if (m->state != Viewed::shown) {
    doc.paragraph(fmt::format("Model beyond the five terms: {} (its pages {})", name(m->state),
                              m->state == Viewed::pending ? "are still arriving" : "were lost"),
                  "note");
    return;
  }
  std::vector<std::vector<Cell>> rows;
  const auto add_row = [&](const std::string& term, protocol::FitParameter kind, std::uint8_t j, const std::string& unit,
                           bool with_status) {
    const FitModelRow::Parameter& q = m->parameters[protocol::fit_parameter_position(kind, j)];
    rows.push_back({{term, {}, "text"},
                    number(q.value),
                    q.rel_uncertainty > 0 ? number(q.value * q.rel_uncertainty) : Cell{},
                    {unit, {}, "text"},
                    {with_status ? (q.resolved ? "resolved" : "not resolved") : time_note(kind, q), {}, "text"}});
  };
  using protocol::FitParameter;
  for (std::uint8_t j = 0; j < m->markov; ++j) {
    add_row(fmt::format("Markov {} sigma", j + 1), FitParameter::markov_sigma, j, u.rate_name, true);
    add_row(fmt::format("Markov {} Tc", j + 1), FitParameter::markov_tc, j, "s", false);
  }
  if (m->bandwidth) add_row("sensor filter Tf", FitParameter::filter_tf, 0, "s", false);
  for (std::uint8_t j = 0; j < m->sinusoids; ++j) {
    add_row(fmt::format("sinusoid {} amplitude", j + 1), FitParameter::sinusoid_amplitude, j, u.rate_name, true);
    add_row(fmt::format("sinusoid {} frequency", j + 1), FitParameter::sinusoid_frequency, j, "Hz", false);
  }
  std::string title = rows.empty() ? "Model: the five terms" : "Model beyond the five terms";
  if (m->bandwidth_excluded_below_tau_s && *m->bandwidth_excluded_below_tau_s > 0)
    title += fmt::format("; taus below {:.4g} s left out (sensor filter)", *m->bandwidth_excluded_below_tau_s);
  if (const auto& r = m->runner_up)
    title += fmt::format("; runner-up: {} Markov, {} sinusoids{}, criterion {:+.3g}", r->runner_up_markov,
                         r->runner_up_sinusoids, r->runner_up_bandwidth ? ", filter" : "", r->criterion_margin);
  if (rows.empty()) doc.paragraph(title, "model");
  else doc.table(id + "-model", title, {"term", "value", "standard uncertainty", "unit", "status"}, rows);
}

// The dynamic Allan deviation: the latest window's ADEV at each window tau, as the terminal view.
void window_table(html::Document& doc, const NodeView& node, const Units& u, const std::string& id) {
  if (node.window_taus == 0 || node.windows.empty()) return;
  const WindowView& w = node.windows.rbegin()->second;
  std::vector<std::vector<Cell>> rows;
  for (std::size_t i = 0; i < w.adev.size(); ++i)  // window tau i is the node's tau i
    rows.push_back({node.tau_s(i) > 0 ? number(node.tau_s(i)) : Cell{},
                    w.received[i] && w.adev[i] > 0 ? number(w.adev[i] * u.rate) : Cell{}});
  doc.table(id + "-window",
            fmt::format("Dynamic ADEV [{}]: the latest window, {}{} ({} windows received)", u.rate_name, w.window,
                        w.gaps ? fmt::format(", {} gaps", w.gaps) : "", node.windows.size()),
            {"tau [s]", "adev"}, rows);
}

}  // namespace

std::string decode_html(const Decoder& decoder, const InputCounters& input, const NodeFilter& shown, const DisplayRate& rate,
                        ConfidenceIntervals& intervals, const std::vector<Limit>& limits, const std::string& command) {
  html::Document doc("gyrochar report: " + input.source);
  doc.heading("Provenance", 2, "provenance");
  doc.facts({{"input", input.source},
             {"frames", fmt::format("{}", input.frames)},
             {"decoder time", fmt::format("{:g} s", input.started ? input.now_s - input.first_s : 0.0)},
             {"bus", input.bus.empty() ? "a log" : input.bus},
             {"command", command},
             {"software", html::software_version()},
             {"written", html::utc_now()}},
            "provenance-facts");
  for (const auto& [address, node] : decoder.nodes()) {
    if (!shown[address]) continue;
    const Units u = units_for(node, rate);
    const std::string id = fmt::format("node-{:02x}", address);
    doc.heading(node_name(node), 2, id);
    const LinkHealth& h = node.health;
    doc.facts(
        {{"node", fmt::format("0x{:02X}, session {}", address, node.session)},
         {"configuration", node.config ? fmt::format("hash 0x{:08X}, report every {} ms", node.config->config_hash,
                                                     node.config->report_period_ms)
                                       : "not received"},
         {"tau0", node.sampling
                      ? fmt::format("{:g} s, stride factor {}", node.sampling->tau0_s, node.sampling->stride_factor)
                      : "not received"},
         {"scale", node.scale ? fmt::format("{:g} {} a pulse, input {}", node.scale->angle_per_pulse,
                                            protocol::name(node.scale->angle_unit), protocol::name(node.scale->input_source))
                              : "not received"},
         {"samples", node.have_status ? fmt::format("{} ({})", node.status.sample_count, format_run_length(run_s_of(node)))
                                      : "no status yet"},
         {"gaps", fmt::format("{} sample gaps, {} lost edges", node.faults.sample_gaps, node.faults.lost_edges)},
         {"link", fmt::format("{} reports complete, {} incomplete, {} lost; {} frames missing; {} restarts",
                              h.reports_complete, h.reports_incomplete, h.reports_lost, h.frames_missing, h.restarts)}},
        id + "-provenance");
    if (!limits.empty()) html::verdict_section(doc, limits, node_decisions(node, limits), id + "-verdicts", 3);
    const NodePlot p = plot_data(node, rate, intervals);
    html::LogPlot plot = node_plot(p);
    for (const Limit& l : limits)
      if (l.kind == Limit::Kind::adev && u.known && !u.pulses)
        if (const auto wire_si = wire_per_si(node))
          plot.limits.push_back({l.tau_s, l.value_si * *wire_si * u.rate, l.quantity() + " limit"});
    doc.raw(html::svg_log_plot(plot) + "\n");
    // The taus, in display units, with their intervals at the view's confidence.
    std::vector<std::vector<Cell>> rows;
    const double tau0 = tau0_of(node);
    for (const TauView& t : node.taus) {
      if (t.m == 0) continue;
      std::vector<Cell> row{number(tau0 > 0 ? static_cast<double>(t.m) * tau0 : NAN),
                            {fmt::format("{}", t.m), fmt::format("{}", t.m), {}},
                            t.n ? Cell{fmt::format("{}", t.n), fmt::format("{}", t.n), {}} : Cell{}};
      for (const TauView::Dev* d : {&t.adev, &t.mdev}) {
        if (!d->received || !d->valid) {
          row.insert(row.end(), {Cell{}, Cell{}, Cell{}, Cell{}, Cell{}});
          continue;
        }
        const double v = static_cast<double>(d->dev) * u.rate;
        const Interval ci = intervals(v, d->edf);
        row.insert(row.end(), {number(v),
                               ci.valid ? number(ci.low) : Cell{},
                               ci.valid ? number(ci.high) : Cell{},
                               d->edf > 0 ? number(d->edf) : Cell{},
                               {protocol::name(d->noise), {}, "text"}});
      }
      rows.push_back(std::move(row));
    }
    doc.table(id + "-taus",
              fmt::format("ADEV and MDEV [{}], intervals at {:g} %", u.rate_name, 100 * intervals.confidence()),
              {"tau [s]", "m", "n", "adev", "ci low", "ci high", "edf", "noise", "mdev", "ci low", "ci high", "edf",
               "noise"},
              rows);
    // The fit.
    std::vector<std::vector<Cell>> terms;
    for (std::size_t k = 0; k < 5; ++k) {
      const Ieee952View& t = node.ieee952[k];
      const double v = static_cast<double>(t.value) * u.ieee[k];
      terms.push_back({{units::ieee952[k].letter, {}, "text"},
                       t.in_model() ? number(v) : Cell{},
                       t.in_model() ? number(v * t.rel_uncertainty) : Cell{},
                       {u.ieee_name[k], {}, "text"},
                       {!t.received     ? "not received"
                        : !t.in_model() ? "not in model"
                        : t.resolved    ? "resolved"
                                        : "not resolved",
                        {},
                        "text"}});
    }
    const auto& s = node.ieee952_summary;
    doc.table(id + "-fit",
              s ? fmt::format("IEEE-952 fit: {}, chi2/dof {:.3g}, {} points, quantization {}", protocol::name(s->status),
                              s->chi2_per_dof, s->points, s->quantization_white ? "white" : "not white (Q held)")
                : std::string("IEEE-952 fit: no summary received"),
              {"term", "value", "standard uncertainty", "unit", "status"}, terms);
    model_table(doc, node, u, id);
    window_table(doc, node, u, id);
    for (const std::string& note : p.notes) doc.paragraph(note, "note");
  }
  return doc.finish();
}

}  // namespace gyrochar::decoding
