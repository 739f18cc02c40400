// The IEEE-952 graphical read-off (readoff.hpp): the floor in a first pass, then each point's local
// slope from its neighbours an octave away, found by two indices that only move forward.
#include "gyrochar/readoff.hpp"

#include <cmath>

namespace gyrochar {

namespace {

bool usable(const AdevPoint& p) { return std::isfinite(p.tau_s) && p.tau_s > 0 && std::isfinite(p.adev) && p.adev > 0; }

// The next usable index after i, or `end`.
std::size_t next_usable(std::span<const AdevPoint> pts, std::size_t i) {
  do ++i;
  while (i < pts.size() && !usable(pts[i]));
  return i;
}

// The value read at point p with factor f (adev x f), its interval scaled alike.
ReadoffValue read_at(const AdevPoint& p, double f) { return {true, p.adev * f, p.ci_low * f, p.ci_high * f, p.tau_s}; }

// Keeps the candidate with the smaller value (the first on ties: the shortest tau).
void keep_smaller(ReadoffValue& best, const ReadoffValue& candidate) {
  if (!best.valid || candidate.value < best.value) best = candidate;
}

}  // namespace

Readoff read_off(std::span<const AdevPoint> pts, const ReadoffOptions& options) {
  Readoff r;
  const std::size_t end = pts.size();
  std::size_t first = 0;
  while (first < end && !usable(pts[first])) ++first;
  if (first >= end) return r;

  // Pass 1: the floor, the last usable point, and the taus' order.
  std::size_t floor = first, last = first;
  for (std::size_t i = next_usable(pts, first); i < end; i = next_usable(pts, i)) {
    if (!(pts[i].tau_s > pts[last].tau_s)) return r;  // taus out of order: nothing is read
    if (pts[i].adev < pts[floor].adev) floor = i;
    last = i;
  }
  r.floor = read_at(pts[floor], 1.0);
  r.b = read_at(pts[floor], 1.0 / flicker_adev_per_b);
  r.floor_at_end = floor == first || floor == last;

  // Pass 2: local slopes. lo: the last point at or below tau_i / 2 (else the first); hi: the
  // first point at or above 2 tau_i (else the last). The relative tolerance keeps an octave
  // grid's neighbours whatever the rounding of m tau0.
  constexpr double tolerance = 1e-9;
  std::size_t lo = first, hi = first;
  for (std::size_t i = first; i < end; i = next_usable(pts, i)) {
    const double tau = pts[i].tau_s;
    for (std::size_t j = next_usable(pts, lo); j < i && pts[j].tau_s <= 0.5 * tau * (1 + tolerance); j = next_usable(pts, j))
      lo = j;
    if (hi < i) hi = i;
    while (hi != last && pts[hi].tau_s < 2.0 * tau * (1 - tolerance)) hi = next_usable(pts, hi);
    if (lo == hi) continue;  // a single point: no slope
    const double slope = std::log(pts[hi].adev / pts[lo].adev) / std::log(pts[hi].tau_s / pts[lo].tau_s);
    if (i <= floor && std::fabs(slope + 0.5) <= options.slope_band) keep_smaller(r.n, read_at(pts[i], std::sqrt(tau)));
    if (i >= floor && std::fabs(slope - 0.5) <= options.slope_band) keep_smaller(r.k, read_at(pts[i], std::sqrt(3.0 / tau)));
  }
  return r;
}

}  // namespace gyrochar
