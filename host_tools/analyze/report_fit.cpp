// The IEEE-952 fits of an analysis (analysis_report.hpp): the points of its Allan and modified
// Allan curves, at long tau from the total family when asked (LongTau), the three fits, and a
// simulation's truth read back from the file's header.
#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <initializer_list>
#include <utility>

#include "analysis_report.hpp"
#include "gyrochar/greenhall_edf.hpp"
#include "gyrochar/total.hpp"
#include "threads.hpp"

namespace gyrochar {

namespace {

const AnalysisRow* oadev_row(const Analysis& a, std::uint64_t m) {  // the row at m, or the last before it
  const AnalysisRow* found = nullptr;
  for (const AnalysisRow& r : a.rows)
    if (r.stat == DevStat::oadev && r.m <= m) found = &r;
  return found;
}

// The Allan curve's long taus from the total family (LongTau; docs/metrology.md says why so). x:
// the phase in engine units; unit: one of them in SI. Points keep the Allan geometry and carry
// variance_scale = the Allan estimate's EDF over their own (Greenhall's and SP 1065's formulas for
// the identified alpha).
void use_long_tau(std::vector<FitPoint>& points, LongTau input, const Analysis& a, PhaseSpan x, double tau0, double unit) {
  const double N = static_cast<double>(x.size());
  auto allan_edf = [&](int alpha, std::uint64_t m) {
    const double md = static_cast<double>(m);
    return edf_greenhall({alpha, 2, md, false, md, N});
  };
  if (input == LongTau::totdev) {
    for (FitPoint& p : points) {
      const AnalysisRow* r = p.stat == Stat::avar ? oadev_row(a, p.m) : nullptr;
      if (r == nullptr || !r->alpha) continue;
      const int alpha = *r->alpha;
      const double md = static_cast<double>(p.m), edf = edf_totvar(alpha, N, md), edf_a = allan_edf(alpha, p.m);
      if (!(edf > edf_a && edf_a > 0)) continue;
      p.variance = totvar(x, p.m, tau0).var / totvar_bias(alpha, N, md) * unit * unit;
      p.edf = edf;
      p.variance_scale = edf_a / edf;
    }
    return;
  }
  const std::uint64_t k = theoh_switch(x.size());
  std::erase_if(points, [&](const FitPoint& p) { return p.stat == Stat::avar && p.m >= k; });
  constexpr std::uint32_t S = 16;
  const ThreadRows threads(2);
  const double ratio = a.theoh_bias.stride_factor == S && a.theoh_bias.ratio > 0  // TheoH's rows made it
                           ? a.theoh_bias.ratio
                           : theo_bias_ratio(x, tau0, S, theo_bias_taus(x.size(), S), &threads).ratio;
  if (!(ratio > 0)) return;
  for (std::uint64_t mt = 2 * k; 2 * (3 * mt / 4) + 1 <= x.size(); mt *= 2) {
    const std::uint64_t m = 3 * mt / 4;  // tau = 0.75 mt tau0: the Allan geometry at m
    const AnalysisRow* r = oadev_row(a, m);
    if (r == nullptr || !r->alpha) continue;
    const double edf = edf_theo1(*r->alpha, N, static_cast<double>(mt)), edf_a = allan_edf(*r->alpha, m);
    if (!(edf > 0 && edf_a > 0)) continue;
    const double var = theo1(x, mt, tau0, theo1_stride(mt, x.size(), S)).var * ratio * unit * unit;
    points.push_back({Stat::avar, m, 1, x.size() - 2 * m, var, edf, edf_a / edf});
  }
}

// The power-law pair sums of every two fit points, and their sinusoid sums where the fit is given
// sinusoids, computed once, on two threads, before the fits, which then only read them (a
// PairSumSource their caches ask first). Each pair is what PairSumCache::get() and sinusoid_pair_sums()
// make for a fresh entry, so the fits see the same bits as when each cache made its own. The fit of
// both curves needs every pair, and its Allan-with-modified-Allan pairs are the dear ones: on one
// thread they were most of its time (perf, 10^6 counts); and the fits of each curve alone, on a
// second thread, made the sinusoid sums of their pairs again.
class PointPairSums final : public PairSumSource {
 public:
  PointPairSums(std::span<const FitPoint> points, std::uint64_t n_phase, const SinusoidSumInputs& sinusoids)
      : sinusoids_(sinusoids) {
    for (const FitPoint& p : points) grids_.push_back(unbroken_grid(p.stat, p.m, p.stride, n_phase));
    std::vector<std::pair<std::size_t, std::size_t>> pairs;
    for (std::size_t i = 0; i < grids_.size(); ++i)
      for (std::size_t j = 0; j <= i; ++j) pairs.emplace_back(i, j);
    sums_.resize(pairs.size());
    if (sinusoids_.any()) sinusoid_sums_.resize(pairs.size());
    on_threads(2, pairs.size(), [&](unsigned, std::size_t k) {
      std::array<PairSumCache::Entry, 1> entry{};
      PairSumCache cache(entry);
      const TermGrid &a = grids_[pairs[k].first], &b = grids_[pairs[k].second];
      sums_[k] = cache.get(a, b);
      if (sinusoids_.any()) sinusoid_sums_[k] = sinusoid_pair_sums(sinusoids_.set, sinusoids_.thetas, a, b);
    });
  }
  // The sums of grids a and b as pairs (i, j), i >= j, of the points give them.
  bool find(const TermGrid& a, const TermGrid& b, PairSums& out) const override {
    const std::size_t k = pair_index(a, b);
    if (k == npos) return false;
    out = sums_[k];
    return true;
  }
  bool find_sinusoids(const NoiseSet& set, std::span<const double> thetas, const TermGrid& a, const TermGrid& b,
                      SinusoidPairSums& out) const override {
    const std::size_t k = sinusoid_sums_.empty() ? npos : pair_index(a, b);
    if (k == npos || !std::ranges::equal(thetas, sinusoids_.thetas) || set.count != sinusoids_.set.count ||
        !std::ranges::equal(set.alpha, sinusoids_.set.alpha))
      return false;
    out = sinusoid_sums_[k];
    return true;
  }

 private:
  static constexpr std::size_t npos = static_cast<std::size_t>(-1);
  std::size_t pair_index(const TermGrid& a, const TermGrid& b) const {
    const std::size_t i = index(a), j = index(b);
    return i == grids_.size() || j == grids_.size() || i < j ? npos : i * (i + 1) / 2 + j;
  }
  std::size_t index(const TermGrid& g) const {
    std::size_t i = 0;
    while (i < grids_.size() && !(grids_[i].stat == g.stat && grids_[i].m == g.m && grids_[i].stride == g.stride &&
                                  grids_[i].first == g.first && grids_[i].n == g.n))
      ++i;
    return i;
  }
  SinusoidSumInputs sinusoids_;
  std::vector<TermGrid> grids_;
  std::vector<PairSums> sums_;                   // pair (i, j), i >= j, at i (i + 1) / 2 + j
  std::vector<SinusoidPairSums> sinusoid_sums_;  // likewise; empty where no sinusoid is given
};

}  // namespace

std::vector<FitPoint> fit_points(const Analysis& a, const ReportUnits& units, double tau0_s, LongTau long_tau,
                                 const PhaseRecord& record) {
  std::vector<FitPoint> points;
  for (const AnalysisRow& r : a.rows) {
    if ((r.stat != DevStat::oadev && r.stat != DevStat::mdev) || !std::has_single_bit(r.m)) continue;
    const double dev_si = r.dev * units.phase_unit_si;
    points.push_back({r.stat == DevStat::oadev ? Stat::avar : Stat::mvar, r.m, r.stride, r.n, dev_si * dev_si, r.edf});
  }
  if (long_tau != LongTau::oadev && !record.phase.empty())
    use_long_tau(points, long_tau, a, record.phase, tau0_s, units.phase_unit_si * record.phase_scale);
  return points;
}

std::vector<CurveFit> fit_curves(const Analysis& a, const ReportUnits& units, double tau0_s, double white_quantization_si,
                                 LongTau long_tau, const PhaseRecord& record,
                                 const std::array<double, max_sinusoids>& sinusoid_hz) {
  const std::vector<FitPoint> points = fit_points(a, units, tau0_s, long_tau, record);
  std::vector<CurveFit> fits;
  if (points.empty()) return fits;
  FitSetup setup{tau0_s, a.n_phase, white_quantization_si};
  setup.sinusoid_hz = sinusoid_hz;
  const ThreadRows rows(2);
  setup.rows = &rows;
  const int used = long_tau != LongTau::oadev && !record.phase.empty() ? static_cast<int>(long_tau) : 0;
  const PointPairSums sums(points, a.n_phase, ieee952_sinusoid_inputs(setup));
  // Fits in turn that read those sums.
  const auto fit_in_turn = [&](std::initializer_list<FitCurve> curves) {
    std::vector<CurveFit> out;
    std::vector<double> workspace(ieee952_workspace_doubles(points.size()));
    std::vector<PairSumCache::Entry> entries(points.size() * points.size() + 16);
    PairSumCache cache(entries);
    cache.attach(&sums);
    for (const FitCurve curve : curves)
      out.push_back({curve, fit_ieee952(points, setup, curve, workspace, &cache), curve == FitCurve::mvar ? 0 : used});
    return out;
  };
  // Each curve alone on a second thread while this one fits both.
  auto alone = std::async(std::launch::async, [&] { return fit_in_turn({FitCurve::avar, FitCurve::mvar}); });
  fits = fit_in_turn({FitCurve::both});
  for (CurveFit& f : alone.get()) fits.push_back(std::move(f));
  return fits;
}

std::optional<Ieee952Truth> truth_of(const std::vector<std::string>& header, DataType type, double tau0_s,
                                     double pulse_weight_rad) {
  if (type != DataType::counts) return std::nullopt;
  for (const std::string& line : header) {
    const auto t = parse_sim_truth_line(line);
    if (!t) continue;
    const auto same = [](double a, double b) { return std::fabs(a - b) <= 1e-9 * std::fabs(b); };
    if (!same(t->options.tau0_s, tau0_s) || !same(t->options.pulse_arcsec * units::arcsec, pulse_weight_rad))
      return std::nullopt;
    if (!t->options.segments.empty()) return std::nullopt;  // the gyro changed: no one truth for the run
    return t->truth;
  }
  return std::nullopt;
}

}  // namespace gyrochar
