#pragma once
// Acceptance limits and the guard-banded verdict, shared by gyrochar-analyze and gyrochar-decode
// (--limits FILE, docs/metrology.md "Acceptance limits").
//
// The file: one limit a line, '#' starts a comment, blank lines are skipped:
//   N <= 0.003 deg/sqrt(h)        an IEEE-952 term of the fit: Q N B K R, in its gyro unit
//   B <= 0.01 deg/h               (units::ieee952) or its SI unit (rad, rad/s^0.5, rad/s,
//   K <= 1e-4 deg/h/sqrt(h)        rad/s^1.5, rad/s^2); Q also in any angle unit, B in any rate unit
//   adev(100 s) <= 0.005 deg/h    the overlapping Allan deviation at that tau (s, min or h), in a
//   mdev(10 s) <= 0.01 deg/h      rate unit (deg/h, deg/s, rad/s); mdev the modified one
// Only upper limits ("<=") exist; a quantity may be limited once.
//
// The decision rule. Each estimate has a lower and an upper bound, each a one-sided 97.5 % bound
// (the two-sided 95 % interval, decision_confidence): a fitted term value -+ 1.96 u (u its standard
// uncertainty, Birge-scaled; the fit's parameters taken as normal), a deviation its chi-squared
// interval from the estimator's EDF (confidence.hpp). Then
//   pass       the upper bound is within the limit     (a gyro at or beyond the limit passes with
//                                                       a chance of at most 2.5 %)
//   fail       the lower bound is beyond the limit     (a gyro within fails at most 2.5 %)
//   undecided  otherwise; and always when the estimate is missing: a fit that is not accepted, a
//              term not resolved or not in the model, no deviation at the tau asked.
// For an undecided verdict with an estimate, the run time at which it is expected to decide: the
// distance from the estimate to its bound shrinks as 1/sqrt(EDF), and EDF grows in proportion to
// the run length T at a fixed tau (and so does the information on a fitted term), the estimate
// staying where it is: T_decide = T (d / |value - limit|)^2, d the distance from the value to the
// bound on the limit's side. Infinite when the value sits on the limit.
#include <cstddef>
#include <limits>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace gyrochar {

/// The two-sided level of the decision intervals, and the standard normal quantile of each bound.
inline constexpr double decision_confidence = 0.95;
inline constexpr double decision_z = 1.959963984540054;  // Phi^-1(0.975)

struct Limit {
  // adev is the overlapping Allan deviation, as on the wire (docs/architecture.md, "Names of statistics").
  enum class Kind : unsigned char { term, adev, mdev };
  Kind kind = Kind::term;
  std::size_t term = 1;  // Kind::term: Q N B K R = 0..4
  double tau_s = 0;      // adev, mdev
  double value_si = 0;   // the limit in SI: rad, rad/s^0.5, rad/s, rad/s^1.5, rad/s^2; deviations rad/s
  std::string unit;      // the unit it was written in
  double unit_si = 1;    // the size of that unit in SI
  std::size_t line = 0;  // line in the file
  std::string text;      // the limit as written (without comment and surrounding blanks)
  /// "N", "B", "adev(100 s)": the quantity, for tables and column names.
  std::string quantity() const;
};

/// A limits file that cannot be used: what() is "line L: why" (or why, for the whole file).
class LimitsError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The limits of `text` (the file's content), in order. Throws LimitsError naming the line and the
/// cause: an unknown quantity, an operator other than "<=", a value that is not a positive finite
/// number, a unit that does not fit the quantity, a quantity limited twice, a tau that is not a
/// positive time, control bytes; and a file with no limit at all. O(length).
std::vector<Limit> parse_limits(std::string_view text);
/// Reads and parses the file at `path` (at most 65536 bytes). Throws LimitsError (the path is the
/// caller's to name) when it cannot be read or parsed.
std::vector<Limit> read_limits_file(const std::string& path);

enum class Verdict : unsigned char { pass, fail, undecided };
/// "pass", "fail", "undecided": static strings.
const char* name(Verdict v);

/// What is known of a limited quantity: the estimate and its decision bounds (SI, as the limit),
/// and the run length it is from; or why there is none.
struct LimitEstimate {
  bool usable = false;
  std::string why;  // not usable: "N not resolved", "fit model rejected", ...
  double value = 0, low = 0, high = 0;
  double run_s = 0;
  /// Which estimate of a fitted term a live node's verdict judged (gyrochar-decode):
  /// estimate_unconstrained, or estimate_shown where the node sends no unconstrained estimate;
  /// empty: not said (a deviation, or gyrochar-analyze, which judges the unconstrained one).
  std::string kind;
};
inline constexpr const char* estimate_unconstrained = "unconstrained";
inline constexpr const char* estimate_shown = "shown";
/// A normal estimate: value -+ decision_z u (the low bound not below 0). O(1).
LimitEstimate normal_estimate(double value, double standard_uncertainty, double run_s);
/// A deviation with `edf` degrees of freedom (skew_dof as confidence.hpp): its chi-squared
/// interval at decision_confidence; not usable without an EDF. O(1).
LimitEstimate deviation_estimate(double dev, double edf, double skew_dof, double run_s);
/// No estimate, and why.
LimitEstimate no_estimate(std::string why);

struct Decision {
  Verdict verdict = Verdict::undecided;
  LimitEstimate estimate;
  /// Undecided with a usable estimate: the run length (s) at which the interval is expected to
  /// decide (infinity when the value sits on the limit); NaN otherwise.
  double decide_at_s = std::numeric_limits<double>::quiet_NaN();
  std::string reason;  // a short explanation for people
};
/// The verdict of `limit` for `estimate` by the rule of the header. O(1).
Decision decide(const Limit& limit, const LimitEstimate& estimate);

/// The worst of the verdicts: fail if any fails, else undecided if any is, else pass (pass for none).
Verdict overall(const std::vector<Decision>& decisions);

/// A run length for people: "3.2 h", "45 min", "12 s", "never at this estimate" (infinite).
std::string format_run_length(double seconds);

}  // namespace gyrochar
