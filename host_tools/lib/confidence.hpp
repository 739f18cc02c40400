#pragma once
// Confidence intervals of a deviation from its equivalent degrees of freedom (chi-squared, NIST SP
// 1065 eq. 45): dev sqrt(edf / chi2_{1-p}) .. dev sqrt(edf / chi2_p), p = (1 - confidence) / 2.
// Quantiles from Boost.Math.

namespace gyrochar {

struct Interval {
  double low = 0.0;
  double high = 0.0;
  bool valid = false;  // false when edf <= 0 (not available) or the confidence is not in (0, 1)
};

/// The interval for deviation `dev` with `edf` degrees of freedom at `confidence` (e.g. 0.683).
/// O(1), may allocate (Boost's quantile); never throws.
Interval confidence_interval(double dev, double edf, double confidence = 0.682689492137086);

}  // namespace gyrochar
