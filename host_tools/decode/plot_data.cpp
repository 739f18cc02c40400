#include "plot_data.hpp"

#include <fmt/format.h>

#include <cmath>
#include <numbers>
#include <tuple>

#include "gyrochar/ieee952.hpp"

namespace gyrochar::decoding {

using namespace protocol;

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

// The fit of the node as core's Ieee952Fit (wire units): the five terms `qnbkr` and the model
// beyond them, for fitted_variance().
Ieee952Fit wire_fit(const std::array<double, 5>& qnbkr, const FitModelRow& m, double rate) {
  Ieee952Fit f;
  for (std::size_t k = 0; k < 5; ++k) f.p[k].value = qnbkr[k];
  const auto page = [&](FitParameter p, std::uint8_t j) { return m.parameters[fit_parameter_position(p, j)].value; };
  f.n_markov = std::min<std::size_t>(m.markov, max_markov);
  for (std::uint8_t j = 0; j < f.n_markov; ++j) {
    f.markov[j].sigma.value = page(FitParameter::markov_sigma, j) / rate;
    f.markov[j].tc_s = page(FitParameter::markov_tc, j);
  }
  f.n_sinusoids = std::min<std::size_t>(m.sinusoids, max_sinusoids);
  for (std::uint8_t j = 0; j < f.n_sinusoids; ++j) {
    f.sinusoids[j].amplitude.value = page(FitParameter::sinusoid_amplitude, j) / rate;
    f.sinusoids[j].frequency_hz = page(FitParameter::sinusoid_frequency, j);
  }
  if (m.bandwidth) f.bandwidth_tc_s = page(FitParameter::filter_tf, 0);
  return f;
}

// ADEV of a fit's exact sampled AVAR at tau (>= tau0), in display units: between the integer
// averaging factors around tau / tau0, interpolated in log-log (no steps at the shortest taus).
double fit_adev(const Ieee952Fit& f, double tau_s, double tau0_s, double rate) {
  const double x = std::max(1.0, tau_s / tau0_s), lo = std::floor(x);
  const auto avar = [&](double m) {
    return std::max(0.0, fitted_variance(f, Stat::avar, static_cast<std::uint64_t>(m), tau0_s));
  };
  const double v_lo = avar(lo), v_hi = avar(lo + 1);
  const double w = std::log(x / lo) / std::log((lo + 1) / lo);
  const double v = v_lo > 0 && v_hi > 0 ? std::exp((1 - w) * std::log(v_lo) + w * std::log(v_hi)) : v_lo;
  return std::sqrt(v) * rate;
}

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

// The simulated gyro's curve in display units over `grid` (its exact sampled curve from tau0 on
// with Markov terms or sinusoids, as the fitted model's); nothing while the node's units are unknown.
std::optional<PlotLine> truth_line(const NodeView& node, const TrueTerms& truth, const NodePlot& p,
                                   const std::vector<double>& grid, const Units& u) {
  const std::optional<double> to_wire = wire_per_si(node);
  if (!to_wire) return std::nullopt;
  // The truth as a fit in wire units; with Markov terms or sinusoids its exact sampled curve
  // (from tau0 on), as the fitted model's below.
  Ieee952Fit f;
  std::array<double, 5> wire{};
  for (std::size_t k = 0; k < 5; ++k) f.p[k].value = wire[k] = truth.qnbkr[k] * *to_wire;
  for (const auto& [sigma, tc] : truth.markov)
    if (f.n_markov < max_markov) f.markov[f.n_markov].sigma.value = sigma * *to_wire, f.markov[f.n_markov++].tc_s = tc;
  for (const auto& [amplitude, hz] : truth.sinusoids)
    if (f.n_sinusoids < max_sinusoids)
      f.sinusoids[f.n_sinusoids].amplitude.value = amplitude * *to_wire, f.sinusoids[f.n_sinusoids++].frequency_hz = hz;
  const bool beyond = (f.n_markov > 0 || f.n_sinusoids > 0) && node.sampling;
  const double tau0_s = node.sampling ? static_cast<double>(node.sampling->tau0_s) : 0.0;
  PlotLine line{std::nullopt,
                false,
                "simulated gyro (truth)",
                beyond ? log_grid(std::max(p.tau_min_s, tau0_s), p.tau_max_s) : grid,
                {}};
  for (const double tau : line.tau_s)
    line.dev.push_back(beyond ? fit_adev(f, tau, tau0_s, u.rate) : model_adev(wire, tau, u.rate));
  return line;
}

// The notes on what the node's fit says, before any model line is drawn; false when no model
// line is to be drawn (the fit rejected or not made).
bool fit_notes(const NodeView& node, NodePlot& p) {
  const auto& fit = node.ieee952_summary;
  if (fit && fit->status == Ieee952Status::rejected) {
    p.notes.push_back(fmt::format("IEEE-952 fit REJECTED (chi2/dof {:.3g}):", fit->chi2_per_dof));
    p.notes.push_back("the model does not describe the curve");
    return false;
  }
  if (fit && fit->status != Ieee952Status::ok) {
    p.notes.push_back(
        fmt::format("no IEEE-952 fit: {}", fit->status == Ieee952Status::too_few_points ? "too few points" : "singular"));
    return false;
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
  return true;
}

// Where each term's ADEV equals its parameter (s); B has its own rule (the floor of the sum).
constexpr std::array<double, 5> read_tau_s{std::numbers::sqrt3, 1.0, 0.0, 3.0, std::numbers::sqrt2};
constexpr std::array<const char*, 5> read_label{"Q at sqrt(3) s", "N at 1 s", "0.664 B", "K at 3 s", "R at sqrt(2) s"};
constexpr auto b_index = static_cast<std::size_t>(Ieee952Term::bias_instability);

// A line per resolved term of the five in the fitted model, with its read-off point within the
// plot; `model` gets every term in the model (wire units). Returns how many are in it.
std::size_t add_term_lines(const NodeView& node, const Units& u, const std::vector<double>& grid, NodePlot& p,
                           std::array<double, 5>& model) {
  const auto inside = [&](double tau) { return tau >= p.tau_min_s && tau <= p.tau_max_s; };
  std::size_t fitted = 0;
  for (std::size_t k = 0; k < 5; ++k) {
    const Ieee952View& t = node.ieee952[k];
    if (!t.in_model()) continue;
    ++fitted;
    model[k] = t.value;
    if (!t.resolved) continue;
    std::array<double, 5> one{};
    one[k] = t.value;
    PlotLine line{static_cast<Ieee952Term>(k),
                  false,
                  fmt::format("{} {:.3g} {} (±{:.2g}%)", units::ieee952[k].letter, t.value * u.ieee[k], u.ieee_name[k],
                              100.0 * t.rel_uncertainty),
                  grid,
                  {}};
    for (const double tau : grid) line.dev.push_back(model_adev(one, tau, u.rate));
    p.terms.push_back(std::move(line));
    if (k != b_index && inside(read_tau_s[k]))
      p.read_offs.push_back({read_tau_s[k], model_adev(one, read_tau_s[k], u.rate), read_label[k]});
  }
  return fitted;
}

}  // namespace

NodePlot plot_data(const NodeView& node, const DisplayRate& rate, ConfidenceIntervals& intervals, const TrueTerms* truth) {
  const Units u = units_for(node, rate);
  NodePlot p;
  p.title = fmt::format("node 0x{:02X}, session {}", node.address, node.session);
  p.rate_name = u.rate_name;
  if (node.window_taus != 0) p.dynamic = window_heat_map(node, u);
  double lo = INFINITY, hi = 0.0;
  for (std::size_t i = 0; i < node.status.tau_count && i < max_taus; ++i) {
    const double tau = node.tau_s(i);
    if (!(tau > 0)) continue;
    const ViewedRow viewed = viewed_row(node, i);  // a stale value (its frame lost) is not drawn
    for (auto [dev, series, shown] : {std::tuple{&node.taus[i].adev, &p.adev, viewed.adev == Viewed::shown},
                                      std::tuple{&node.taus[i].mdev, &p.mdev, viewed.mdev == Viewed::shown}}) {
      if (!shown || !dev->received || !dev->valid) continue;
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
  if (truth != nullptr) p.truth = truth_line(node, *truth, p, grid, u);

  // What the node's fit says, before any model line is drawn.
  const auto& fit = node.ieee952_summary;
  if (!fit_notes(node, p)) return p;

  std::array<double, 5> model{};  // the fitted model, wire units
  const std::size_t fitted = add_term_lines(node, u, grid, p, model);
  // Version 4: the model beyond the five terms, from the same fit (never another's).
  const std::optional<FitModelRow> beyond = fit_model_row(node, u);
  if (beyond && beyond->state != Viewed::shown) {
    p.notes.push_back(fmt::format("fit's model pages {}:", name(beyond->state)));
    p.notes.push_back("model not drawn");
    return p;
  }
  const bool extra = beyond && (beyond->markov > 0 || beyond->sinusoids > 0 || beyond->bandwidth) && node.sampling;
  const double tau0_s = node.sampling ? static_cast<double>(node.sampling->tau0_s) : 0.0;
  // The exact sampled model exists from tau0 on: its lines start there.
  const std::vector<double> sampled_grid = extra ? log_grid(std::max(p.tau_min_s, tau0_s), p.tau_max_s) : grid;
  if (extra) {
    for (std::uint8_t j = 0; j < beyond->markov; ++j) {
      const FitModelRow::Parameter& sigma = beyond->parameters[fit_parameter_position(FitParameter::markov_sigma, j)];
      if (!sigma.resolved) continue;
      FitModelRow one = *beyond;
      one.markov = 1, one.sinusoids = 0, one.bandwidth = false;
      one.parameters[fit_parameter_position(FitParameter::markov_sigma, 0)] = sigma;
      one.parameters[fit_parameter_position(FitParameter::markov_tc, 0)] =
          beyond->parameters[fit_parameter_position(FitParameter::markov_tc, j)];
      const Ieee952Fit f = wire_fit({}, one, u.rate);
      PlotLine line{std::nullopt,
                    true,
                    fmt::format("Markov {:.3g} {} (±{:.2g}%), Tc {:.3g} s", sigma.value, u.rate_name,
                                100.0 * sigma.rel_uncertainty, f.markov[0].tc_s),
                    sampled_grid,
                    {}};
      for (const double tau : sampled_grid) line.dev.push_back(fit_adev(f, tau, tau0_s, u.rate));
      p.terms.push_back(std::move(line));
    }
  }
  if (fitted == 0 && !extra) return p;
  if (fit && !fit->quantization_white && !node.ieee952[0].in_model() && node.scale)
    model[0] = static_cast<double>(node.scale->angle_per_pulse) / std::sqrt(12.0);  // Q held there
  PlotLine sum{std::nullopt,
               false,
               fit ? fmt::format("IEEE-952 model, chi2/dof {:.2g}", fit->chi2_per_dof) : "IEEE-952 model (sum)",
               grid,
               {}};
  if (extra) {
    const Ieee952Fit f = wire_fit(model, *beyond, u.rate);
    sum.tau_s = sampled_grid;
    for (const double tau : sampled_grid) sum.dev.push_back(fit_adev(f, tau, tau0_s, u.rate));
  } else {
    for (const double tau : grid) sum.dev.push_back(model_adev(model, tau, u.rate));
  }
  if (node.ieee952[b_index].resolved && model[b_index] > 0) {  // B: the floor, at the sum's minimum within the points
    std::optional<std::size_t> floor;
    for (std::size_t k = 0; k < sum.tau_s.size(); ++k) {
      if (sum.tau_s[k] >= lo && sum.tau_s[k] <= hi && (!floor || sum.dev[k] < sum.dev[*floor])) floor = k;
    }
    std::array<double, 5> b{};
    b[b_index] = model[b_index];
    if (floor) p.read_offs.push_back({sum.tau_s[*floor], model_adev(b, sum.tau_s[*floor], u.rate), read_label[b_index]});
  }
  p.terms.push_back(std::move(sum));
  return p;
}

}  // namespace gyrochar::decoding
