#include "report.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <span>

#include "gyrochar/estimates.hpp"
#include "gyrochar/ieee952.hpp"

namespace gyrochar::firmware {

bool configure(BoardCharacterizer& c, const ReportSettings& s) {
  if (s.octaves < 1 || s.octaves > max_octaves || s.stride_factor > max_stride_factor || !(s.tau0_s > 0)) return false;
  std::array<std::uint64_t, max_octaves> m_list{};
  for (unsigned k = 0; k < s.octaves; ++k) m_list[k] = std::uint64_t{1} << k;
  return c.configure({s.stride_factor, s.config_hash, s.identity}, std::span(m_list.data(), s.octaves)) ==
         ConfigureStatus::ok;
}

namespace {

protocol::Ieee952Status status_on_wire(FitStatus s) {
  switch (s) {
    case FitStatus::ok: return protocol::Ieee952Status::ok;
    case FitStatus::too_few_points: return protocol::Ieee952Status::too_few_points;
    case FitStatus::rejected: return protocol::Ieee952Status::rejected;
    case FitStatus::singular: return protocol::Ieee952Status::singular;
  }
  return protocol::Ieee952Status::singular;
}

/// A tau below which points were left out, 2 m tau0 of the longest one left out: on the wire as
/// log2 of 2m, rounded up (exact for the octave taus), 1..31; 0 for none.
std::uint8_t excluded_code(double below_tau_s, double tau0_s) {
  const double below_m = below_tau_s / tau0_s;
  if (!(below_m > 1)) return 0;
  const double code = std::ceil(std::log2(below_m) - 1e-6);  // 2m tau0 / tau0 may miss 2m by an ulp
  return static_cast<std::uint8_t>(std::clamp(code, 1.0, 31.0));
}

/// A double as a finite float of the wire, within [-max, max] of float.
float wire_float(double v) {
  const double largest = static_cast<double>(std::numeric_limits<float>::max());
  return static_cast<float>(std::isfinite(v) ? std::clamp(v, -largest, largest) : largest);
}

/// The summary page of `fit`.
protocol::Ieee952SummaryMsg ieee952_summary(const Ieee952Fit& fit, std::uint8_t seq, double tau0_s) {
  protocol::Ieee952SummaryMsg m;
  m.seq = seq;
  m.status = status_on_wire(fit.status);
  m.chi2_per_dof = wire_float(std::max(fit.chi2_per_dof(), 0.0));
  m.points = static_cast<std::uint32_t>(fit.points);
  m.quantization_white = fit.quantization_white;
  for (std::size_t k = 0; k < 2 && !fit.quantization_white; ++k)
    m.excluded_below_log2_m[k] = excluded_code(fit.excluded_below_tau_s[k], tau0_s);
  return m;
}

/// The model page of `fit` (version 4): the terms the arrays of the fit hold, and its runner-up.
protocol::Ieee952ModelMsg ieee952_model(const Ieee952Fit& fit, std::uint8_t seq, double tau0_s) {
  protocol::Ieee952ModelMsg m;
  m.seq = seq;
  m.markov = static_cast<std::uint8_t>(fit.n_markov);
  m.sinusoids = static_cast<std::uint8_t>(fit.n_sinusoids);
  m.bandwidth = fit.bandwidth_tc_s > 0;
  m.bandwidth_excluded_below_log2_m = excluded_code(fit.bandwidth_excluded_below_tau_s, tau0_s);
  if (fit.chosen.valid && fit.runner_up.valid) {
    m.runner_up = true;
    m.runner_up_markov = fit.runner_up.markov;
    m.runner_up_sinusoids = fit.runner_up.sinusoids;
    m.runner_up_bandwidth = fit.runner_up.bandwidth;
    m.criterion_margin = wire_float(fit.runner_up.criterion - fit.chosen.criterion);
  }
  return m;
}

/// Parameter page k (protocol::fit_parameter_slot order) of `fit`: a value with its relative
/// uncertainty, zeros for a term the model does not hold. Resolved needs an accepted fit.
protocol::Ieee952ParameterMsg ieee952_parameter(const Ieee952Fit& fit, std::uint8_t seq, std::size_t k) {
  using protocol::FitParameter;
  const protocol::FitParameterSlot slot = protocol::fit_parameter_slot(k);
  protocol::Ieee952ParameterMsg m{seq, slot.parameter, slot.index};
  double value = 0, uncertainty = 0;
  bool resolved = false;
  switch (slot.parameter) {
    case FitParameter::markov_sigma:
    case FitParameter::markov_tc:
      if (slot.index >= fit.n_markov) break;
      if (slot.parameter == FitParameter::markov_sigma) {
        const Ieee952Parameter& sigma = fit.markov[slot.index].sigma;
        value = sigma.value, uncertainty = sigma.uncertainty, resolved = sigma.resolved;
      } else {
        value = fit.markov[slot.index].tc_s, uncertainty = fit.markov[slot.index].tc_uncertainty_s;
      }
      break;
    case FitParameter::filter_tf: value = fit.bandwidth_tc_s, uncertainty = fit.bandwidth_tc_uncertainty_s; break;
    case FitParameter::sinusoid_amplitude:
    case FitParameter::sinusoid_frequency:
      if (slot.index >= fit.n_sinusoids) break;
      if (slot.parameter == FitParameter::sinusoid_amplitude) {
        const Ieee952Parameter& a = fit.sinusoids[slot.index].amplitude;
        value = a.value, uncertainty = a.uncertainty, resolved = a.resolved;
      } else {
        value = fit.sinusoids[slot.index].frequency_hz;  // given to the fit, not fitted
      }
      break;
  }
  if (!(value > 0) || !std::isfinite(value)) return m;
  m.value = wire_float(value);
  m.rel_uncertainty = std::isfinite(uncertainty) && uncertainty > 0 ? uncertainty / value : 0.0;
  m.resolved = resolved && fit.ok() && protocol::has_resolved(slot.parameter);
  return m;
}

/// The window frames of report `seq`: the latest completed window's curve in arcsec/s, taken when a
/// slow cycle begins so that every window frame of a cycle describes the same window.
void build_window(const ReportSettings& s, std::uint8_t seq, const WindowCurve* window, ReportContent& out) {
  out.window_taus = window != nullptr ? s.window_taus : 0;
  if (out.window_taus == 0) return;
  const auto taus = static_cast<std::uint8_t>(out.window_taus);
  const bool take = seq % protocol::slow_cycle_reports == 0;
  if (take) out.window = {seq, taus, window->complete, window->window, window->gaps};
  out.window.seq = seq;
  out.window.tau_count = taus;
  out.window_length = {seq, s.window_length};
  const double unit = s.pulse_weight_arcsec / s.tau0_s;  // pulses per tau0 -> arcsec/s
  auto dev = [&](double variance) { return std::max(std::sqrt(variance) * unit, protocol::window_dev_floor); };
  for (std::size_t i = 0; i < out.window_taus; ++i) {
    protocol::WindowDevMsg& d = out.window_dev[i];
    if (take) {
      const bool valid = window->complete && window->valid[i];
      d = {seq, static_cast<std::uint8_t>(i), static_cast<std::uint8_t>(window->window & 15u),
           valid ? dev(window->avar[i]) : 0.0, valid ? dev(window->mvar[i]) : 0.0};
    }
    d.seq = seq;
    d.tau_index = static_cast<std::uint8_t>(i);
  }
}

}  // namespace

ReportWorkspace::ReportWorkspace(unsigned octaves, FitMode fit_mode)
    : entries_(std::size_t{octaves} * 16 + 64),  // a few pairs per tau, the table less than half full
      cache_(entries_),
      fitter_(octaves, fit_mode) {}

bool refit_due(std::uint64_t samples, std::uint64_t last_fit_samples, double tau0_s) {
  if (last_fit_samples == 0 || samples < last_fit_samples) return true;
  const auto grown = static_cast<double>(samples - last_fit_samples);
  return grown >= 0.25 * static_cast<double>(last_fit_samples) || grown * tau0_s >= refit_after_s;
}

void build_report(const Characterizer<CountArith>& c, const ReportSettings& s, std::uint8_t seq, std::uint64_t uptime_ms,
                  const FaultCounters& f, ReportWorkspace& work, ReportContent& out, const WindowCurve* window) {
  using namespace protocol;
  const std::size_t taus = c.tau_count();
  const std::uint64_t samples = c.increments();
  out.status = {seq, samples ? NodeState::running : NodeState::starting, static_cast<std::uint8_t>(taus), samples};
  out.faults = {seq, f.lost_edges, f.sample_gaps, f.tx_dropped_frames, f.bus_off_events};
  std::array<TauSums, max_octaves> sums{};
  std::array<NoiseId, max_octaves> noise{};
  take_sums(c, std::span(sums.data(), taus));
  identify_noise(std::span(sums.data(), taus), c.phase_points(), 2, false, std::span(noise.data(), taus), &work.cache());
  // The wire carries the EDF; the skewness stays home (decoders use the plain chi-squared).
  const EstimateOptions options{s.tau0_s, s.pulse_weight_arcsec, EdfModel::exact, false};
  std::array<FitPoint, 2 * max_octaves> points{};
  std::size_t n_points = 0;
  for (std::size_t i = 0; i < taus; ++i) {
    const Estimate a = estimate(sums[i], c.phase_points(), DevStat::oadev, noise[i], options, &work.cache());
    const Estimate m = estimate(sums[i], c.phase_points(), DevStat::mdev, noise[i], options, &work.cache());
    const NoiseType type = noise[i].identified() ? noise_type(noise[i].alpha) : NoiseType::not_identified;
    const auto idx = static_cast<std::uint8_t>(i);
    out.adev[i] = {seq, idx, DevKind::adev, static_cast<float>(a.deviation), a.edf, type, a.clean && a.n > 0};
    out.mdev[i] = {seq, idx, DevKind::mdev, static_cast<float>(m.deviation), m.edf, type, m.clean && m.n > 0};
    out.terms[i] = {seq, idx, a.n};
    out.info[i] = {seq, idx, a.m, static_cast<std::uint8_t>(std::countr_zero(sums[i].stride))};
    for (const Estimate* e : {&a, &m})
      if (e->n > 0 && e->clean) points[n_points++] = {stat_of(e->stat), e->m, e->stride, e->n, e->variance, e->edf};
  }
  out.sampling = {seq, static_cast<float>(s.tau0_s), static_cast<std::uint16_t>(s.stride_factor)};
  out.clock = {seq, uptime_ms, version};
  out.scale = {seq, static_cast<float>(s.pulse_weight_arcsec), AngleUnit::arcsec, s.source};
  out.config = {seq, s.config_hash, s.report_period_ms};
  build_window(s, seq, window, out);
  // The recommended fit of both curves with model selection, in arcsec and seconds; quantization's
  // white level is the pulse weight over sqrt(12). The first report of each slow cycle asks for a
  // new fit when refit_due() and takes the latest finished one: every Ieee952 frame of the cycle
  // (the terms, the summary, the model and its parameters, spread over its reports) describes it.
  if (seq % slow_cycle_reports == 0) {
    if (refit_due(samples, work.fitter().requested_samples(), s.tau0_s))
      work.fitter().request(std::span(points.data(), n_points),
                            {s.tau0_s, c.phase_points(), s.pulse_weight_arcsec / std::sqrt(12.0)}, samples);
    const FitWorker::Result latest = work.fitter().latest();
    out.fit = latest.fit;
    out.fit_samples = latest.samples;
  }
  const Ieee952Fit& fit = out.fit;
  // A term in the model goes out with its value and uncertainty, resolved or not (an upper-bound
  // reading); Resolved also needs an accepted fit. A term left out or held fixed goes out as zeros.
  for (std::size_t k = 0; k < 5; ++k) {
    const Ieee952Parameter& p = fit.p[k];
    const bool fitted = p.fitted && p.value > 0;
    const bool resolved = fitted && fit.ok() && p.resolved;
    out.ieee952[k] = {seq,
                      static_cast<Ieee952Term>(k),
                      resolved,
                      fitted ? static_cast<float>(p.value) : 0.0f,
                      fitted ? p.uncertainty / p.value : 0.0,
                      fitted};
  }
  // Each term's unconstrained estimate (version 5), what verdicts judge: zeros where it has none.
  for (std::size_t k = 0; k < 5; ++k) {
    const Ieee952Parameter& p = fit.p[k];
    const bool known = std::isfinite(p.unconstrained_uncertainty) && p.unconstrained_uncertainty > 0;
    out.unconstrained[k] = {seq, static_cast<Ieee952Term>(k), known ? wire_float(p.unconstrained_signed) : 0.0f,
                            known ? p.unconstrained_uncertainty : 0.0};
  }
  out.ieee952_summary = ieee952_summary(fit, seq, s.tau0_s);
  out.ieee952_model = ieee952_model(fit, seq, s.tau0_s);
  for (std::size_t k = 0; k < fit_parameter_pages; ++k) out.ieee952_parameters[k] = ieee952_parameter(fit, seq, k);
}

protocol::Message report_message(const ReportContent& c, std::size_t k) {
  using namespace protocol;
  const ReportSlot s = report_slot(c.status.seq, c.status.tau_count, k, version, c.window_taus);
  switch (s.slot) {
    case Slot::status: return c.status;
    case Slot::faults: return c.faults;
    case Slot::adev: return c.adev[s.index];
    case Slot::mdev: return c.mdev[s.index];
    case Slot::terms: return c.terms[s.index];
    case Slot::tau_info: return c.info[s.index];
    case Slot::sampling: return c.sampling;
    case Slot::clock: return c.clock;
    case Slot::scale: return c.scale;
    case Slot::config: return c.config;
    case Slot::ieee952: return s.index == ieee952_summary_page ? Message{c.ieee952_summary} : Message{c.ieee952[s.index]};
    case Slot::window: return c.window;
    case Slot::window_length: return c.window_length;
    case Slot::window_dev: return c.window_dev[s.index];
    case Slot::fit_model: return c.ieee952_model;
    case Slot::fit_parameter: return c.ieee952_parameters[s.index];
    case Slot::unconstrained: return c.unconstrained[s.index];
  }
  return c.status;
}

}  // namespace gyrochar::firmware
