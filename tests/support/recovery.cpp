#include "support/recovery.hpp"

#include "psd.hpp"

#include <atomic>
#include <chrono>
#include <cmath>
#include <exception>
#include <mutex>
#include <thread>

#include "analysis.hpp"
#include "analysis_report.hpp"

namespace gyrochar::test_support {

namespace {

Scenario long_run(const char* name, double hours, double ramp_deg_per_h2) {
  Scenario s{name, {}, true};
  s.sim.duration_s = hours * 3600;
  s.sim.tau0_s = 0.1;
  s.sim.white_angle_arcsec = 1;
  s.sim.arw_deg_per_sqrt_h = 0.002;
  s.sim.bias_deg_per_h = 0.02;
  s.sim.rrw_deg_per_h_sqrt_h = 0.05;
  s.sim.ramp_deg_per_h2 = ramp_deg_per_h2;
  return s;
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
      // The documented Markov gyro as gyrochar-sim makes it (1.5 pulses of earth rate a sample: periodic
      // quantization), and two Markov terms far apart in Tc over a whitened quantization.
      make("ARW + Markov, periodic quantization", 8, 0.1,
           [](SimOptions& o) {
             o.arw_deg_per_sqrt_h = 0.02;
             o.markov = {{0.5, 300}};
           }),
      make("ARW + two Markov terms", 8, 0.1,
           [](SimOptions& o) {
             o.white_angle_arcsec = 1;
             o.arw_deg_per_sqrt_h = 0.02;
             o.markov = {{0.5, 20}, {0.4, 1500}};
           }),
      // The same with the second term's hump well inside the record (its Tc 1/96 of it, not 1/19):
      // what the fit can do where the record shows both humps whole.
      make("ARW + two Markov terms inside the record", 8, 0.1,
           [](SimOptions& o) {
             o.white_angle_arcsec = 1;
             o.arw_deg_per_sqrt_h = 0.02;
             o.markov = {{0.5, 20}, {0.4, 300}};
           }),
      // A sinusoidal rate (a thermal cycle of 100 s; its Allan bump near 37 s, twice the white
      // rate noise's level there), alone and beside a Markov term whose bump lies an octave above.
      make("ARW + sinusoid", 8, 0.1,
           [](SimOptions& o) {
             o.white_angle_arcsec = 1;
             o.arw_deg_per_sqrt_h = 0.02;
             o.sinusoids = {{0.5, 0.01}};
           }),
      make("ARW + sinusoid + Markov", 8, 0.1,
           [](SimOptions& o) {
             o.white_angle_arcsec = 1;
             o.arw_deg_per_sqrt_h = 0.02;
             o.sinusoids = {{0.5, 0.01}};
             o.markov = {{0.5, 300}};
           }),
      // Long runs, the seed paper's length and a day: N/B cross at 80 s, B/K at 760 s, K/R at 17 h.
      long_run("long-run RLG, 24 h", 24, 0.01),
      long_run("long-run RLG, 120 h", 120, 0.01),
      long_run("long-run RLG without ramp, 24 h", 24, 0),
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
  o.keep_record = long_tau;  // the total family's record, for the long-tau fits
  Analyzer analyzer(o);
  RateRecord rates(false, true, sim.tau0_s);
  for (std::uint64_t k = 0; k < n; ++k) {
    const double count = static_cast<double>(gyro.next_count());
    analyzer.add(count);
    rates.add(std::span(&count, 1));
  }
  // The sinusoids the analyzer would offer the fit (its default search).
  std::array<double, max_sinusoids> offered_hz{};
  const std::size_t segment = default_psd_segment(rates.rate().size());
  if (segment != 0) {
    // FFTW's planner is not thread-safe and the study's workers run recover() side by side.
    static std::mutex fftw_planner;
    const std::lock_guard lock(fftw_planner);
    offered_hz = spectrum_of(rates.rate(), true, sim.tau0_s, segment, 0.683, true).fit_hz();
  }
  ReportUnits units;
  units.gyro = true;
  units.phase_unit_si = sim.pulse_arcsec * units::arcsec;
  const Analysis analysis = analyzer.result();
  const double qw = units.phase_unit_si / std::sqrt(12.0);
  // The recommended fit of both curves, once per input (fit_curves() would make all three); in the
  // long-run scenarios the total family stands in for the Allan curve's long taus.
  const FitCurve curve = FitCurve::both;
  auto fit = [&](LongTau input) {
    const std::vector<FitPoint> points = fit_points(analysis, units, sim.tau0_s, input, analyzer.record());
    std::vector<double> workspace(ieee952_workspace_doubles(points.size()));
    FitSetup setup{sim.tau0_s, analysis.n_phase, qw};
    setup.sinusoid_hz = offered_hz;
    return fit_ieee952(points, setup, curve, workspace);
  };
  Recovery out{{fit(LongTau::oadev)}, ieee952_truth(sim)};
  if (!long_tau) return out;
  for (const LongTau input : {LongTau::totdev, LongTau::theoh}) out.fits[static_cast<std::size_t>(input)] = fit(input);
  return out;
}

namespace {

std::uint64_t splitmix(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15u;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9u;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBu;
  return x ^ (x >> 31);
}

void tally_terms(std::array<TermTally, tallied_terms>& terms, const Ieee952Fit& f, const Ieee952Truth& truth_si);

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
    for (std::size_t i = 0; i < r.fits.size(); ++i) {
      tally_terms(cell.by_long_tau[i], r.fits[i], r.truth);
      cell.long_tau_ok[i] += r.fits[i].ok();
      cell.long_tau_chi2[i] += (r.fits[i].chi2_per_dof() - cell.long_tau_chi2[i]) / static_cast<double>(cell.runs);
    }
}

// One value against its truth (zero: a resolved value is false).
// How a value's distance from the truth is judged: in its unit, or in its logarithm (a correlation
// time is stated to a factor, tc_interval(): within k sigma where the truth lies in exp(+-k sd(ln Tc))
// about the fit, sd(ln Tc) = uncertainty / Tc).
enum class Scale { linear, logarithmic };

void tally_value(TermTally& t, double truth, bool usable, bool fitted, bool resolved, double value, double uncertainty,
                 Scale scale = Scale::linear) {
  ++t.runs;
  const bool present = truth > 0;
  t.present += present;
  t.fitted += usable && fitted;
  if (!usable || !resolved) return;
  ++t.resolved;
  if (!present) {
    ++t.false_resolved;
    return;
  }
  const bool log = scale == Scale::logarithmic && value > 0;
  const double off = log ? std::fabs(std::log(value / truth)) : std::fabs(value - truth);
  const double sd = log ? uncertainty / value : uncertainty;
  t.within1 += off <= sd;
  t.within2 += off <= 2 * sd;
  t.sum_relative_uncertainty += uncertainty / truth;
  const double error = (value - truth) / truth;
  t.sum_squared_relative_error += error * error;
}

void tally_markov(std::array<TermTally, tallied_terms>& terms, const Ieee952Fit& f, const Ieee952Truth& truth_si) {
  if (truth_si.markov.empty()) {  // any resolved Markov term is false; "fitted": one in the model
    bool resolved = false;
    for (std::size_t j = 0; j < f.n_markov; ++j) resolved |= f.markov[j].sigma.resolved;
    tally_value(terms[5], 0, f.ok(), f.n_markov > 0, resolved, 0, 0);
    tally_value(terms[6], 0, f.ok(), f.n_markov > 0, resolved, 0, 0);
    return;
  }
  // Each fitted term stands for the simulated one nearest to it in ln Tc, and each simulated term
  // takes the nearest of the fitted terms that stand for it: with one fitted term (20 s) for two
  // simulated ones (20 s and 1 500 s), the 1 500 s term is not found, rather than compared with
  // the 20 s one a second time.
  auto distance = [](double a, double b) { return std::fabs(std::log(a / b)); };
  for (const MarkovRate& m : truth_si.markov) {
    std::size_t nearest = f.n_markov;
    for (std::size_t j = 0; j < f.n_markov; ++j) {
      bool stands_for_m = true;
      for (const MarkovRate& other : truth_si.markov)
        if (distance(f.markov[j].tc_s, other.tc_s) < distance(f.markov[j].tc_s, m.tc_s)) stands_for_m = false;
      if (stands_for_m &&
          (nearest == f.n_markov || distance(f.markov[j].tc_s, m.tc_s) < distance(f.markov[nearest].tc_s, m.tc_s)))
        nearest = j;
    }
    const bool found = nearest < f.n_markov;
    const MarkovTerm fitted = found ? f.markov[nearest] : MarkovTerm{};
    tally_value(terms[5], m.sigma_rad_s, f.ok(), found, found && fitted.sigma.resolved, fitted.sigma.value,
                fitted.sigma.uncertainty);
    tally_value(terms[6], m.tc_s, f.ok(), found, found && fitted.sigma.resolved, fitted.tc_s, fitted.tc_uncertainty_s,
                Scale::logarithmic);
  }
}

void tally_sinusoids(std::array<TermTally, tallied_terms>& terms, const Ieee952Fit& f, const Ieee952Truth& truth_si) {
  if (truth_si.sinusoids.empty()) {  // any resolved sinusoid is false; "fitted": one in the model
    bool resolved = false;
    for (std::size_t j = 0; j < f.n_sinusoids; ++j) resolved |= f.sinusoids[j].amplitude.resolved;
    tally_value(terms[7], 0, f.ok(), f.n_sinusoids > 0, resolved, 0, 0);
    return;
  }
  for (const SinusoidRate& r : truth_si.sinusoids) {
    std::size_t nearest = f.n_sinusoids;
    for (std::size_t j = 0; j < f.n_sinusoids; ++j)
      if (nearest == f.n_sinusoids || std::fabs(f.sinusoids[j].frequency_hz - r.frequency_hz) <
                                          std::fabs(f.sinusoids[nearest].frequency_hz - r.frequency_hz))
        nearest = j;
    const bool found = nearest < f.n_sinusoids;
    const Ieee952Parameter a = found ? f.sinusoids[nearest].amplitude : Ieee952Parameter{};
    tally_value(terms[7], r.amplitude_rad_s, f.ok(), found, found && a.resolved, a.value, a.uncertainty);
  }
}

void tally_terms(std::array<TermTally, tallied_terms>& terms, const Ieee952Fit& f, const Ieee952Truth& truth_si) {
  const std::array<double, 5> truth{truth_si.q_rad, truth_si.n_rad_sqrt_s, truth_si.b_rad_s, truth_si.k_rad_s_sqrt_s,
                                    truth_si.r_rad_s2};
  for (std::size_t k = 0; k < 5; ++k) {
    const Ieee952Parameter& p = f.p[k];
    tally_value(terms[k], truth[k], f.ok(), p.fitted, p.resolved, p.value, p.uncertainty);
    terms[k].held += f.ok() && !p.fitted && k == 0 && !f.quantization_white;
  }
  tally_markov(terms, f, truth_si);
  tally_sinusoids(terms, f, truth_si);
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
