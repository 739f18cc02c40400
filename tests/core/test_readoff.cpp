// The IEEE-952 graphical read-off (readoff.hpp) on exact model curves. Oracles: IEEE Std 952's
// closed forms of the Allan variance (the design brief's table): AVAR = N^2/tau + (2 ln 2/pi) B^2
// + K^2 tau/3, whose minimum over tau for N and K alone is 2 N K / sqrt(3); and the closed form of
// a first-order low-pass filter on white rate noise (the design brief's first-order Gauss-Markov
// formula), which bends the shortest taus below the -1/2 line as a sensor's own filter does.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include "gyrochar/readoff.hpp"

namespace gyrochar {
namespace {

constexpr double ln2 = std::numbers::ln2;
constexpr double flicker = 2.0 * ln2 / std::numbers::pi;  // IEEE 952: AVAR of B is (2 ln 2 / pi) B^2

struct Model {
  double n = 0, b = 0, k = 0;  // rad/s^0.5, rad/s, rad/s^1.5
  double avar(double tau) const { return n * n / tau + flicker * b * b + k * k * tau / 3.0; }
};

// Points at tau0 2^(i / per_octave), i = 0 .. count-1, adev from `avar`, a +-2 % interval.
template <class F>
std::vector<AdevPoint> curve(F avar, double tau0, int count, int per_octave = 1) {
  std::vector<AdevPoint> pts;
  for (int i = 0; i < count; ++i) {
    const double tau = tau0 * std::exp2(static_cast<double>(i) / per_octave);
    const double adev = std::sqrt(avar(tau));
    pts.push_back({tau, adev, 0.98 * adev, 1.02 * adev});
  }
  return pts;
}

void expect_interval_scaled(const ReadoffValue& v) {  // the point's +-2 % scaled like the value
  EXPECT_NEAR(v.ci_low, 0.98 * v.value, 1e-12 * v.value);
  EXPECT_NEAR(v.ci_high, 1.02 * v.value, 1e-12 * v.value);
}

TEST(Readoff, FlickerFactorIsSqrtOfTwoLnTwoOverPi) {
  EXPECT_DOUBLE_EQ(flicker_adev_per_b, std::sqrt(flicker));  // closed form
}

// Each term alone: its line is the curve, read exactly (IEEE 952: N = sigma(1), floor 0.664 B,
// K = sigma(3)).
TEST(Readoff, EachTermAloneIsReadExactly) {
  const Model arw{2e-4, 0, 0}, bias{0, 3e-5, 0}, rrw{0, 0, 4e-6};
  const Readoff n = read_off(curve([&](double t) { return arw.avar(t); }, 0.01, 20));
  ASSERT_TRUE(n.n.valid);
  EXPECT_NEAR(n.n.value, arw.n, 1e-12 * arw.n);
  expect_interval_scaled(n.n);
  EXPECT_FALSE(n.k.valid);      // never rises
  EXPECT_TRUE(n.floor_at_end);  // still falling at the last point
  EXPECT_DOUBLE_EQ(n.floor.tau_s, 0.01 * std::exp2(19.0));

  const Readoff b = read_off(curve([&](double t) { return bias.avar(t); }, 0.01, 20));
  ASSERT_TRUE(b.b.valid);
  EXPECT_NEAR(b.floor.value, flicker_adev_per_b * bias.b, 1e-12 * bias.b);
  EXPECT_NEAR(b.b.value, bias.b, 1e-12 * bias.b);
  expect_interval_scaled(b.b);
  EXPECT_FALSE(b.n.valid);  // slope 0
  EXPECT_FALSE(b.k.valid);

  const Readoff k = read_off(curve([&](double t) { return rrw.avar(t); }, 0.01, 20));
  ASSERT_TRUE(k.k.valid);
  EXPECT_NEAR(k.k.value, rrw.k, 1e-12 * rrw.k);
  expect_interval_scaled(k.k);
  EXPECT_FALSE(k.n.valid);
  EXPECT_TRUE(k.floor_at_end);
  EXPECT_DOUBLE_EQ(k.floor.tau_s, 0.01);
}

// N, B and K a decade or more apart (N/B cross at 100 s, B/K at 10^4 s): N read at the first
// point, K at the last, both just above their line; the floor holds N and K's share, so B read off
// exceeds B: the closed forms bound it.
void check_three_terms(const std::vector<AdevPoint>& pts, const Model& m, double max_ratio) {
  const Readoff r = read_off(pts);
  ASSERT_TRUE(r.n.valid && r.b.valid && r.k.valid);
  const double t1 = pts.front().tau_s, tn = pts.back().tau_s;
  EXPECT_DOUBLE_EQ(r.n.tau_s, t1);
  EXPECT_NEAR(r.n.value, std::sqrt(m.avar(t1) * t1), 1e-12 * m.n);
  EXPECT_GT(r.n.value, m.n);
  EXPECT_LT(r.n.value, 1.0001 * m.n);
  EXPECT_DOUBLE_EQ(r.k.tau_s, tn);
  EXPECT_NEAR(r.k.value, std::sqrt(3.0 * m.avar(tn) / tn), 1e-12 * m.k);
  EXPECT_GT(r.k.value, m.k);
  EXPECT_LT(r.k.value, 1.01 * m.k);
  EXPECT_FALSE(r.floor_at_end);
  // The continuous minimum is flicker B^2 + 2 N K / sqrt(3); a grid point lies above it by at most
  // the factor (r^0.5 + r^-0.5)/2 on the N-K part (r: the grid's step in tau).
  const double nk = 2.0 * m.n * m.k / std::sqrt(3.0);
  EXPECT_GE(r.floor.value * r.floor.value, flicker * m.b * m.b + nk);
  EXPECT_LE(r.floor.value * r.floor.value, flicker * m.b * m.b + max_ratio * nk);
  EXPECT_NEAR(r.b.value, r.floor.value / flicker_adev_per_b, 1e-15 * r.b.value);
  EXPECT_GT(r.b.value, m.b);  // an upper bound: N and K add at the floor
}

TEST(Readoff, ThreeTermsOnAnOctaveGrid) {
  const Model m{1.0, std::sqrt(0.01 / flicker), std::sqrt(3e-6)};
  const auto pts = curve([&](double t) { return m.avar(t); }, 0.01, 27);  // 0.01 s .. 6.7e5 s
  check_three_terms(pts, m, (std::sqrt(2.0) + std::sqrt(0.5)) / 2);
}

TEST(Readoff, ThreeTermsOnADenseGrid) {  // any spacing: eight points an octave
  const Model m{1.0, std::sqrt(0.01 / flicker), std::sqrt(3e-6)};
  const auto pts = curve([&](double t) { return m.avar(t); }, 0.01, 26 * 8 + 1, 8);
  const double r = std::exp2(1.0 / 8);
  check_three_terms(pts, m, (std::sqrt(r) + 1 / std::sqrt(r)) / 2);
}

// White rate noise through a first-order filter of time constant T (the brief's Gauss-Markov
// closed form with N = q_c T): AVAR = N^2/tau [1 - (T / 2 tau)(3 - 4 e^(-tau/T) + e^(-2 tau/T))],
// below the -1/2 line everywhere, by a factor 0.24 at tau = T/2. The points the filter bends
// (slope flatter than -0.4) are not eligible: N is read within 10 % below the truth, where the
// smallest adev sqrt(tau) of all points is 0.24 N.
TEST(Readoff, ASensorsFilterAtShortTausIsNotTakenForTheLine) {
  const double n = 2e-4, T = 0.02;
  const auto avar = [&](double tau) {
    return n * n / tau * (1 - T / (2 * tau) * (3 - 4 * std::exp(-tau / T) + std::exp(-2 * tau / T)));
  };
  const auto pts = curve(avar, 0.01, 16);
  double lowest = std::numeric_limits<double>::infinity();
  for (const AdevPoint& p : pts) lowest = std::min(lowest, p.adev * std::sqrt(p.tau_s));
  EXPECT_LT(lowest, 0.25 * n);
  const Readoff r = read_off(pts);
  ASSERT_TRUE(r.n.valid);
  EXPECT_LT(r.n.value, n);
  EXPECT_GT(r.n.value, 0.9 * n);
  // The closed form's own slope (a central difference of 10^-4 in ln tau) at the tau read.
  const double h = 1e-4, t = r.n.tau_s;
  const double slope = std::log(avar(t * std::exp(h)) / avar(t * std::exp(-h))) / (4 * h);
  EXPECT_LT(std::fabs(slope + 0.5), 0.1);
}

TEST(Readoff, BadPointsAreSkippedAndDisorderReadsNothing) {
  EXPECT_FALSE(read_off({}).floor.valid);
  const Model arw{2e-4, 0, 0};
  auto pts = curve([&](double t) { return arw.avar(t); }, 0.01, 10);
  pts.insert(pts.begin() + 3, AdevPoint{0.05, std::numeric_limits<double>::quiet_NaN(), 0, 0});
  pts.insert(pts.begin(), AdevPoint{0.001, 0.0, 0, 0});  // zero adev: skipped, not a floor
  const Readoff r = read_off(pts);
  ASSERT_TRUE(r.n.valid);
  EXPECT_NEAR(r.n.value, arw.n, 1e-12 * arw.n);
  EXPECT_DOUBLE_EQ(r.floor.tau_s, 0.01 * std::exp2(9.0));
  std::swap(pts[4], pts[6]);
  const Readoff bad = read_off(pts);
  EXPECT_FALSE(bad.n.valid || bad.floor.valid || bad.b.valid || bad.k.valid);
  // A point without an interval gives a value without one.
  pts = curve([&](double t) { return arw.avar(t); }, 0.01, 10);
  for (AdevPoint& p : pts) p.ci_low = p.ci_high = std::numeric_limits<double>::quiet_NaN();
  const Readoff no_ci = read_off(pts);
  ASSERT_TRUE(no_ci.n.valid);
  EXPECT_TRUE(std::isnan(no_ci.n.ci_low) && std::isnan(no_ci.n.ci_high));
}

}  // namespace
}  // namespace gyrochar
