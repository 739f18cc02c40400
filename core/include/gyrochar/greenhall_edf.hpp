#pragma once
// Greenhall & Riley's approximation of the equivalent degrees of freedom of the Allan-family
// variance estimators, as Stable32 and allantools compute it (gyrochar's own EDF is the exact one of
// noise_model.hpp; this one serves comparisons with those tools). The algorithm of
// C. A. Greenhall and W. J. Riley, "Uncertainty of stability variances based on finite
// differences", 35th PTTI meeting, 2003 (also NIST SP 1065 section 5.2). Freestanding, no heap.
//
// The estimator is described by d (2: Allan and modified Allan, 3: Hadamard), the filter factor F
// (1: modified variance, m: unmodified), the stride factor S (the summands are m/S samples apart:
// S = 1 non-overlapped, S = m fully overlapped, anything between is the strided estimator of the
// pyramid), the averaging factor m and the number N of PHASE points; the noise by its power-law
// exponent alpha (S_y(f) ~ f^alpha, +2 .. -4), valid where alpha + 2d > 1.
#include <cstdint>

namespace gyrochar {

struct EdfQuery {
  int alpha = 0;          // +2 (white PM) .. -4 (random run FM)
  int d = 2;              // 2 Allan / modified Allan, 3 Hadamard
  double m = 1;           // averaging factor
  bool modified = false;  // modified variance: filter factor F = 1; unmodified: F = m
  double S = 1;           // stride factor, 1 <= S <= m
  double N = 0;           // phase points
};

/// EDF of one estimate, or 0 ("not available") when alpha + 2d <= 1, d is not 2 or 3, alpha is out
/// of range, or there are too few points for a single term (N < m/F + m d). O(1) except the direct
/// sums, which have at most 100 + (d+1) terms when the tables do not apply (O(Jmax)).
double edf_greenhall(const EdfQuery& q);

/// The BasicSum of Greenhall & Riley (their eq. 10) evaluated directly, exposed for tests:
/// 1/EDF = BasicSum(J, M, S, F) / (M sz(0)^2).
double edf_basic_sum_inverse(int alpha, int d, double m, double F, double S, double N);

}  // namespace gyrochar
