#pragma once
// Statistical acceptance for the simulator tests, so that no tolerance is picked by hand.
// - One estimate with known EDF: AVAR_hat ~ AVAR chi2_EDF / EDF, so the true AVAR lies in
//   [EDF AVAR_hat / chi2_{EDF, 1-p/2}, EDF AVAR_hat / chi2_{EDF, p/2}] with probability 1 - p.
// - Several independent estimates (one per seed) of the same expectation: the mean is within
//   t_{S-1, 1-p/2} s / sqrt(S) of it with probability 1 - p (s: the sample standard deviation).
// Quantiles from Boost.Math.
#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/distributions/students_t.hpp>
#include <cmath>
#include <vector>

namespace gyrochar::oracle {

struct Range {
  double low = 0, high = 0;
  bool contains(double v) const { return v >= low && v <= high; }
};

/// Where the true AVAR lies, given an estimate with `edf` degrees of freedom, at probability 1 - p.
inline Range chi2_range(double estimate, double edf, double p) {
  const boost::math::chi_squared chi2(edf);
  return {edf * estimate / boost::math::quantile(chi2, 1 - p / 2), edf * estimate / boost::math::quantile(chi2, p / 2)};
}

struct Spread {
  double mean = 0, sd = 0;
  std::size_t n = 0;
  /// Half-width of the two-sided 1 - p interval of the mean (Student t with n - 1 degrees of freedom).
  double half_width(double p) const {
    const boost::math::students_t t(static_cast<double>(n - 1));
    return boost::math::quantile(t, 1 - p / 2) * sd / std::sqrt(static_cast<double>(n));
  }
};

inline Spread spread(const std::vector<double>& v) {
  Spread s;
  s.n = v.size();
  for (double x : v) s.mean += x;
  s.mean /= static_cast<double>(v.size());
  for (double x : v) s.sd += (x - s.mean) * (x - s.mean);
  s.sd = std::sqrt(s.sd / static_cast<double>(v.size() - 1));
  return s;
}

}  // namespace gyrochar::oracle
