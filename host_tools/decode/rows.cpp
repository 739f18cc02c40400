#include "rows.hpp"

#include <cmath>

namespace gyrochar::decoding {

using namespace protocol;

std::optional<double> fit_excluded_below_tau_s(const NodeView& node, std::size_t k) {
  if (!node.ieee952_summary || k > 1) return std::nullopt;
  const std::uint8_t c = node.ieee952_summary->excluded_below_log2_m[k];
  if (c == 0) return 0.0;
  if (!node.sampling) return std::nullopt;
  return static_cast<double>(node.sampling->tau0_s) * std::ldexp(1.0, c);
}

const char* name(DevCell::Status s) {
  switch (s) {
    case DevCell::Status::ok: return "ok";
    case DevCell::Status::invalid: return "invalid";
    case DevCell::Status::missing: return "missing";
  }
  return "invalid";
}

ViewedRow viewed_row(const NodeView& node, std::size_t i) {
  const TauView& t = node.taus[i];
  const std::uint64_t latest = node.report;
  const auto from = [](const TauView::Dev& d, std::uint64_t report) { return d.received && d.report == report; };
  const bool in_latest = from(t.adev, latest) || from(t.mdev, latest);
  const std::uint64_t row = in_latest || !node.report_open || latest == 0 ? latest : latest - 1;
  const auto viewed = [&](const TauView::Dev& d) {
    if (row == 0 || from(d, row)) return Viewed::shown;
    return row == latest && node.report_open ? Viewed::pending : Viewed::missing;
  };
  return {viewed(t.adev), viewed(t.mdev)};
}

const char* name(Viewed v) {
  switch (v) {
    case Viewed::shown: return "shown";
    case Viewed::missing: return "missing";
    case Viewed::pending: return "pending";
  }
  return "invalid";
}

std::optional<FitModelRow> fit_model_row(const NodeView& node, const Units& units) {
  if (!node.ieee952_summary || node.schedule_version() < 4) return std::nullopt;
  const std::uint64_t cycle = node.ieee952_summary_cycle;
  const FitModelView* pages = node.fit_model.cycle == cycle            ? &node.fit_model
                              : node.previous_fit_model.cycle == cycle ? &node.previous_fit_model
                                                                       : nullptr;
  FitModelRow row;
  if (pages == nullptr || !pages->complete()) {
    // The summary's cycle is still being received unless its last report has closed.
    const bool last_closed = node.reports_made % slow_cycle_reports == slow_cycle_reports - 1 && !node.report_open;
    row.state = node.cycle() == cycle && !last_closed ? Viewed::pending : Viewed::missing;
    return row;
  }
  const Ieee952ModelMsg& m = *pages->model;
  row.state = Viewed::shown;
  row.markov = m.markov;
  row.sinusoids = m.sinusoids;
  row.bandwidth = m.bandwidth;
  if (m.bandwidth_excluded_below_log2_m == 0) row.bandwidth_excluded_below_tau_s = 0.0;
  else if (node.sampling)
    row.bandwidth_excluded_below_tau_s = static_cast<double>(node.sampling->tau0_s) *
                                         std::ldexp(1.0, m.bandwidth_excluded_below_log2_m);
  if (m.runner_up) row.runner_up = m;
  for (std::size_t k = 0; k < fit_parameter_pages; ++k) {
    if (!pages->in_model(k)) continue;
    const Ieee952ParameterMsg& p = *pages->parameters[k];
    const bool rate = p.parameter == FitParameter::markov_sigma || p.parameter == FitParameter::sinusoid_amplitude;
    row.parameters[k] = {true, static_cast<double>(p.value) * (rate ? units.rate : 1.0), p.rel_uncertainty, p.resolved};
  }
  return row;
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

void tau_rows(const NodeView& node, const Decoder::Report& report, const Units& units, ConfidenceIntervals& intervals,
              std::vector<TauRow>& out) {
  const std::optional<FitModelRow> model = fit_model_row(node, units);
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
    r.adev = dev_cell(t.adev, report.received(Slot::adev, i), units.rate, intervals);
    r.mdev = dev_cell(t.mdev, report.received(Slot::mdev, i), units.rate, intervals);
    r.fit = node.ieee952_summary;
    r.fit_excluded_below_tau_s = {fit_excluded_below_tau_s(node, 0), fit_excluded_below_tau_s(node, 1)};
    r.fit_model = model;
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

}  // namespace gyrochar::decoding
