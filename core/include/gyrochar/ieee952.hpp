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
// ramp response, which is not its own).
//
// Quantization. For counts the white-quantization level is known: Q_w = pulse weight / sqrt(12).
// A steady rate without dither (and with too little random angle per sample to spread it) makes a
// periodic pattern instead, whose Allan variance at short taus swings above and below the white
// level 3 Q_w^2 / tau^2. Quantization is declared not white when, before the fit, a point the
// white level alone would dominate lies below it, or when, after the fit (Q free: white angle
// noise beyond quantization is in the model), a point the fitted Q dominates departs from the
// model either way; both by three standard deviations and 2 %. Then every point with a
// quantization share of 1 % or more is left out, Q is held at Q_w (not fitted) and the rest is
// fitted again.
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "gyrochar/noise_model.hpp"
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
  Stat stat = Stat::avar;    // avar or mvar
  std::uint64_t m = 1;       // averaging factor
  std::uint64_t stride = 1;  // terms every `stride` phase points (a power of two)
  std::uint64_t n = 0;       // terms formed (gaps remove some)
  double variance = 0;       // the estimate, (r/s)^2
  double edf = 0;            // the per-tau EDF (first weights only); <= 0: n
  double variance_scale = 1; // 1: the Allan-family estimate itself; < 1: a total-family one for it
};

struct FitSetup {
  double tau0_s = 1.0;
  std::uint64_t n_phase = 0;        // phase points of the run (the unbroken grids)
  double white_quantization = 0.0;  // Q_w in r when the data are counts (pulse weight / sqrt 12); 0: unknown
  double model_spread = 0.001;      // how closely the model is taken to describe each point (relative)
};

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
};

struct Ieee952Fit {
  FitCurve curve = FitCurve::both;
  FitStatus status = FitStatus::too_few_points;
  std::array<Ieee952Parameter, 5> p{};  // Q, N, B, K, R
  double chi2 = 0;                      // generalized chi-squared of the final fit
  std::size_t dof = 0;                  // points used minus terms fitted
  double birge = 1;                     // factor applied to the uncertainties (>= 1)
  std::size_t points = 0;               // points used
  bool quantization_white = true;       // false: periodic quantization detected (counts only)
  std::array<double, 2> excluded_below_tau_s{};  // AVAR, MVAR points below these taus left out (non-white)
  bool ok() const { return status == FitStatus::ok; }
  double chi2_per_dof() const { return dof ? chi2 / static_cast<double>(dof) : 0.0; }
};

/// Doubles of workspace fit_ieee952() needs for `points` points: about 7.5 points^2.
constexpr std::size_t ieee952_workspace_doubles(std::size_t points) {
  return points * (points + 1) / 2 * 14 + points * points + points * 8;
}

/// Fits the model to the points of `curve` (points of the other statistic are ignored; any
/// order). `workspace` holds at least ieee952_workspace_doubles(points.size()) doubles. O(P^2 x
/// pair_sums()) for the covariances (O(P^2) from `cache`, optional), then O(P^3) per iteration;
/// no allocation; never fails hard.
Ieee952Fit fit_ieee952(std::span<const FitPoint> points, const FitSetup& setup, FitCurve curve,
                       std::span<double> workspace, PairSumCache* cache = nullptr);

/// The model's exact expected AVAR or MVAR at averaging factor m for parameters {Q, N, B, K, R}.
/// O(1).
double ieee952_variance(const std::array<double, 5>& qnbkr, Stat stat, std::uint64_t m, double tau0_s);

/// IEEE 952's closed form of the AVAR at any tau (the large-m limit of the above), for drawing
/// the model and reading it off: 3Q^2/tau^2 + N^2/tau + (2 ln 2/pi) B^2 + K^2 tau/3 + R^2 tau^2/2.
double ieee952_avar(const std::array<double, 5>& qnbkr, double tau_s);

}  // namespace gyrochar
