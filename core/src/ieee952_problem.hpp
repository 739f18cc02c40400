#pragma once
// The IEEE-952 fit's own types, shared by its three files (not part of the core's interface):
//   ieee952.cpp         the entry points: points in, model selection, the fit written out
//   ieee952_gls.cpp     the design rows, the points' covariance and the non-negative GLS solve
//   ieee952_select.cpp  the model selection: nonlinear searches, profiles, the candidates compared
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "gyrochar/ieee952.hpp"
#include "gyrochar/noise_model.hpp"

namespace gyrochar::ieee952_fit {

constexpr std::size_t power_terms = 5;  // Q N B K R
constexpr std::size_t noises = 4;       // Q N B K: the random ones
constexpr std::size_t max_terms = power_terms + max_markov + max_sinusoids;
constexpr std::size_t width = max_terms + 3;  // a row: the design, y, Sigma's diagonal, y less the held terms
constexpr std::size_t y_slot = max_terms, diag_slot = max_terms + 1, offset_slot = max_terms + 2;
// A pair's exact Markov sums: sum c_j c_t (j Markov, t noise), sum c_j c_l, sum c_j.
constexpr std::size_t markov_slots = max_markov * noises + max_markov * max_markov + max_markov;
// A pair's sinusoid sums: sum c_j c_t (j sinusoid, t noise).
constexpr std::size_t sinusoid_slots = max_sinusoids * noises;
static_assert(max_markov <= max_markov_rates && max_sinusoids <= max_sinusoid_rates);
static_assert(ieee952_workspace_doubles(7) == 7 * 8 / 2 * (14 + markov_slots + sinusoid_slots) + 7 * 7 + 7 * width);
constexpr std::array<int, noises> alphas{2, 0, -1, -2};  // Q N B K
using Terms = std::array<double, max_terms>;
using Flags = std::array<bool, max_terms>;
// Two estimates keep a noise's part of their covariance when they lie at most band_octaves apart
// and double precision evaluates it: pair_sums_rounding() bounds the rounding of its correlation
// at covariance_rounding_kept. Far apart, the closed forms of the flicker and random-walk FM sums
// are differences of nearly equal huge numbers (on a 120 h record at tau0 0.1 s the random-walk FM
// sum of the modified Allan estimate at 512 tau0 and the Allan one at 2^19 tau0, ten octaves
// apart, came out wrong by more than its value, and the matrix indefinite: the fit was singular);
// their correlations there are small (0.04 for that pair, by an exact computation without the
// closed forms). The bound is loose (typically far above the actual error): at 1e-3 it dropped
// accurate parts of neighbouring estimates and the fit of short records was rejected where it had
// been fine, so only parts it cannot vouch for to 0.1 go. White PM is exact at any distance and
// need not decay: fully overlapped Allan estimates share the sum of x^2 and stay correlated by
// about 0.24 across every tau up to the stride factor; it is always kept.
constexpr double covariance_rounding_kept = 0.1;
constexpr int band_octaves = 10;
constexpr double quantization_left_out = 0.01;  // share of a point that makes it unusable (non-white)
constexpr double bandwidth_left_out = 0.01;     // change of white rate noise by the sensor's filter, likewise
constexpr double pi = 3.14159265358979323846;
// A criterion difference of 2 ln 19: the runner-up keeps 1/20 of the chosen model's weight (the
// Bayesian information criterion's approximation of the evidence), the odds of a 2-sigma result.
constexpr double model_doubt = 5.8888779583328805;

// The terms of one candidate model beyond the five: columns 5.. are its Markov terms, then its
// sinusoids; the filter changes N's column.
struct Model {
  std::size_t markov = 0;
  std::array<double, max_markov> a{};  // tau0 / Tc of each Markov term
  std::size_t sinusoids = 0;
  std::array<double, max_sinusoids> hz{};
  double band = 0;    // tau0 / Tf of the filter on N's white noise; 0: none
  unsigned held = 0;  // power terms (bit t) held at zero: a Markov term stands in B's or K's place
  std::size_t columns() const { return power_terms + markov + sinusoids; }
  std::size_t nonlinear() const { return markov + sinusoids + (band > 0 ? 1 : 0); }
};

using Matrix = std::array<std::array<double, max_terms>, max_terms>;

// The points in use, with their design rows and the workspace views.
struct Problem {
  std::size_t n = 0;
  const FitPoint* point[max_fit_points];
  std::array<double, power_terms> power[max_fit_points];  // each point's five-term design (power_design())
  double tau0 = 1;
  std::uint64_t n_phase = 0;
  double spread = 0;
  Model model;  // the model the rows are made for
  // Each point's place in the first fit of this call: the pair sums and the sinusoids' sums are
  // kept by place and made once (a later fit has fewer points, never new ones).
  std::size_t place[max_fit_points];
  std::size_t places = 0;
  bool sums_made = false;
  double* pair = nullptr;                  // per pair of places (i <= j): 10 sums c_t c_u, then 4 sums c_t
  double* markov_pair = nullptr;           // per pair (i <= j): the Markov terms' sums (markov_slots)
  bool exact_markov = false;               // markov_pair holds the sums of model.a: Sigma is exact
  double* sinusoid_pair = nullptr;         // per pair (i <= j): the sums of the given sinusoids
  std::array<double, max_sinusoids> hz{};  // the given sinusoids (FitSetup::sinusoid_hz)
  double* sigma = nullptr;                 // n x n
  double* rows = nullptr;                  // per point: the design, y, Sigma's diagonal, y less the held terms
  double* row(std::size_t i) const { return rows + i * width; }
  std::size_t place_pair(std::size_t i, std::size_t j) const {
    i = place[i];
    j = place[j];
    return i > j ? i * (i + 1) / 2 + j : j * (j + 1) / 2 + i;
  }
  double* pair_at(std::size_t i, std::size_t j) const { return pair + place_pair(i, j) * 14; }
  double* markov_pair_at(std::size_t i, std::size_t j) const {
    return markov_pair + (i > j ? i * (i + 1) / 2 + j : j * (j + 1) / 2 + i) * markov_slots;
  }
  double* sinusoid_pair_at(std::size_t i, std::size_t j) const { return sinusoid_pair + place_pair(i, j) * sinusoid_slots; }
  // Keeps the points for which keep(point) is true, in order, with their places.
  template <class Keep>
  void keep_points(Keep&& keep) {
    std::size_t kept = 0;
    for (std::size_t i = 0; i < n; ++i) {
      if (!keep(*point[i])) continue;
      place[kept] = place[i];
      point[kept++] = point[i];
    }
    n = kept;
  }
};

struct Solution {
  Terms theta{};
  Matrix cov{};
  Flags active{};
  Terms free_theta{}, free_variance{};  // each free term in the model with every free term, unconstrained
  double chi2 = 0;
  bool ok = false;
  bool feasible = false;  // a non-negative solution with every term beyond the five in it was found
};

// Where a fit stands: its solution, status and numbers, before they are written out.
struct Candidate {
  Model model;
  Solution sol;
  FitStatus status = FitStatus::too_few_points;
  std::size_t dof = 0;
  std::size_t parameters = 0;
  double criterion = 0;
  bool valid = false;
  // Its correlation times lie inside their search range and chi2 curves around each (the
  // selection's test of where a Markov term was found; significance is judged on the fit).
  bool placed = true;
};

// ieee952_gls.cpp
double markov_column(double a, Stat s, std::uint64_t m, double tau0);
double sinusoid_column(double hz, Stat s, std::uint64_t m, double tau0);
std::array<double, power_terms> power_design(Stat s, std::uint64_t m, double tau0);
Terms design(const Model& model, const std::array<double, power_terms>& p, Stat s, std::uint64_t m, double tau0);
int octave(std::uint64_t m);
void set_rows(Problem& pr);
bool weigh(const Problem& pr, const Terms& theta);
Solution solve(const Problem& pr, const Flags& free, const Terms& fixed);
bool rejected(double chi2, std::size_t dof);
void pair_sums_of_points(Problem& pr, const FitSetup& setup, PairSumCache* cache);
void markov_sums_of_points(Problem& pr, const FitSetup& setup);
void sinusoid_sums_of_points(Problem& pr, const FitSetup& setup, PairSumCache* cache);
double criterion_of(double chi2, std::size_t parameters, std::size_t points);
double log_det(const Problem& pr);
Candidate fit_model(Problem& pr, const Flags& free, const Terms& fixed, bool first, int iterations);
double profile_chi2(Problem& pr, const Flags& free, const Terms& fixed);

// ieee952_select.cpp
/// The spread of ln(value) of a nonlinear parameter (a Markov term's tau0 / Tc, the filter's): the
/// half-widths of its interval below and above the fitted value. A profile's two differ (a
/// Markov term's chi2 rises more slowly towards one side); a curvature's are equal. 0: not
/// determined.
struct LogSpread {
  double down = 0, up = 0;
  /// The standard deviation stated for ln(value): the root mean square of the two half-widths.
  double sd() const { return std::sqrt((down * down + up * up) / 2); }
};
using LogSpreads = std::array<LogSpread, max_markov + 1>;  // the Markov terms', then the filter's
Candidate select_model(Problem& pr, const FitSetup& setup, bool filter, const Flags& free, const Terms& fixed,
                       Candidate& runner_up, LogSpreads& nonlinear_sd);
void widen_by_nonlinear(Problem& pr, const Flags& free, const Terms& fixed, const LogSpreads& nl_sd, Solution& sol);
bool refit_exactly(Problem& pr, const FitSetup& setup, const Flags& free, const Terms& fixed, Candidate& chosen,
                   Candidate& runner_up, LogSpreads& nl_sd, bool with_profile = true);
void profile_markov_terms(Problem& pr, const Flags& free, const Terms& fixed, LogSpreads& nl_sd);
bool markov_terms_hold(const Candidate& more, const Candidate& fewer);
bool column_significant(const Candidate& c, std::size_t t);
struct MarkovTaus {
  double lo, hi;  // [s]
};
MarkovTaus markov_taus(const Problem& pr, const Solution& sol);
bool place_markov_term(Problem& pr, const Flags& free, const Terms& fixed, std::size_t k, double lo, double hi, bool above);
Candidate markov_in_place(Problem& pr, const Flags& free, const Terms& fixed, const Candidate& base, std::size_t t);
Candidate markov_in_place_of(Problem& pr, const Flags& free, const Terms& fixed, const Candidate& chosen, std::size_t t);

}  // namespace gyrochar::ieee952_fit
