#pragma once
// The IEEE Std 952 graphical read-off: N, the bias floor, B and K read off an overlapping Allan
// deviation curve the way gyro data sheets print them, to stand beside the fit of ieee952.hpp.
// Freestanding: no heap, no exceptions; deterministic (the same points give the same values).
//
// Units. The points are in one rate unit r/s (rad/s, deg/h, ...) and tau in s. Then N is in
// r/s^0.5 (rate x sqrt(s)), the floor and B in r/s, K in r/s^1.5 (rate / sqrt(s)).
//
// The read-off (IEEE 952's table: the -1/2 line read at tau = 1 s is N, the flat part is 0.664 B,
// the +1/2 line read at tau = 3 s is K):
//   local slope  of point i: d ln(adev) / d ln(tau) between its neighbours an octave away: the
//                last point with tau <= tau_i / 2 (else the first point) and the first point with
//                tau >= 2 tau_i (else the last point). On an octave grid, its two neighbours; at
//                either end of the curve, one-sided.
//   floor        the smallest adev (the first on ties), its tau and its interval.
//   B            floor / sqrt(2 ln 2 / pi) = floor / 0.664, the flicker-FM floor's IEEE-952 factor.
//   N            the line of slope -1/2 tangent to the curve from below: the smallest
//                adev(tau) sqrt(tau) (= its value at tau = 1 s) over the eligible points, those at or
//                before the floor whose local slope lies within slope_band of -1/2. Where a
//                sensor's own filter bends the shortest taus below the line, their slope is
//                flatter (e.g. -0.35) and they are not eligible.
//   K            the line of slope +1/2 tangent from below: the smallest adev(tau) sqrt(3 / tau)
//                (= its value at tau = 3 s) over the points at or after the floor whose local slope
//                lies within slope_band of +1/2. Not available when the curve never rises so.
// Each value reports the tau of the point it was read at.
//
// Intervals. A value's interval is the chosen point's own confidence interval (from that point's
// EDF, as the caller formed it), scaled by the same factor as the value: sqrt(tau) for N,
// 1/0.664 for B, sqrt(3/tau) for K. It is the sampling uncertainty of that one point; it knows
// nothing of the choice of the point (the minimum over several scattered points is biased low, most
// where they scatter most: the longest taus) nor of the terms mixed in at that tau.
//
// What the read-off is NOT: a separation of the terms. Every point holds all of them. The floor
// includes the N and K contributions (and any hump's) at its tau: N and K alone already make a
// floor, the minimum over tau of N^2/tau + K^2 tau/3 being 2 N K / sqrt(3), so B read off is, but
// for the floor's own sampling error, an upper bound of the flicker term. N and K are read where their line is only nearly tangent, so
// they too carry the other terms (upper bounds as far as the curve lies above the line), except
// where a filter or a correlated term bends the curve below the line (then lower). The IEEE-952
// fit (ieee952.hpp) separates the terms; where it disagrees with the read-off, one of the two
// does not describe the curve, and the report says so.
#include <cstddef>
#include <span>

namespace gyrochar {

/// sqrt(2 ln 2 / pi): the Allan deviation of flicker FM of IEEE-952 coefficient B is this x B.
inline constexpr double flicker_adev_per_b = 0.6642824702679601;

/// One point of an overlapping Allan deviation curve: tau in s; adev and its confidence interval
/// in one rate unit. ci_low / ci_high NaN: the point has no interval (the read-off's is then NaN).
struct AdevPoint {
  double tau_s = 0;
  double adev = 0;
  double ci_low = 0;
  double ci_high = 0;
};

/// One read-off value: valid false when it could not be read (the other fields are then 0).
struct ReadoffValue {
  bool valid = false;
  double value = 0;   // unit: see the header
  double ci_low = 0;  // the chosen point's interval, scaled like the value
  double ci_high = 0;
  double tau_s = 0;  // tau of the point it was read at
};

struct Readoff {
  ReadoffValue n;             // angle random walk N, r/s^0.5
  ReadoffValue floor;         // the smallest adev, r/s
  ReadoffValue b;             // bias instability B = floor / 0.664, r/s
  ReadoffValue k;             // rate random walk K, r/s^1.5
  bool floor_at_end = false;  // the floor is the first or the last point: the curve has not turned there
};

struct ReadoffOptions {
  double slope_band = 0.1;  // a point is on a +-1/2 line when its local slope is within this of it
};

/// Reads N, the floor, B and K off `points` (increasing tau, any spacing; see the header). Points
/// whose tau or adev is not a positive finite number are skipped; when the taus of the others do
/// not strictly increase, or none is left, nothing is read (every value invalid). O(points) (two
/// passes, each neighbour search moving forward only); no allocation; never fails hard.
Readoff read_off(std::span<const AdevPoint> points, const ReadoffOptions& options = {});

}  // namespace gyrochar
