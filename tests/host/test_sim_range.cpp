// The simulator's count range: parameters whose angle could pass max_pulse_total (2^53 pulses)
// over the run are refused up front, naming the largest term; a run that passes it all the same
// stops with an error, never a wrapped or rounded count. Oracles: closed forms of the angle each
// term adds (gyro_sim.hpp; 1 deg/h = 1 arcsec/s, 1 deg/sqrt(h) = 60 arcsec/sqrt(s)) and 2^53.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "gyro_sim.hpp"
#include "sim_truth.hpp"

namespace gyrochar {
namespace {

TEST(SimRange, ARunAtTheLimitIsAcceptedAndOnePastItRefused) {
  // 10^9 deg/h = 10^9 arcsec/s, 1 arcsec per pulse, tau0 1 s: 10^9 pulses per second, so the
  // limit 2^53 = 9007199254740992 falls between 9007199 and 9007200 s.
  SimOptions o;
  o.tau0_s = 1;
  o.pulse_arcsec = 1;
  o.rate_deg_per_h = 1e9;
  o.duration_s = 9007199;
  EXPECT_NEAR(worst_case_pulses(o).total, 9007199e9, 1e3);
  EXPECT_FALSE(check_parameters(o).has_value());
  o.duration_s = 9007200;
  const auto problem = check_parameters(o);
  ASSERT_TRUE(problem.has_value());
  EXPECT_STREQ(problem->what, "--rate");
  EXPECT_NE(problem->why.find("limit of 2^53"), std::string::npos) << problem->why;
}

TEST(SimRange, TheIssuesReproducersAreRefusedNamingTheirTerm) {
  SimOptions arw;  // --duration 5 --tau0 1 --arw 1e20: 10 x 60e20 arcsec x sqrt(5) per arcsec pulse
  arw.duration_s = 5;
  arw.tau0_s = 1;
  arw.arw_deg_per_sqrt_h = 1e20;
  EXPECT_NEAR(worst_case_pulses(arw).largest, 10 * 60e20 * std::sqrt(5.0), 1e-12 * 10 * 60e20 * std::sqrt(5.0));
  const auto a = check_parameters(arw);
  ASSERT_TRUE(a.has_value());
  EXPECT_STREQ(a->what, "--arw");
  SimOptions fast;  // --rate 1e9 --pulse-weight 1e-9 over the default hour: 3.6e12 arcsec / 1e-9
  fast.rate_deg_per_h = 1e9;
  fast.pulse_arcsec = 1e-9;
  EXPECT_NEAR(worst_case_pulses(fast).total, 3.6e21, 1e-9 * 3.6e21);
  const auto f = check_parameters(fast);
  ASSERT_TRUE(f.has_value());
  EXPECT_STREQ(f->what, "--rate");
}

TEST(SimRange, EveryTermCountsAndSegmentsTakeTheirLargestLevel) {
  // Each term alone, 1 arcsec pulses, tau0 1 s, 100 s: its closed form in pulses (arcsec).
  const auto alone = [](auto set) {
    SimOptions o;
    o.tau0_s = 1;
    o.duration_s = 100;
    o.rate_deg_per_h = 0;
    set(o);
    return worst_case_pulses(o);
  };
  const double t = 100;
  EXPECT_NEAR(alone([](SimOptions& o) { o.ramp_deg_per_h2 = 3600; }).total, 1 * t * t / 2,
              1e-9);  // 3600 deg/h/h = 1 arcsec/s^2
  EXPECT_NEAR(alone([](SimOptions& o) { o.white_angle_arcsec = 2; }).total, 10 * 2, 1e-12);
  EXPECT_NEAR(alone([](SimOptions& o) { o.rrw_deg_per_h_sqrt_h = 60; }).total,  // 60 deg/h/sqrt(h) = 1 arcsec/s^1.5
              10 * std::pow(t, 1.5) / std::sqrt(3.0), 1e-9);
  EXPECT_NEAR(alone([](SimOptions& o) { o.dither_arcsec = 7; }).total, 7, 1e-12);
  EXPECT_NEAR(alone([](SimOptions& o) { o.markov.push_back({2, 10}); }).total, 10 * 2 * t, 1e-9);
  EXPECT_NEAR(alone([](SimOptions& o) { o.sinusoids.push_back({3, 0.1}); }).total, 3 / (M_PI * 0.1), 1e-9);
  // A segment quadrupling the rate: the run's largest rate counts.
  const PulseReach stepped = alone([](SimOptions& o) {
    o.rate_deg_per_h = 1;
    SimSegment g;
    g.start_s = 50;
    g.rate_deg_per_h = -4;
    o.segments.push_back(g);
  });
  EXPECT_NEAR(stepped.total, 4 * t, 1e-9);
  EXPECT_STREQ(stepped.largest_what, "--rate");
}

TEST(SimRange, TheSimulatorThrowsRatherThanPassTheLimit) {
  // 1.5 x 2^50 pulses per sample, exactly representable: the total passes 2^53 = 8 x 2^50 at the
  // sixth sample (9 x 2^50); the five before are counted (each within 2 of 1.5 x 2^50: the
  // angle's rounding), the sixth throws.
  GyroParameters p;
  p.tau0_s = 1;
  p.pulse_weight_rad = 4.8481368110953599e-6;
  p.rate_rad_s = 1.5 * std::ldexp(1.0, 50) * p.pulse_weight_rad;
  GyroSimulator sim(p);
  std::int64_t sum = 0;
  for (int k = 1; k <= 5; ++k) {
    const std::int64_t count = sim.next_count();
    EXPECT_NEAR(static_cast<double>(count), 1.5 * std::ldexp(1.0, 50), 2.0) << k;
    sum += count;
  }
  EXPECT_LE(sum, std::int64_t{1} << 53);
  try {
    sim.next_count();
    ADD_FAILURE() << "no error past 2^53 pulses";
  } catch (const std::overflow_error& e) {
    EXPECT_NE(std::string(e.what()).find("sample 6: "), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("2^53"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace gyrochar
