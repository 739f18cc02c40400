// The IEEE-952 fit's model selection (see ieee952_problem.hpp): the nonlinear parameters (Markov
// correlation times, the sensor's filter) searched on chi2's profile, their uncertainties, and the
// candidate models compared by the criterion.
#include <cmath>

#include "ieee952_problem.hpp"

namespace gyrochar::ieee952_fit {

// Whether a searched value lies inside its range [lo, hi], not at one of its ends (within 5 %).
bool inside_search_range(double value, double lo, double hi) {
  constexpr double edge = 0.05;  // in ln(value)
  return std::log(value) > std::log(lo) + edge && std::log(value) < std::log(hi) - edge;
}

// Golden-section minimum of profile_chi2 over ln(*value) in [a, b] (`iterations` steps); leaves
// *value at it and returns chi2 there.
double golden_min(Problem& pr, const Flags& free, const Terms& fixed, double* value, double a, double b, int iterations) {
  constexpr double golden = 0.6180339887498949;
  double x1 = b - golden * (b - a), x2 = a + golden * (b - a);
  *value = std::exp(x1);
  double f1 = profile_chi2(pr, free, fixed);
  *value = std::exp(x2);
  double f2 = profile_chi2(pr, free, fixed);
  for (int k = 0; k < iterations; ++k) {
    if (f1 < f2) {
      b = x2, x2 = x1, f2 = f1, x1 = b - golden * (b - a);
      *value = std::exp(x1);
      f1 = profile_chi2(pr, free, fixed);
    } else {
      a = x1, x1 = x2, f1 = f2, x2 = a + golden * (b - a);
      *value = std::exp(x2);
      f2 = profile_chi2(pr, free, fixed);
    }
  }
  *value = std::exp(f1 < f2 ? x1 : x2);
  return f1 < f2 ? f1 : f2;
}

// Minimizes profile_chi2 over *value in log space: a grid from lo to hi (`per_octave` a factor of
// two), then golden section around the best node. Leaves *value at the minimum and returns whether
// it lies inside the range (at an end, the data want the term where the search does not allow it).
bool search(Problem& pr, const Flags& free, const Terms& fixed, double* value, double lo, double hi, int per_octave) {
  const double step = std::log(2.0) / per_octave;
  double best_log = std::log(lo), best = HUGE_VAL;
  for (double l = std::log(lo); l <= std::log(hi) + 1e-12; l += step) {
    *value = std::exp(l);
    const double chi2 = profile_chi2(pr, free, fixed);
    if (chi2 < best) best = chi2, best_log = l;
  }
  golden_min(pr, free, fixed, value, std::fmax(best_log - step, std::log(lo)), std::fmin(best_log + step, std::log(hi)), 24);
  return inside_search_range(*value, lo, hi);
}

// The standard deviation of ln(*value) from the curvature of chi2 on the fitted model's own
// covariance (pr holds it), the linear terms solved again at each point: ln(value) +- h with
// h = 0.2, where the profile is a parabola to a few percent (0: no curvature).
double log_sd(Problem& pr, const Flags& free, const Terms& fixed, double* value) {
  constexpr double h = 0.2;
  const double at = *value;
  const double mid = profile_chi2(pr, free, fixed);
  *value = at * std::exp(h);
  const double up = profile_chi2(pr, free, fixed);
  *value = at * std::exp(-h);
  const double down = profile_chi2(pr, free, fixed);
  *value = at;
  set_rows(pr);
  const double curvature = up + down - 2 * mid;
  return curvature > 0 && std::isfinite(curvature) ? h * std::sqrt(2 / curvature) : 0.0;
}

// The spread of ln(a_k), Markov term k's tau0 / Tc, from its profile: the two half-widths of the
// interval where chi2 (on the fitted model's covariance, the linear terms solved again at
// each step, and every other Markov term's Tc placed again within an octave of where it was) lies
// within 1 of its minimum, walked out in steps of 0.1 to at most 3 either side. A Markov term's
// profile flattens away from its minimum, so the curvature there (log_sd()) says too little: in the
// recovery study its Tc lay within one such sigma of the truth in 38 % of the runs, not 68 %; and
// with the other terms held where they were, a second term's profile was too narrow again.
LogSpread profile_log_sd(Problem& pr, const Flags& free, const Terms& fixed, std::size_t k) {
  constexpr double step = 0.1, reach = 3.0, octave_ln = 0.6931471805599453;
  const Model fitted = pr.model;
  const double at = fitted.a[k];
  const double mid = profile_chi2(pr, free, fixed);
  double half[2] = {reach, reach};
  for (int side = 0; side < 2; ++side) {
    double before = 0;
    pr.model = fitted;
    for (double l = step; l <= reach + 1e-9; l += step) {
      pr.model.a[k] = at * std::exp(side == 0 ? -l : l);
      double chi2 = profile_chi2(pr, free, fixed);
      for (std::size_t j = 0; j < fitted.markov; ++j)  // within an octave of its fitted Tc
        if (j != k) {
          const double centre = std::log(fitted.a[j]);
          chi2 = golden_min(pr, free, fixed, &pr.model.a[j], centre - octave_ln, centre + octave_ln, 12);
        }
      const double rise = chi2 - mid;
      if (rise >= 1) {
        half[side] = std::isfinite(rise) ? l - step + step * (1 - before) / (rise - before) : l - step / 2;
        break;
      }
      before = std::fmax(rise, 0.0);
    }
  }
  pr.model = fitted;
  set_rows(pr);
  return std::isfinite(mid) ? LogSpread{half[0], half[1]} : LogSpread{};
}

// True when column t of candidate c lies more than two standard uncertainties (Birge-scaled) above
// zero. Not "resolved": a Markov term shares its rising side with K and its falling side with N,
// and need not be the largest anywhere to be there (the fit still says whether it is resolved).
bool column_significant(const Candidate& c, std::size_t t) {
  const double birge = c.dof && c.sol.chi2 > static_cast<double>(c.dof) ? std::sqrt(c.sol.chi2 / static_cast<double>(c.dof))
                                                                        : 1.0;
  return c.sol.active[t] && c.sol.theta[t] > 2 * std::sqrt(std::fabs(c.sol.cov[t][t])) * birge;
}

// Places Markov term k (pr.model has k + 1) beside the terms found before: sought over its whole
// range [lo, hi], or, `above`, only above those terms (from twice the longest Tc), then every term
// moves to where it belongs beside the others (two passes over +-2 octaves). Returns whether every
// correlation time lies inside [lo, hi] and the first search's optimum inside its range (at an end
// the data want the term where the search does not allow it). False, pr.model unchanged, where
// nothing lies above the others.
bool place_markov_term(Problem& pr, const Flags& free, const Terms& fixed, std::size_t k, double lo, double hi, bool above) {
  double top = hi;
  for (std::size_t j = 0; above && j < k; ++j) top = std::fmin(top, pr.model.a[j] / 2);
  if (!(lo < top)) return false;
  bool inside = search(pr, free, fixed, &pr.model.a[k], lo, top, 4) || top < hi;  // a cut range's end is no end
  for (int pass = 0; pass < 2 && k > 0; ++pass)
    for (std::size_t j = 0; j <= k; ++j) {
      const double at = pr.model.a[j];
      search(pr, free, fixed, &pr.model.a[j], std::fmax(lo, at / 4), std::fmin(hi, at * 4), 8);
    }
  for (std::size_t j = 0; j <= k; ++j) inside &= inside_search_range(pr.model.a[j], lo, hi);
  return inside;
}

// The taus a Markov term is sought among: from the shortest where white angle noise (Q) makes up
// less than half the five terms' part of the model `sol` (below, a Markov term cannot be told from
// a quantization pattern: a steady 1.5 pulses a sample made one "appear" at Tc = 0.17 s) to the
// longest. pr's rows are the model's.
MarkovTaus markov_taus(const Problem& pr, const Solution& sol) {
  MarkovTaus taus{1e300, 0};
  for (std::size_t i = 0; i < pr.n; ++i) {
    const double tau = static_cast<double>(pr.point[i]->m) * pr.tau0;
    double model = 0;
    for (std::size_t t = 0; t < power_terms; ++t) model += sol.theta[t] * pr.row(i)[t];
    if (sol.theta[0] * pr.row(i)[0] < 0.5 * model) taus.lo = std::fmin(taus.lo, tau);
    taus.hi = std::fmax(taus.hi, tau);
  }
  return taus;
}

// The search for the model: the five terms, then the filter, Markov terms and sinusoids while each
// lowers the criterion. Leaves the winner's covariance in pr; `runner_up` is the next best.
Candidate select_model(Problem& pr, const FitSetup& setup, bool filter, const Flags& free, const Terms& fixed,
                       Candidate& runner_up, LogSpreads& nonlinear_sd) {
  pr.model = Model{};
  Candidate best = fit_model(pr, free, fixed, true, 12);
  runner_up = Candidate{};
  nonlinear_sd = {};
  if (!setup.select_model || !best.valid || best.status == FitStatus::singular) return best;
  const MarkovTaus taus = markov_taus(pr, best.sol);
  const double tau_lo = taus.lo, tau_hi = taus.hi;
  // A candidate wins when it lowers the criterion and the term it adds is significant (a Markov term
  // or sinusoid) or determined (the filter's Tf within a factor e^0.5); else it may be the runner-up.
  // Both are compared on the candidate's covariance (pr holds it): under its own, a model that
  // overshoots the long taus predicts their variance too large and is hardly charged for it.
  auto consider = [&](const Candidate& c, bool added_term_holds) {
    if (!c.valid || c.status == FitStatus::singular || c.status == FitStatus::too_few_points) return false;
    pr.model = best.model;
    const double incumbent = criterion_of(profile_chi2(pr, free, fixed), best.parameters, pr.n);
    pr.model = c.model;
    if (c.criterion < incumbent && added_term_holds) {
      runner_up = best;
      best = c;
      return true;
    }
    if (!runner_up.valid || c.criterion < runner_up.criterion) runner_up = c;
    return false;
  };
  // Restores the winner's rows and covariance (the search overwrote them).
  auto settle = [&]() {
    pr.model = best.model;
    set_rows(pr);
    weigh(pr, best.sol.theta);
  };
  // The sensor's filter on its white rate noise: Tf from tau0 / 20 to 4 tau0. Only where that
  // noise dominates the shortest tau: under white angle noise a filter on N cannot be told from
  // Q's own shape, nor from a quantization pattern (a steady rate of 1.5 pulses a sample made it
  // "find" a 3 Hz filter on a simulated gyro that has none).
  std::size_t shortest = 0;
  for (std::size_t i = 1; i < pr.n; ++i)
    if (pr.point[i]->m < pr.point[shortest]->m) shortest = i;
  const bool white_rate_first = best.sol.theta[1] * pr.row(shortest)[1] > best.sol.theta[0] * pr.row(shortest)[0];
  if (filter && white_rate_first) {
    pr.model = best.model;
    const bool inside = search(pr, free, fixed, &pr.model.band, 0.25, 20.0, 4);
    const Candidate c = fit_model(pr, free, fixed, false, 12);
    const double sd = log_sd(pr, free, fixed, &pr.model.band);
    if (consider(c, inside && sd > 0 && sd < 0.5)) nonlinear_sd[max_markov] = {sd, sd};
    settle();
  }
  // Sinusoids at the frequencies given, before the Markov terms: a spectral line found in the
  // record is evidence of its own, while a Markov term searched first takes up part of a
  // sinusoid's hump and stays in the model after the sinusoid came in (a simulated gyro with a
  // sinusoid and no Markov term was given one of 0.06 +- 0.97 deg/h that way).
  for (double hz : setup.sinusoid_hz) {
    if (!(hz > 0) || best.model.sinusoids >= max_sinusoids) continue;
    pr.model = best.model;
    pr.model.hz[pr.model.sinusoids++] = hz;
    const Candidate c = fit_model(pr, free, fixed, false, 12);
    consider(c, column_significant(c, pr.model.columns() - 1));
    settle();
  }
  // Markov terms, one at a time: Tc from twice the shortest tau (shorter, the term is white rate
  // noise over the whole curve: N's double) to half the longest (its Allan peak near 1.89 Tc).
  for (std::size_t k = 0; k < setup.markov_terms && k < max_markov && 4 * tau_lo <= tau_hi; ++k) {
    pr.model = best.model;
    pr.model.markov = k + 1;
    const double lo = 2 * pr.tau0 / tau_hi, hi = pr.tau0 / (2 * tau_lo);
    // The terms found before were placed without this one: each moves to where it belongs beside
    // it. Without this the first of two Markov terms (20 s and 300 s) sat at 26-31 s, its hump
    // taking up part of the second, which was then not significant, and B and R stood in for it.
    // And a second term is sought from two starts, over the whole range and above the first, the
    // better kept: from the whole range alone, the first term held at 30 s made the second take
    // the short taus (3 to 6 s, the first then moving to 40-60 s), and the 300 s one was not tried.
    bool inside = place_markov_term(pr, free, fixed, k, lo, hi, false);
    if (k > 0) {
      const Model whole = pr.model;
      const double whole_chi2 = profile_chi2(pr, free, fixed);
      pr.model = best.model;
      pr.model.markov = k + 1;
      const bool above_inside = place_markov_term(pr, free, fixed, k, lo, hi, true);
      if (above_inside && profile_chi2(pr, free, fixed) < whole_chi2) inside = above_inside;
      else pr.model = whole;
    }
    Candidate c = fit_model(pr, free, fixed, false, 12);
    LogSpreads sds = nonlinear_sd;
    for (std::size_t j = 0; j <= k; ++j) {
      const double sd = log_sd(pr, free, fixed, &pr.model.a[j]);
      sds[j] = {sd, sd};
    }
    // Its Tc inside the range and determined (chi2 curves around it), every Markov term significant
    // (a second one that splits the first in two is not), and none taking white rate noise's place
    // (N fitted before, not after: that is N again).
    c.placed = inside && sds[k].sd() > 0;
    const bool better = consider(c, c.placed && markov_terms_hold(c, best));
    if (better) nonlinear_sd = sds;
    settle();
    if (!better) break;
  }
  // B or K with a Markov term in its place, the term held at zero, where the curve holds a Markov
  // term already: a Markov term's rising side is a rate random walk's and its hump can stand for a
  // floor, and beside a free B or K a new Markov term need not be significant (two Markov terms,
  // 20 s and 1 500 s over 8 h: 4 of 100 fits stayed at one and B, rejected). Not where the curve
  // has none: there a lone Markov hump imitates a flicker floor over the decade a short record
  // shows, and took B's or K's place in 3 to 8 % of the runs of gyros that have no Markov term.
  for (std::size_t t = 2; t < 4; ++t) {
    if (best.model.markov == 0 || best.model.markov >= setup.markov_terms || !column_significant(best, t)) continue;
    const Candidate base = best;
    const Candidate c = markov_in_place(pr, free, fixed, base, t);
    if (c.valid) consider(c, c.placed && markov_terms_hold(c, base));
    settle();
  }
  // The runner-up's figures on the chosen model's covariance (pr holds it), comparable with its own.
  if (runner_up.valid) {
    pr.model = runner_up.model;
    runner_up.sol.chi2 = profile_chi2(pr, free, fixed);
    runner_up.criterion = criterion_of(runner_up.sol.chi2, runner_up.parameters, pr.n);
    settle();
  }
  return best;
}

// Every Markov term of `more` significant, and N in it if it was in `fewer`, the model it adds to.
bool markov_terms_hold(const Candidate& more, const Candidate& fewer) {
  bool holds = !fewer.sol.active[1] || more.sol.active[1];
  for (std::size_t j = 0; j < more.model.markov; ++j) holds &= column_significant(more, power_terms + j);
  return holds;
}

// The linear terms' covariance given the nonlinear parameters, widened by what their uncertainty
// passes on. Each nonlinear parameter is moved to the two ends of its interval, ln a - down and
// ln a + up, the linear terms solved again there, and their shifts v_down, v_up added as
// (v_down v_down^T + v_up v_up^T) / 2: for a linear dependence b this is b b^T sd(ln a)^2 (the
// Schur complement of the joint information), and where the dependence bends or the interval is
// lopsided it follows both. Without any widening a Markov term's sigma was stated with the
// uncertainty it would have if Tc were known: within one stated sigma of the truth in 47 % of the
// recovery study's runs instead of 68 %. With the slope at the fitted Tc (a central difference of
// +-0.1) times the mean of the two half-widths, one Markov term over 300 runs: sigma 62.8 / 91.1 %
// within 1 / 2 stated sigma, Tc 63.8 / 92.8 %; so: 67.0 / 92.0 % and 72.2 / 94.8 %
// (docs/metrology.md). Where an end has no solution, the slope at the fitted value stands in.
void widen_by_nonlinear(Problem& pr, const Flags& free, const Terms& fixed, const LogSpreads& nl_sd, Solution& sol) {
  const std::size_t columns = pr.model.columns();
  // The linear terms solved with *value moved by a factor exp(shift).
  auto solved_at = [&](double* value, double shift, Solution& out) {
    const double at = *value;
    *value = at * std::exp(shift);
    set_rows(pr);
    out = solve(pr, free, fixed);
    *value = at;
    set_rows(pr);
    return out.feasible;
  };
  auto widen = [&](double* value, const LogSpread& spread) {
    if (!(spread.down > 0) || !(spread.up > 0) || !(*value > 0)) return;
    Solution here, up, down;
    if (!solved_at(value, 0, here)) return;
    Terms vu{}, vd{};
    if (solved_at(value, spread.up, up) && solved_at(value, -spread.down, down)) {
      for (std::size_t t = 0; t < columns; ++t) {
        vu[t] = up.theta[t] - here.theta[t];
        vd[t] = here.theta[t] - down.theta[t];
      }
    } else {  // an end has no solution: the slope at the fitted value (a central difference)
      constexpr double h = 0.1;
      if (!solved_at(value, h, up) || !solved_at(value, -h, down)) return;
      for (std::size_t t = 0; t < columns; ++t) {
        const double slope = (up.theta[t] - down.theta[t]) / (2 * h);
        vu[t] = slope * spread.up;
        vd[t] = slope * spread.down;
      }
    }
    for (std::size_t t = 0; t < columns; ++t)
      for (std::size_t u = 0; u < columns; ++u) sol.cov[t][u] += (vu[t] * vu[u] + vd[t] * vd[u]) / 2;
  };
  for (std::size_t j = 0; j < pr.model.markov; ++j) widen(&pr.model.a[j], nl_sd[j]);
  widen(&pr.model.band, nl_sd[max_markov]);
}

// Each Markov term's sd(ln Tc) from its profile (profile_log_sd()) on the covariance pr holds.
void profile_markov_terms(Problem& pr, const Flags& free, const Terms& fixed, LogSpreads& nl_sd) {
  for (std::size_t k = 0; k < pr.model.markov; ++k) nl_sd[k] = profile_log_sd(pr, free, fixed, k);
}

// The chosen model with Markov terms fitted again on the exact covariance (the selection used the
// approximation local_noise() makes): its terms, its correlation times' uncertainties and the
// runner-up's figures on it (without_profile: the terms alone). Keeps the approximate fit where the
// exact one fails (false).
bool refit_exactly(Problem& pr, const FitSetup& setup, const Flags& free, const Terms& fixed, Candidate& chosen,
                   Candidate& runner_up, LogSpreads& nl_sd, bool with_profile) {
  pr.model = chosen.model;
  markov_sums_of_points(pr, setup);
  Candidate exact = fit_model(pr, free, fixed, false, 12);
  if (!exact.valid || exact.status == FitStatus::singular || !weigh(pr, exact.sol.theta)) {
    pr.exact_markov = false;
    pr.model = chosen.model;
    set_rows(pr);
    weigh(pr, chosen.sol.theta);
    return false;
  }
  chosen = exact;
  if (!with_profile) return true;
  profile_markov_terms(pr, free, fixed, nl_sd);
  if (runner_up.valid) {
    pr.model = runner_up.model;
    runner_up.sol.chi2 = profile_chi2(pr, free, fixed);
    runner_up.criterion = criterion_of(runner_up.sol.chi2, runner_up.parameters, pr.n);
    pr.model = chosen.model;
    set_rows(pr);
  }
  return true;
}

// The model `base` with B or K (column t) held at zero and one Markov term more in its place,
// sought above the terms found before (B and K live at the long taus), fitted on its own
// (approximate) covariance, which pr then holds. `placed`: every correlation time inside its range
// and the new one determined. Invalid where base has no room for another Markov term or its taus
// none, or the term found no place.
Candidate markov_in_place(Problem& pr, const Flags& free, const Terms& fixed, const Candidate& base, std::size_t t) {
  const std::size_t k = base.model.markov;
  pr.model = base.model;
  set_rows(pr);
  const MarkovTaus taus = markov_taus(pr, base.sol);
  if (k >= max_markov || !(4 * taus.lo <= taus.hi)) return Candidate{};
  const double lo = 2 * pr.tau0 / taus.hi, hi = pr.tau0 / (2 * taus.lo);
  pr.model.markov = k + 1;
  pr.model.held |= 1u << t;
  if (!place_markov_term(pr, free, fixed, k, lo, hi, true)) return Candidate{};
  Candidate c = fit_model(pr, free, fixed, false, 12);
  c.placed = log_sd(pr, free, fixed, &pr.model.a[k]) > 0;
  return c;
}

// The chosen model's B or K (column t) replaced as well by a Markov term in its place
// (markov_in_place()): accepted, every Markov term significant, N still in it, and its chi2 within
// model_doubt of the chosen model's, both on its covariance (as the search compares). By chi2, not
// by the criterion: the question is whether the record tells the two apart, not which of them is
// the simpler. By the criterion, which charges the Markov term's three parameters (3 ln 34 = 10.6
// on 34 points), two Markov terms of 20 s and 1 500 s gave B resolved in 12 of 200 runs where the
// Markov term in its place had about the same chi2 (from 4.4 less to 3.8 more). Returns that
// model, else an invalid candidate. Leaves pr's model and covariance the chosen one's again (an
// exact covariance's Markov sums are not touched).
Candidate markov_in_place_of(Problem& pr, const Flags& free, const Terms& fixed, const Candidate& chosen, std::size_t t) {
  const bool exact = pr.exact_markov;
  pr.exact_markov = false;
  const Candidate c = markov_in_place(pr, free, fixed, chosen, t);
  bool as_well = false;
  if (c.valid && c.status == FitStatus::ok && c.placed && markov_terms_hold(c, chosen)) {
    pr.model = chosen.model;
    as_well = c.sol.chi2 - profile_chi2(pr, free, fixed) < model_doubt;
  }
  pr.model = chosen.model;
  pr.exact_markov = exact;
  set_rows(pr);
  weigh(pr, chosen.sol.theta);
  return as_well ? c : Candidate{};
}

}  // namespace gyrochar::ieee952_fit
