#include "support/recovery.hpp"

#include <atomic>
#include <bit>
#include <chrono>
#include <cmath>
#include <exception>
#include <mutex>
#include <thread>

#include "analysis.hpp"
#include "analysis_report.hpp"
#include "gyrochar/greenhall_edf.hpp"
#include "gyrochar/total.hpp"

namespace gyrochar::test_support {

namespace {

Scenario long_run(const char* name, double hours) {
  Scenario s{name, {}, true};
  s.sim.duration_s = hours * 3600;
  s.sim.tau0_s = 0.1;
  s.sim.white_angle_arcsec = 1;
  s.sim.arw_deg_per_sqrt_h = 0.002;
  s.sim.bias_deg_per_h = 0.02;
  s.sim.rrw_deg_per_h_sqrt_h = 0.05;
  s.sim.ramp_deg_per_h2 = 0.01;
  return s;
}

// The octave points of both curves in SI units, as fit_curves() takes them.
std::vector<FitPoint> curve_points(const Analysis& a, const ReportUnits& units) {
  std::vector<FitPoint> points;
  for (const AnalysisRow& r : a.rows)
    if ((r.stat == DevStat::oadev || r.stat == DevStat::mdev) && std::has_single_bit(r.m)) {
      const double v = r.dev * units.phase_unit_si;
      points.push_back({r.stat == DevStat::oadev ? Stat::avar : Stat::mvar, r.m, r.stride, r.n, v * v, r.edf});
    }
  return points;
}

const AnalysisRow* oadev_row(const Analysis& a, std::uint64_t m) {  // the row at m, or the last before it
  const AnalysisRow* found = nullptr;
  for (const AnalysisRow& r : a.rows)
    if (r.stat == DevStat::oadev && r.m <= m) found = &r;
  return found;
}

// The Allan curve's long taus from the total family (recovery.hpp). x: the run's phase in pulses;
// unit: one pulse in rad. Points keep the Allan geometry and carry variance_scale = the Allan
// estimate's EDF over their own (both SP 1065 / Greenhall's formulas for the identified alpha).
void use_long_tau(std::vector<FitPoint>& points, LongTau input, const Analysis& a, const std::vector<double>& x,
                  double tau0, double unit) {
  const double N = static_cast<double>(x.size());
  auto allan_edf = [&](int alpha, std::uint64_t m) {
    const double md = static_cast<double>(m);
    return edf_greenhall({alpha, 2, md, false, md, N});
  };
  if (input == LongTau::totdev) {
    for (FitPoint& p : points) {
      const AnalysisRow* r = p.stat == Stat::avar ? oadev_row(a, p.m) : nullptr;
      if (r == nullptr) continue;
      const int alpha = r->edf_alpha;
      const double md = static_cast<double>(p.m), edf = edf_totvar(alpha, N, md), edf_a = allan_edf(alpha, p.m);
      if (!(edf > edf_a && edf_a > 0)) continue;
      p.variance = totvar(x, p.m, tau0).var / totvar_bias(alpha, N, md) * unit * unit;
      p.edf = edf;
      p.variance_scale = edf_a / edf;
    }
    return;
  }
  if (input != LongTau::theoh) return;
  const std::uint64_t k = theoh_switch(x.size());
  std::erase_if(points, [&](const FitPoint& p) { return p.stat == Stat::avar && p.m >= k; });
  constexpr std::uint32_t S = 16;
  const double ratio = theo_bias_ratio(x, tau0, S, theo_bias_taus(x.size(), S)).ratio;
  for (std::uint64_t mt = 2 * k; 2 * (3 * mt / 4) + 1 <= x.size(); mt *= 2) {
    const std::uint64_t m = 3 * mt / 4;  // tau = 0.75 mt tau0: the Allan geometry at m
    const AnalysisRow* r = oadev_row(a, m);
    if (r == nullptr || !(ratio > 0)) break;
    const double edf = edf_theo1(r->edf_alpha, N, static_cast<double>(mt)), edf_a = allan_edf(r->edf_alpha, m);
    if (!(edf > 0 && edf_a > 0)) continue;
    const double var = theo1(x, mt, tau0, theo1_stride(mt, x.size(), S)).var * ratio * unit * unit;
    points.push_back({Stat::avar, m, 1, x.size() - 2 * m, var, edf, edf_a / edf});
  }
}

}  // namespace

std::vector<Scenario> standard_scenarios() {
  auto make = [](const char* name, double hours, double tau0, auto&& set) {
    Scenario s{name, {}};
    s.sim.duration_s = hours * 3600;
    s.sim.tau0_s = tau0;
    set(s.sim);
    return s;
  };
  return {
      // The README's pipeline without and with a whitener: 0.15 pulse per sample of earth rate.
      make("ARW, periodic quantization", 2, 0.01, [](SimOptions& o) { o.arw_deg_per_sqrt_h = 0.003; }),
      make("ARW, quantization whitened", 2, 0.01,
           [](SimOptions& o) {
             o.arw_deg_per_sqrt_h = 0.003;
             o.white_angle_arcsec = 1;  // a random dither residue of a pulse
           }),
      // The reports: bias instability, rate random walk, a large ARW alone.
      make("ARW + bias instability", 4, 0.1,
           [](SimOptions& o) {
             o.white_angle_arcsec = 1;
             o.arw_deg_per_sqrt_h = 0.005;
             o.bias_deg_per_h = 0.05;
           }),
      make("ARW + rate random walk", 4, 0.1,
           [](SimOptions& o) {
             o.white_angle_arcsec = 1;
             o.arw_deg_per_sqrt_h = 0.01;
             o.rrw_deg_per_h_sqrt_h = 0.1;
           }),
      // The rate random walk without the whitener: 1.5 pulses per sample still quantize
      // into a pattern, one the fit can only see after fitting.
      make("ARW + rate random walk, periodic quantization", 4, 0.1,
           [](SimOptions& o) {
             o.arw_deg_per_sqrt_h = 0.01;
             o.rrw_deg_per_h_sqrt_h = 0.1;
           }),
      make("ARW + rate ramp", 4, 0.1,
           [](SimOptions& o) {
             o.white_angle_arcsec = 1;
             o.arw_deg_per_sqrt_h = 0.005;
             o.ramp_deg_per_h2 = 1;
           }),
      make("large ARW alone", 0.5, 0.1, [](SimOptions& o) { o.arw_deg_per_sqrt_h = 0.1; }),
      // A complete ring laser gyro: every term dominates somewhere.
      make("complete RLG", 6, 0.01,
           [](SimOptions& o) {
             o.pulse_arcsec = 2;
             o.white_angle_arcsec = 3;
             o.arw_deg_per_sqrt_h = 0.003;
             o.bias_deg_per_h = 0.05;
             o.rrw_deg_per_h_sqrt_h = 0.15;
           }),
      // Long runs, the seed paper's length and a day: N/B cross at 80 s, B/K at 760 s, K/R at 17 h.
      long_run("long-run RLG, 24 h", 24), long_run("long-run RLG, 120 h", 120),
  };
}

Recovery recover(const SimOptions& sim, bool long_tau) {
  GyroSimulator gyro(gyro_parameters(sim));
  AnalysisOptions o;
  o.type = DataType::counts;
  o.tau0_s = sim.tau0_s;
  const auto n = static_cast<std::uint64_t>(std::llround(sim.duration_s / sim.tau0_s));
  o.m_list = octave_taus(n + 1);
  o.stats = {DevStat::oadev, DevStat::mdev};
  Analyzer analyzer(o);
  std::vector<double> phase;  // pulses, for the total family
  if (long_tau) phase.reserve(n + 1), phase.push_back(0.0);
  for (std::uint64_t k = 0; k < n; ++k) {
    const auto c = static_cast<double>(gyro.next_count());
    analyzer.add(c);
    if (long_tau) phase.push_back(phase.back() + c);
  }
  ReportUnits units;
  units.gyro = true;
  units.phase_unit_si = sim.pulse_arcsec * units::arcsec;
  const Analysis analysis = analyzer.result();
  const double qw = units.phase_unit_si / std::sqrt(12.0);
  Recovery out{{fit_curves(analysis, units, sim.tau0_s, qw).at(0).fit}, ieee952_truth(sim)};
  if (!long_tau) return out;
  for (const LongTau input : {LongTau::totdev, LongTau::theoh}) {
    std::vector<FitPoint> points = curve_points(analysis, units);
    use_long_tau(points, input, analysis, phase, sim.tau0_s, units.phase_unit_si);
    std::vector<double> workspace(ieee952_workspace_doubles(points.size()));
    out.fits[static_cast<std::size_t>(input)] =
        fit_ieee952(points, {sim.tau0_s, analysis.n_phase, qw}, FitCurve::both, workspace);
  }
  return out;
}

namespace {

std::uint64_t splitmix(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15u;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9u;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBu;
  return x ^ (x >> 31);
}

void tally_terms(std::array<TermTally, 5>& terms, const Ieee952Fit& f, const Ieee952Truth& truth_si);

void tally(RecoveryCell& cell, const Recovery& r, bool long_tau) {
  const Ieee952Fit& f = r.fit();
  ++cell.runs;
  cell.ok += f.status == FitStatus::ok;
  cell.rejected += f.status == FitStatus::rejected;
  cell.too_few += f.status == FitStatus::too_few_points;
  cell.singular += f.status == FitStatus::singular;
  cell.quantization_white += f.quantization_white;
  cell.mean_chi2_per_dof += (f.chi2_per_dof() - cell.mean_chi2_per_dof) / static_cast<double>(cell.runs);
  tally_terms(cell.terms, f, r.truth);
  cell.long_tau = long_tau;
  if (long_tau)
    for (std::size_t i = 0; i < r.fits.size(); ++i) tally_terms(cell.by_long_tau[i], r.fits[i], r.truth);
}

void tally_terms(std::array<TermTally, 5>& terms, const Ieee952Fit& f, const Ieee952Truth& truth_si) {
  const std::array<double, 5> truth{truth_si.q_rad, truth_si.n_rad_sqrt_s, truth_si.b_rad_s, truth_si.k_rad_s_sqrt_s,
                                    truth_si.r_rad_s2};
  for (std::size_t k = 0; k < 5; ++k) {
    TermTally& t = terms[k];
    const Ieee952Parameter& p = f.p[k];
    ++t.runs;
    const bool present = truth[k] > 0;
    t.present += present;
    const bool usable = f.ok();
    t.fitted += usable && p.fitted;
    t.held += usable && !p.fitted && k == 0 && !f.quantization_white;
    if (!usable || !p.resolved) continue;
    ++t.resolved;
    if (!present) {
      ++t.false_resolved;
      continue;
    }
    const double off = std::fabs(p.value - truth[k]);
    t.within1 += off <= p.uncertainty;
    t.within2 += off <= 2 * p.uncertainty;
    t.sum_relative_uncertainty += p.uncertainty / truth[k];
    t.sum_squared_relative_error += (off / truth[k]) * (off / truth[k]);
  }
}

}  // namespace

std::vector<RecoveryCell> run_recovery_study(const RecoverySettings& s) {
  const std::size_t total = s.scenarios.size() * s.runs;
  std::vector<Recovery> results(total);
  std::atomic<std::size_t> next{0}, done{0};
  std::exception_ptr failure;
  std::mutex failure_mutex;
  auto worker = [&] {
    for (;;) {
      const std::size_t i = next.fetch_add(1);
      if (i >= total) return;
      SimOptions sim = s.scenarios[i / s.runs].sim;
      sim.seed = splitmix(splitmix(s.seed) ^ (i / s.runs) * 0x100000001B3u ^ (i % s.runs));
      try {
        results[i] = recover(sim, s.scenarios[i / s.runs].long_tau);
      } catch (...) {
        const std::lock_guard<std::mutex> lock(failure_mutex);
        if (!failure) failure = std::current_exception();
        next.store(total);
      }
      ++done;
    }
  };
  std::vector<std::thread> threads;
  for (unsigned w = 0; w < (s.workers ? s.workers : 1); ++w) threads.emplace_back(worker);
  while (done.load() < total && !failure) {
    std::this_thread::sleep_for(std::chrono::seconds(1));
    if (s.progress) s.progress(done.load(), total);
  }
  for (auto& t : threads) t.join();
  if (failure) std::rethrow_exception(failure);
  std::vector<RecoveryCell> cells(s.scenarios.size());
  for (std::size_t i = 0; i < total; ++i) {  // in run order: the tallies do not depend on scheduling
    RecoveryCell& c = cells[i / s.runs];
    c.scenario = s.scenarios[i / s.runs].name;
    tally(c, results[i], s.scenarios[i / s.runs].long_tau);
  }
  return cells;
}

}  // namespace gyrochar::test_support
