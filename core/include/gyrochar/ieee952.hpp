#pragma once
// The IEEE Std 952 gyro error model fitted to the Allan and modified Allan variance curves by
// generalized least squares: every point weighted by its exact variance, and the correlation of
// the estimates at neighbouring taus (and of AVAR and MVAR at the same tau) taken into account.
// Freestanding; memory comes from the caller (ieee952_workspace_doubles()).
//
// Model (tau = m tau0 in s; an angle unit r, rates in r/s). Each term is a power-law noise of
// noise_model.hpp with innovations of a fixed variance, so the expected variance of every point,
// and the covariance of any two, are exact sums over the terms:
//   Q  quantization / white angle noise   white PM (alpha 2),       innovations Q^2          [r]
//   N  angle random walk                  white FM (alpha 0),       N^2 tau0                  [r/s^0.5]
//   B  bias instability                   flicker FM (alpha -1),    B^2 tau0^2                [r/s]
//   K  rate random walk                   random-walk FM (alpha -2), K^2 tau0^3              [r/s^1.5]
//   R  rate ramp                          deterministic x = R t^2/2, AVAR = MVAR = R^2 tau^2/2 [r/s^2]
// At large m they are IEEE 952's AVAR = 3Q^2/tau^2 + N^2/tau + (2 ln 2/pi) B^2 + K^2 tau/3 + R^2 tau^2/2
// (B is the flicker floor of ADEV divided by sqrt(2 ln 2 / pi) = 0.664); at small m they are the
// exact expectations of the discrete estimators (the MVAR of N is N^2 (m^2 + 1)/(2 m^2 tau), ...).
//
// The fit. The five squared parameters enter linearly. The covariance of the points is the exact
// one under the current parameters plus, on the diagonal, (model_spread x point)^2, 0.1 % by
// default: the model is an idealization, and where a point's own sampling error is far below that
// (short taus, EDF 10^6) it would otherwise weigh in with a precision no model has; it also keeps
// the covariance of AVAR and MVAR at one tau, correlated up to 0.99, well conditioned. Estimates
// more than 10 octaves apart keep only the white PM part of their covariance, nearer ones the
// parts double precision evaluates (pair_sums_rounding(); far apart, the flicker and random-walk
// FM parts are small and their closed forms cancel to nothing: ieee952.cpp says more). As the
// covariance depends on the parameters, the fit iterates: covariance from the current parameters, then the
// non-negative generalized least-squares solution (every subset of terms is tried, the best
// feasible one kept; a term left out is "not fitted"). chi2 is the generalized residual; where
// chi2/dof > 1 every uncertainty is scaled by sqrt(chi2/dof) (the Birge ratio), and where the model
// is rejected outright (chi2/dof > 2 with a p-value below 1e-4) the fit says so (status).
// A term is "resolved" when it is fitted, its square lies more than two standard uncertainties
// above zero, and it is the largest of the five contributions at one of the taus used at least (for R,
// at the tau of an Allan or modified Allan point: a total-family point's expectation takes AVAR's
// ramp response, which is not its own). B, K and R must also survive the choice of model: where the
// runner-up of the model selection comes within 2 ln 19 of the chosen model by the criterion and
// does without the term (not two standard uncertainties above zero there), it is not resolved
// (`doubted`); nor, in a model that holds a Markov term, is a B or K that one more Markov term in
// its place (its correlation time inside the search range, every Markov term significant) replaces
// with a chi2 within 2 ln 19 of the chosen model's. Where such a model does as well (B or K
// resolved or not), the record cannot choose between the two: each term both hold has the
// difference between its two values added to its uncertainty, and is resolved only where its
// square stays two of the wider uncertainties above zero.
//
// Quantization. For counts the white-quantization level is known: Q_w = pulse weight / sqrt(12).
// A steady rate without dither (and with too little random angle per sample to spread it) makes a
// periodic pattern instead, whose Allan variance at short taus swings above and below the white
// level 3 Q_w^2 / tau^2. Quantization is declared not white when, before the fit, a point the
// white level alone would dominate lies below it, or when, after the fit (Q free: white angle
// noise beyond quantization is in the model), a point the fitted Q dominates departs from the
// model either way; both by three standard deviations and 2 %; or when the angle moves so little
// between samples (the fitted N, Q's excess over Q_w) that the quantization error's correlation
// could move a point by half its standard deviation. Then every point with a
// quantization share of 1 % or more is left out, Q is held at Q_w (not fitted) and the rest is
// fitted again.
//
// Beyond the five terms (IEEE 952 has them too; real sensors show them), with model selection:
//   Markov  first-order Gauss-Markov rate: a sampled AR(1) rate of stationary standard deviation
//           sigma [r/s] and correlation time Tc [s] (noise_model.hpp, markov_term_covariance());
//           rate-random-walk-like below Tc, white-rate-like above, ADEV peak near tau = 1.89 Tc
//   bandwidth the sensor's own first-order filter on its white rate noise: N's term becomes a
//           Markov term of short correlation time Tf whose long-tau level is N^2 / tau (N keeps
//           its meaning; the shortest taus bend below the N line)
//   sinusoid a rate A sin(2 pi f t + random phase) [r/s], f given by the caller (a spectral line):
//           AVAR A^2 (sin^2 x / x)^2, MVAR A^2 sin^6 x / (x^2 m^2 sin^2(pi f tau0)), x = pi f tau
// Their expected variances are exact for the sampled estimators. During the model search their
// part in the covariance of the points is approximate: a Markov term's variance at each point is
// taken as white rate noise and rate random walk in the proportion its local slope says (-1:
// white, +1: random walk), the filter as white rate noise of the filtered level. A sinusoid is
// deterministic but for its phase: its part is its cross term with the noises, exact for a phase
// uniform over the turn (sinusoid_pair_sums(); its cross term with a Markov term is left out). The chosen model's Markov terms are then fitted again on the exact
// covariance (markov_pair_sums()), where the choice is checked once more: a runner-up with fewer
// Markov terms and the lower criterion on that covariance is the model; a runner-up with one more
// Markov term (it lost on the approximate covariance) is fitted on its own exact covariance and is
// the model when its Gaussian likelihood is the higher, each model on its own exact covariance
// (criterion + ln det Sigma); the recovery study measures the result (docs/metrology.md).
// Model selection (FitSetup::select_model): from the five terms, the filter, then the given
// sinusoids (spectral lines found in the record), then one Markov term and a second are added while
// each lowers the Bayesian information criterion chi2 + p ln(points) (p: the terms fitted plus
// twice each correlation time or frequency); a correlation time is found on a grid of four per
// octave (Tc from twice the shortest usable tau to half the longest), then refined by golden
// section, both on the covariance of the model before it. A candidate is compared with the model before it on its
// own covariance (under the other's, a model that overshoots the long taus predicts their variance
// too large and is hardly charged for it) and wins when its criterion is lower and the term it adds
// lies two standard uncertainties above zero with its time inside the search range (a Markov term:
// every Markov term, and N kept if it was in; the filter: Tf within a factor e^0.5). The filter is tried only where white rate noise
// dominates the shortest tau, Markov terms only among the taus where white angle noise does not
// (there either could stand in for a quantization pattern). The runner-up's figures are given on
// the chosen model's covariance.
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>

#include "gyrochar/noise_model.hpp"
#include "gyrochar/rows.hpp"
#include "gyrochar/stat.hpp"

namespace gyrochar {

/// One point of a curve: an overlapping (or strided) AVAR or MVAR estimate and its geometry.
///
/// A total-family estimate (TOTVAR or TheoBR for AVAR, bias-corrected: docs/total.md) may stand in
/// for the Allan estimate of the same tau: stat avar, the Allan geometry (m, stride 1, n = N - 2m),
/// and variance_scale = its variance over the Allan estimate's (EDF of the Allan estimate over its
/// own, below 1 where it has more degrees of freedom). Its covariance with every point is the Allan
/// estimate's scaled by sqrt(variance_scale): the correlations of the Allan estimates it replaces,
/// its own smaller variance (docs/metrology.md says why that is the honest choice we can make).
struct FitPoint {
  Stat stat = Stat::avar;     // avar or mvar
  std::uint64_t m = 1;        // averaging factor
  std::uint64_t stride = 1;   // terms every `stride` phase points (a power of two)
  std::uint64_t n = 0;        // terms formed (gaps remove some)
  double variance = 0;        // the estimate, (r/s)^2
  double edf = 0;             // the per-tau EDF (first weights only); <= 0: n
  double variance_scale = 1;  // 1: the Allan-family estimate itself; < 1: a total-family one for it
};

inline constexpr std::size_t max_markov = 2;     // Markov terms a model may have
inline constexpr std::size_t max_sinusoids = 2;  // sinusoids a model may have
inline constexpr std::size_t max_fit_points = 128;

struct FitSetup {
  double tau0_s = 1.0;
  std::uint64_t n_phase = 0;                        // phase points of the run (the unbroken grids)
  double white_quantization = 0.0;                  // Q_w in r when the data are counts (pulse weight / sqrt 12); 0: unknown
  double model_spread = 0.001;                      // how closely the model is taken to describe each point (relative)
  bool select_model = true;                         // false: the five terms only, as IEEE 952's basic model
  std::size_t markov_terms = max_markov;            // at most this many Markov terms (<= max_markov)
  std::array<double, max_sinusoids> sinusoid_hz{};  // candidate sinusoid frequencies (0: none)
  const RowRunner* rows = nullptr;                  // runs the rows of the exact Markov sums (null: in turn, here)
};

/// The curve(s) a fit reads: the overlapping Allan deviation's (avar), the modified Allan
/// deviation's (mvar) or both. Not a statistic: the statistics are DevStat (stat.hpp).
enum class FitCurve : std::uint8_t { avar, mvar, both };
enum class FitStatus : std::uint8_t {
  ok,
  too_few_points,  // fewer points than fitted terms
  rejected,        // the model does not describe the curve (chi2/dof > 2, p < 1e-4)
  singular,        // the covariance of the points or the normal equations could not be solved
};
/// "avar", "mvar", "both" / "ok", "too few points", "model rejected", "singular": static strings.
const char* name(FitCurve c);
const char* name(FitStatus s);

struct Ieee952Parameter {
  double value = 0;        // Q, N, B, K or R (units above)
  double uncertainty = 0;  // standard uncertainty, same unit (scaled by the Birge ratio)
  bool fitted = false;     // part of the model the fit kept (false: left out, or held fixed)
  bool resolved = false;   // see the header
  // B, K or R that the chosen model resolves but the runner-up, within model_doubt of it by the
  // criterion, does without, or (B, K) that one more Markov term in its place replaces as well
  // (chi2 within model_doubt): not resolved (see the header).
  bool doubted = false;
  // B or K in a model with a Markov term, where one more Markov term in its place describes the curve
  // as well (chi2 within model_doubt): that term's correlation time [s], else 0. The term is not
  // resolved, and every term both models hold has the difference between its two values added to
  // its uncertainty (in quadrature; Tc's in ln Tc).
  double markov_in_place_tc_s = 0;
  // B or K held at zero in the chosen model: one of its Markov terms stands in the term's place
  // (the term free beside it, the Markov term was not significant).
  bool held_for_markov = false;
  // The same term in the model with every free term, its square not held non-negative: unbiased
  // where the model holds (the non-negative value above leans low or high where another term is
  // clipped at zero); 0 and 0 where the term was not free. What acceptance verdicts judge.
  double unconstrained = 0, unconstrained_uncertainty = 0;
  // The signed root of that unconstrained square s, sign(s) sqrt(|s|): negative where s is (and
  // `unconstrained` 0); 0 where the term was not free. What the CAN protocol carries (version 5).
  double unconstrained_signed = 0;
};

/// A Markov term of the fit: sigma its stationary standard deviation [r/s], Tc its correlation time.
struct MarkovTerm {
  Ieee952Parameter sigma;
  double tc_s = 0;
  // Tc times the standard deviation of ln Tc (chi2's profile in ln Tc on the model's covariance,
  // Birge-scaled). The 68 % interval is Tc exp(-u / Tc) .. Tc exp(u / Tc) (tc_interval()): a
  // correlation time is known to a factor, and Tc +- u would reach zero where u approaches Tc.
  double tc_uncertainty_s = 0;
};
/// The 68 % interval of a correlation time stated as Tc and u = Tc sd(ln Tc): {Tc e^(-u/Tc),
/// Tc e^(u/Tc)}; {0, 0} where it is not determined (u = 0).
inline std::array<double, 2> tc_interval(double tc_s, double uncertainty_s) {
  if (!(tc_s > 0) || !(uncertainty_s > 0)) return {0.0, 0.0};
  const double factor = std::exp(uncertainty_s / tc_s);
  return {tc_s / factor, tc_s * factor};
}
/// A sinusoid of the fit: amplitude [r/s] at a given frequency.
struct SinusoidTerm {
  Ieee952Parameter amplitude;
  double frequency_hz = 0;
};
/// One candidate model of the selection and how well it did.
struct ModelSummary {
  bool valid = false;  // false: no such candidate was fitted
  std::uint8_t markov = 0, sinusoids = 0;
  bool bandwidth = false;
  FitStatus status = FitStatus::too_few_points;
  double chi2 = 0;
  std::size_t dof = 0;
  std::size_t parameters = 0;  // linear terms fitted plus correlation times and frequencies
  double criterion = 0;        // chi2 + parameters ln(points)
};
/// A point of the fit against its model: (variance - model) / its standard deviation.
struct FitResidual {
  Stat stat = Stat::avar;
  std::uint64_t m = 0;
  double variance = 0, model = 0, normalized = 0;
};

struct Ieee952Fit {
  FitCurve curve = FitCurve::both;
  FitStatus status = FitStatus::too_few_points;
  std::array<Ieee952Parameter, 5> p{};           // Q, N, B, K, R
  double chi2 = 0;                               // generalized chi-squared of the final fit
  std::size_t dof = 0;                           // points used minus terms fitted
  double birge = 1;                              // factor applied to the uncertainties (>= 1)
  std::size_t points = 0;                        // points used
  bool quantization_white = true;                // false: non-white quantization found (counts only)
  std::array<double, 2> excluded_below_tau_s{};  // AVAR, MVAR points below these taus left out (non-white)
  std::array<MarkovTerm, max_markov> markov{};   // the first n_markov are in the model
  std::size_t n_markov = 0;
  std::array<SinusoidTerm, max_sinusoids> sinusoids{};
  std::size_t n_sinusoids = 0;
  double bandwidth_excluded_below_tau_s = 0;            // points below this tau left out: the sensor's own filter (0: none)
  double bandwidth_tc_s = 0;                            // Tf of the filter on N's white noise (0: none in the model)
  double bandwidth_tc_uncertainty_s = 0;                // Tf sd(ln Tf), as a Markov term's (tc_interval())
  ModelSummary chosen, runner_up;                       // the selected model and the next best candidate
  std::array<FitResidual, max_fit_points> residuals{};  // every point used, in the fit's order
  std::size_t n_residuals = 0;
  bool ok() const { return status == FitStatus::ok; }
  double chi2_per_dof() const { return dof ? chi2 / static_cast<double>(dof) : 0.0; }
};

/// Doubles of workspace fit_ieee952() needs for `points` points: about 19 points^2.
constexpr std::size_t ieee952_workspace_doubles(std::size_t points) {
  // per pair: 14 power-law sums, the Markov terms' (4 noises, each other, alone) and the sinusoids'
  // (4 noises); Sigma; rows
  return points * (points + 1) / 2 * (14 + max_markov * 4 + max_markov * max_markov + max_markov + max_sinusoids * 4) +
         points * points + points * 12;
}

/// Fits the model to the points of `curve` (points of the other statistic are ignored; any
/// order). `workspace` holds at least ieee952_workspace_doubles(points.size()) doubles. O(P^2 x
/// pair_sums()) for the covariances (O(P^2) from `cache`, optional), then O(P^3) per iteration;
/// no allocation; never fails hard.
Ieee952Fit fit_ieee952(std::span<const FitPoint> points, const FitSetup& setup, FitCurve curve, std::span<double> workspace,
                       PairSumCache* cache = nullptr);

/// What the fit's sinusoid sums (sinusoid_pair_sums() of every two points) are made of: the
/// noises and each given frequency's phase step 2 pi f tau0 (0: none given). A PairSumSource that
/// makes them beforehand makes them from these. O(1).
struct SinusoidSumInputs {
  NoiseSet set;
  std::array<double, max_sinusoids> thetas{};
  bool any() const { return thetas[0] > 0 || thetas[max_sinusoids - 1] > 0; }
};
SinusoidSumInputs ieee952_sinusoid_inputs(const FitSetup& setup);

/// The model's exact expected AVAR or MVAR at averaging factor m for parameters {Q, N, B, K, R}.
/// O(1).
double ieee952_variance(const std::array<double, 5>& qnbkr, Stat stat, std::uint64_t m, double tau0_s);
/// The same for the whole model of a fit: its five terms, the filter, Markov terms and sinusoids. O(1).
double fitted_variance(const Ieee952Fit& fit, Stat stat, std::uint64_t m, double tau0_s);

/// IEEE 952's closed form of the AVAR at any tau (the large-m limit of the above), for drawing
/// the model and reading it off: 3Q^2/tau^2 + N^2/tau + (2 ln 2/pi) B^2 + K^2 tau/3 + R^2 tau^2/2.
double ieee952_avar(const std::array<double, 5>& qnbkr, double tau_s);

}  // namespace gyrochar
