#pragma once
// The exact expected Allan and modified Allan variances of gyrochar-sim's Gauss-Markov and
// sinusoidal rate terms, as the simulator makes them (gyro_sim.hpp) and as the fully overlapped
// estimators measure them from the phase x (the cumulative angle at the sample instants):
//   AVAR(n) = E[(x[j+2n] - 2x[j+n] + x[j])^2] / (2 n^2 tau0^2),
//   MVAR(n) = E[(sum_{i=j}^{j+n-1} x[i+2n] - 2x[i+n] + x[i])^2] / (2 n^4 tau0^2),
// tau = n tau0. Results are in the square of the rate unit the amplitude is given in.
// docs/metrology.md ("The simulator and its conventions") derives them; tests/host/
// test_sim_markov_sinusoid.cpp checks them against the defining double sums and the simulator.
//
// Gauss-Markov: the rate held over interval k is the stationary AR(1) y_k = phi y_{k-1} +
// sigma sqrt(1 - phi^2) e_k, phi = exp(-tau0 / Tc), of variance sigma^2 and autocovariance
// sigma^2 phi^|d|. A term is tau0 sum_t w_t y_t with weights w on 2n rates (AVAR: -1 n times, then
// +1 n times) or on 3n - 1 rates (MVAR: a triangle 1, 2 .. n .. 2, 1 subtracted, the same triangle
// n samples later added), so E[term^2] = tau0^2 sigma^2 sum_{t,t'} w_t w_t' phi^|t-t'|. Summed in
// closed form, with e = 1 - phi and u = 1 - phi^n:
//   AVAR(n) = sigma^2 [n (1 + phi) / e - phi u (2 + u) / e^2] / n^2
//           = sigma^2 (n - 3 phi - n phi^2 + 4 phi^(n+1) - phi^(2n+1)) / (n^2 (1 - phi)^2)
//     (N. F. Zhang, Metrologia 45 (2008), whose s^2 is the innovation variance sigma^2 (1 - phi^2)),
//   MVAR(n) = sigma^2 [n (n^2 + 1)(1 + phi) / e - 6 n phi / e^2 - 12 n phi^2 / e^3
//                      + 2 phi^2 u (6 + 3u + u^2) / e^4] / (2 n^4).
// Both cancel as n tau0 / Tc goes to 0 (the terms grow as (Tc / tau)^3 and (Tc / tau)^4 times the
// result); there, below n tau0 / Tc = 0.1, the same expectation is summed exactly in O(n) as a
// sum of squares (the innovations representation: sum_t w_t y_t = g_1 y_1 +
// sum_{t>=2} g_t sigma sqrt(1 - phi^2) e_t, g_t = w_t + phi g_{t+1}). Long double throughout:
// relative error below 1e-13 (measured 1.4e-14 against the defining double sums).
//
// Sinusoid A sin(2 pi f t + phi0), phi0 uniform, integrated exactly over each interval: the phase
// is the sampled angle -(A / (2 pi f)) cos(2 pi f t_k + phi0), whose terms are sinusoids in j;
// averaged over phi0,
//   AVAR(tau) = A^2 (sin^2(pi f tau) / (pi f tau))^2,
//   MVAR(n)   = A^2 sin^6(pi f tau) / ((pi f tau)^2 n^2 sin^2(pi f tau0)).
// One run's estimate (one phi0, M terms) differs from these by at most 1 / (M |sin(2 pi f tau0)|)
// relative: the mean of cos^2 over M terms of a sinusoid of step 2 pi f tau0.
#include <cstdint>

namespace gyrochar {

/// Expected overlapping AVAR at tau = n tau0 of a Gauss-Markov rate of stationary variance
/// `sigma2` and correlation time tc_s (the simulator's convention above), in sigma2's unit.
/// Expects n >= 1, tau0_s > 0, tc_s > 0. O(1) when n tau0 >= 0.1 tc, else O(n); no allocation.
double markov_avar(double sigma2, double tau0_s, double tc_s, std::uint64_t n);

/// Expected overlapping MVAR at tau = n tau0 of the same. Same expectations and cost.
double markov_mvar(double sigma2, double tau0_s, double tc_s, std::uint64_t n);

/// AVAR at tau_s of a sinusoidal rate of amplitude `amplitude` and frequency f (Hz), averaged over
/// its phase. O(1).
double sinusoid_avar(double amplitude, double frequency_hz, double tau_s);

/// MVAR at tau = n tau0 of the same. Expects sin(pi f tau0) != 0 (f below the Nyquist frequency).
/// O(1).
double sinusoid_mvar(double amplitude, double frequency_hz, double tau0_s, std::uint64_t n);

}  // namespace gyrochar
