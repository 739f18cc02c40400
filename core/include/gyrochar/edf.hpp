#pragma once
// Equivalent degrees of freedom of the Allan-family variance estimators, by the algorithm of
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

/// The statistics of this project.
enum class EdfStat : std::uint8_t {
  avar,   // overlapping (or strided) Allan: d = 2, F = m
  mvar,   // modified Allan (and TVAR): d = 2, F = 1
  hvar,   // overlapping (or strided) Hadamard: d = 3, F = m
};

/// EDF of statistic `stat` at averaging factor m with terms formed every `stride` points
/// (stride 1: fully overlapped, stride m: non-overlapped) over N phase points. O(Jmax).
double edf_for(EdfStat stat, int alpha, std::uint64_t m, std::uint64_t stride, std::uint64_t n_phase_points);

/// Terms an unbroken run of N phase points forms at averaging factor m with terms every `stride`
/// points on the global grid (newest point e >= 2m for AVAR, e >= 3m - 1 for MVAR, e >= 3m for
/// HVAR, e < N). O(1).
std::uint64_t unbroken_terms(EdfStat stat, std::uint64_t m, std::uint64_t stride, std::uint64_t n_phase_points);

/// EDF of a run that gaps split into segments: the EDF of an unbroken run of the same phase points
/// scaled by the share of its terms actually formed (`terms`; those spanning a gap are not).
/// Equal to edf_for() without gaps; against the pooled EDF of independent segments (the sum of
/// their EDFs) it is 0 to 4 % low for segments of 25 m or longer (tests/core/test_edf.cpp), so the
/// intervals are, if anything, slightly wide. O(Jmax).
double edf_for_terms(EdfStat stat, int alpha, std::uint64_t m, std::uint64_t stride, std::uint64_t n_phase_points,
                     std::uint64_t terms);

/// The BasicSum of Greenhall & Riley (their eq. 10) evaluated directly, exposed for tests:
/// 1/EDF = BasicSum(J, M, S, F) / (M sz(0)^2).
double edf_basic_sum_inverse(int alpha, int d, double m, double F, double S, double N);

}  // namespace gyrochar
