#pragma once
// Power-law phase noise for tests and Monte Carlo studies, and the exact expectations of the
// overlapping Allan and modified Allan variances of that noise (the oracles of the studies).
//
// The model. Phase x (tau0 = 1, innovations w white Gaussian of unit variance) is
//     x = (1 - B)^(-d) w,   d = (2 - alpha) / 2,
// B the backshift operator, so that the fractional frequency y = (1 - B) x has S_y(f) ~ f^alpha:
//     alpha  +2 white PM (d = 0)      +1 flicker PM (d = 1/2)    0 white FM (d = 1)
//            -1 flicker FM (d = 3/2)  -2 random walk FM (d = 2)  -3 flicker walk FM (d = 5/2)
//            -4 random run FM (d = 3)
// Only differences of order D >= d are stationary; the statistics below use D = 2 (AVAR, MVAR)
// and so need alpha >= -2 (alpha -3 and -4 are generated for Hadamard-type statistics, D = 3).
//
// Integer d: x is w summed d times (cumulative sums from the first sample); its D-th differences
// are exactly those of the infinite-past process.
//
// Half-integer d: the integer part is summed as above; the half (1 - B)^(-1/2) is the impulse
// response of Kasdin & Walter (1992), h_0 = 1, h_k = h_{k-1} (k - 1 + d) / k, applied to a white
// series that starts a burn-in of b = n samples before the first returned point (the prefix is
// discarded). The statistics assume the stationary-increment process with an infinite past;
// the truncated filter reproduces every innovation from -b on exactly, so the only error of a
// D-th difference with lag m at time t >= 0 is the innovations before -b, i.e. the filter tail of
// (1 - B^m)^D (1 - B)^(-d) beyond k = b + t + D m. That tail behaves like m^D times the tail of
// (1 - B)^(D - d), which decays as k^-(D - d) - 1: its share of the term's variance is of order
// (m / (b + D m))^(2 (D - d)). It is largest at the first point and the largest octave with a
// term (m = n / 4), where tests/host/test_power_law_noise.cpp computes it exactly: flicker FM
// (D - d = 1/2, the slowest case) 1.8e-3 of the AVAR term and 2.2e-3 of the MVAR term, flicker PM
// (D - d = 3/2) 4.5e-6 and 2.4e-5, the same for n = 65536; at m = n / 16 flicker FM loses 1.6e-4
// and 2.2e-4. Beside the statistical error of one estimate at such m (tens of per cent) and of a
// mean over 10^4 runs (about 1 %), that is negligible: the increments are stationary to that
// accuracy.
//
// Reproducible: the same (alpha, n, seed) gives the same series on every run and every thread
// (std::mt19937_64 feeding std::normal_distribution, libstdc++'s Marsaglia polar method).
//
// Thread safety: every function may be called from several threads at once. The FFT plans and
// the transformed filter are made once per transform length under a lock and kept until exit.
#include <cstdint>
#include <vector>

namespace gyrochar::test_support {

/// Kasdin & Walter's impulse response of (1 - B)^(-d): h_0 = 1, h_k = h_{k-1} (k - 1 + d) / k, for
/// k < n. Any real d (negative d gives the fractional difference). O(n), allocates n doubles.
std::vector<double> kasdin_response(double d, std::size_t n);

/// n phase points of power-law noise with exponent alpha (see above; alpha in -4..+2), tau0 = 1,
/// innovations of unit variance, seeded by `seed`. Integer d: O(n). Half-integer d: O(n log n)
/// (FFT convolution of length 4 n rounded up to a power of two, FFTW3 with FFTW_ESTIMATE plans,
/// which are deterministic). Allocates the result; for half-integer d also a per-thread scratch of
/// about 48 n bytes kept for the next call of the same length, and once per transform length the
/// plans and the filter's transform (kept until exit).
/// Throws std::invalid_argument for alpha outside -4..+2.
std::vector<double> power_law_phase(int alpha, std::size_t n, std::uint64_t seed);

/// Burn-in prefix generated and discarded before n points of half-integer-d noise: n.
std::size_t burn_in_length(std::size_t n);

enum class Variance { avar, mvar };  // overlapping Allan, modified Allan

/// The exact expectation of the overlapping AVAR or the MVAR estimator (the same for every term)
/// of the infinite-past noise of exponent alpha at averaging factor m >= 1, tau0 = 1, innovations of
/// unit variance: the variance of the term divided by 2 m^2 (AVAR) or 2 m^4 (MVAR). The AVAR term
/// x[j+2m] - 2 x[j+m] + x[j] is the filter g = (1 - B^m)^2 (1 - B)^(-d) of w; the MVAR term
/// P[j+3m] - 3 P[j+2m] + 3 P[j+m] - P[j] is g = (1 - B^m)^3 (1 - B)^(-(d+1)) (the phase sums P are
/// one more summation). Its variance is sum_k g_k^2, summed exactly over k < K = 64 m + 1024 with
/// the Kasdin coefficients at the D + 1 lags run in lockstep (no storage), plus the tail beyond K
/// from the asymptote g_k ~ m^D (d-1)(d-2)/Gamma(d) (k - D m / 2)^(d-3), whose own share is below
/// 1e-5 of the sum, so the result's relative error is of order 1e-10. Integer d: the filter has
/// finite support and the sum is exact up to rounding. Closed forms for comparison:
///   white PM   AVAR 3 / m^2              MVAR 3 / m^3
///   white FM   AVAR 1 / m                MVAR (m^2 + 1) / (2 m^3)
///   RW FM      AVAR m / 3 + 1 / (6 m)    MVAR (11 m^4 + 5 m^2 + 4) / (40 m^3)
/// O(m), no allocation. Throws std::invalid_argument for alpha outside -2..+2 or m = 0.
double expected_variance(int alpha, Variance v, std::uint64_t m);

/// The plain partial sum sum_{k < terms} g_k^2 / (2 m^2) or / (2 m^4) behind expected_variance(),
/// without the tail (for tests of the truncation). O(terms), no allocation. Same throws.
double expected_variance_partial(int alpha, Variance v, std::uint64_t m, std::uint64_t terms);

}  // namespace gyrochar::test_support
