#pragma once
// Confidence intervals of a deviation from its equivalent degrees of freedom (chi-squared, NIST SP
// 1065 eq. 45): dev sqrt(edf / chi2_{1-p}) .. dev sqrt(edf / chi2_p), p = (1 - confidence) / 2.
// With the skewness too (skew_dof = nu3 of core's noise_model.hpp), the variance estimate is taken
// as distributed like mean x (a + b chi2_nu3), b = 1/sqrt(edf nu3), a = 1 - b nu3 (three moments
// matched): dev / sqrt(a + b chi2_nu3(1-p)) .. dev / sqrt(a + b chi2_nu3(p)). Where the EDF is small
// (the last octaves) that interval holds the truth 66-69 % of the time, the plain one 72-75 %.
// Quantiles from Boost.Math. ConfidenceIntervals memoizes them per EDF for a stream of values.
#include <string>
#include <unordered_map>

namespace gyrochar {

struct Interval {
  double low = 0.0;
  double high = 0.0;
  bool valid = false;  // false when edf <= 0 (not available) or the confidence is not in (0, 1)
};

/// The interval for deviation `dev` with `edf` degrees of freedom at `confidence` (e.g. 0.683);
/// skew_dof > 0 (and below edf) shapes it by the third moment as above, 0 gives the plain one.
/// O(1), may allocate (Boost's quantile); never throws.
Interval confidence_interval(double dev, double edf, double confidence = 0.682689492137086, double skew_dof = 0);

/// Plain confidence intervals memoized per EDF: the interval is proportional to the deviation, and
/// a stream of estimates (the CAN wire carries at most 4095 distinct EDFs) meets few distinct EDFs,
/// so the quantiles are computed once per EDF, then looked up in O(1).
class ConfidenceIntervals {
 public:
  /// `confidence` in (0, 1), e.g. 0.683.
  explicit ConfidenceIntervals(double confidence) : confidence_(confidence) {}
  /// The interval of deviation `dev` (any unit) with `edf` degrees of freedom; invalid when edf <= 0.
  /// Allocates a table entry at the first meeting of an EDF; never throws.
  Interval operator()(double dev, double edf);
  double confidence() const { return confidence_; }

 private:
  double confidence_;
  std::unordered_map<double, Interval> unit_intervals_;  // by edf, for dev = 1
};

/// A correlation time's 68 % interval as text, "68 %: 101 .. 286 s": stated to a factor, Tc
/// exp(-+u / Tc) (tc_interval(), gyrochar/ieee952.hpp); empty where u is not known.
std::string correlation_time_interval(double tc_s, double uncertainty_s);

}  // namespace gyrochar
