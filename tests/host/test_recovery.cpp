// The recovery study (docs/metrology.md, tests/benchmarks/recovery_study.cpp) in small: simulated
// gyros through the analyzer and the recommended IEEE-952 fit. Oracle: the simulator's parameters
// (sim_truth.hpp). Loose bounds, 4 standard errors from the study's targets over the pooled runs:
// resolved terms within 2 stated sigma of the truth in at least 80 % (target 95 %, standard error
// about 3 points here), terms of zero truth called resolved in at most 15 % (target 5 %), every fit
// usable, and the periodic quantization of a rate below one pulse per sample found.
#include <gtest/gtest.h>

#include <cstdint>
#include <string>

#include "support/recovery.hpp"

namespace gyrochar::test_support {
namespace {

TEST(Recovery, SimulatedGyrosComeBackWithinTheirStatedUncertainties) {
  RecoverySettings s;
  s.scenarios.clear();
  for (const Scenario& full : standard_scenarios()) {
    // Half an hour (at tau0 0.1 s but for the periodic quantization, which needs its 0.01 s to stay
    // below one pulse per sample): enough taus for three terms, fast enough for the suite.
    if (full.name != "ARW + bias instability" && full.name != "ARW + rate ramp" && full.name != "ARW, periodic quantization")
      continue;
    Scenario short_run = full;
    short_run.sim.duration_s = 1800;
    if (full.name != "ARW, periodic quantization") short_run.sim.tau0_s = 0.1;  // 0.15 pulse per sample kept
    s.scenarios.push_back(short_run);
  }
  ASSERT_EQ(s.scenarios.size(), 3u);
  s.runs = 16;
  const auto cells = run_recovery_study(s);
  std::size_t resolved = 0, within2 = 0, absent = 0, false_resolved = 0;
  for (const RecoveryCell& c : cells) {
    EXPECT_EQ(c.ok, c.runs) << c.scenario << ": every fit usable";
    for (const TermTally& t : c.terms) {
      resolved += t.resolved - t.false_resolved;
      within2 += t.within2;
      absent += t.runs - t.present;
      false_resolved += t.false_resolved;
    }
    std::printf("%s: N resolved in %zu of %zu, within 1 sigma %zu, 2 sigma %zu; chi2/dof %.2f\n", c.scenario.c_str(),
                c.terms[1].resolved, c.runs, c.terms[1].within1, c.terms[1].within2, c.mean_chi2_per_dof);
  }
  ASSERT_GT(resolved, 0u);
  EXPECT_GE(static_cast<double>(within2) / static_cast<double>(resolved), 0.80) << within2 << " of " << resolved;
  EXPECT_LE(static_cast<double>(false_resolved) / static_cast<double>(absent), 0.15) << false_resolved << " of " << absent;
  const RecoveryCell& periodic = cells.at(0);
  EXPECT_EQ(periodic.scenario, "ARW, periodic quantization");
  EXPECT_EQ(periodic.quantization_white, 0u) << "a rate of 0.15 pulse per sample without dither is periodic";
}

TEST(Recovery, ASinusoidIsNotTakenForAQuantizationPattern) {
  // gyrochar-sim --duration 28800 --tau0 0.1 --white-angle 1 --arw 0.02 --markov 0.5,300
  // --sinusoid 0.5,0.01 --seed 65: one run of the study's "ARW + sinusoid + Markov", the sinusoid
  // offered as the record's spectrum finds it. White angle noise of a pulse rms a sample makes the
  // quantization white (gyrochar-sim's rule). The quantization test's fit once held the five terms
  // alone: under the sinusoid's hump they departed at the short taus, the quantization was taken for
  // a pattern, its taus left out and Q held at the quantization's white level beside the white
  // angle noise: rejected, chi2/dof 7.9 on 23 points. Oracle: the simulator's white quantization
  // and its sinusoid's amplitude, within 3 stated sigma.
  SimOptions sim;
  sim.duration_s = 28800;
  sim.tau0_s = 0.1;
  sim.white_angle_arcsec = 1;
  sim.arw_deg_per_sqrt_h = 0.02;
  sim.markov = {{0.5, 300}};
  sim.sinusoids = {{0.5, 0.01}};
  sim.seed = 65;
  const Recovery r = recover(sim);
  const Ieee952Fit& f = r.fit();
  ASSERT_TRUE(f.ok()) << name(f.status) << ", chi2/dof " << f.chi2_per_dof() << " on " << f.points << " points";
  EXPECT_TRUE(f.quantization_white);
  ASSERT_EQ(f.n_sinusoids, 1u);
  ASSERT_EQ(r.truth.sinusoids.size(), 1u);
  const Ieee952Parameter& a = f.sinusoids[0].amplitude;
  EXPECT_NEAR(a.value, r.truth.sinusoids[0].amplitude_rad_s, 3 * a.uncertainty);
}

// The simulator's options of the study's scenario `name`, with the seed given.
SimOptions study_gyro(const std::string& name, std::uint64_t seed) {
  for (const Scenario& s : standard_scenarios())
    if (s.name == name) {
      SimOptions sim = s.sim;
      sim.seed = seed;
      return sim;
    }
  ADD_FAILURE() << "no scenario " << name;
  return {};
}

TEST(Recovery, AMarkovTermThatDoesAsWellInKsPlaceLeavesKUnresolved) {
  // gyrochar-sim --duration 28800 --tau0 0.1 --white-angle 1 --arw 0.02 --markov 0.5,20
  // --markov 0.4,1500 --seed 7: one run of the study's "ARW + two Markov terms". The model chosen
  // is one Markov term (20 s) and K = 0.61(10) deg/h/sqrt(h); its runner-up, the five terms alone,
  // is far behind, so K was "resolved" where none was simulated. The second Markov term in K's
  // place describes the curve as well: K is not resolved, and says which term could stand for it.
  // Oracle: the simulator's K of zero; the Markov term's Tc within a factor 2 of its 1 500 s.
  const Recovery r = recover(study_gyro("ARW + two Markov terms", 7));
  const Ieee952Fit& f = r.fit();
  ASSERT_TRUE(f.ok()) << name(f.status) << ", chi2/dof " << f.chi2_per_dof();
  ASSERT_EQ(r.truth.k_rad_s_sqrt_s, 0.0);
  const Ieee952Parameter& k = f.p[3];
  ASSERT_TRUE(k.fitted) << "the case: K in the chosen model";
  EXPECT_FALSE(k.resolved);
  EXPECT_TRUE(k.doubted);
  EXPECT_GT(k.markov_in_place_tc_s, 750.0);
  EXPECT_LT(k.markov_in_place_tc_s, 3000.0);
}

TEST(Recovery, AMarkovTermInBsPlaceIsTheModelWhereTheCriterionPrefersIt) {
  // --seed 12284238937601492669: run 48 of the study's "ARW + two Markov terms" (its seeds, the
  // scenarios "ARW + two Markov terms" alone). Beside a free B the second Markov term was not
  // significant, so the model stayed at one Markov term and B, and was rejected on its exact
  // covariance (chi2/dof 49.8). With B held at zero and the second term sought above the first,
  // the criterion prefers the two terms. Oracle: the simulator's terms; the fit's own acceptance.
  const Recovery r = recover(study_gyro("ARW + two Markov terms", 12284238937601492669u));
  const Ieee952Fit& f = r.fit();
  ASSERT_TRUE(f.ok()) << name(f.status) << ", chi2/dof " << f.chi2_per_dof();
  ASSERT_EQ(f.n_markov, 2u);
  EXPECT_TRUE(f.p[2].held_for_markov);
  EXPECT_FALSE(f.p[2].fitted);
  for (std::size_t j = 0; j < 2; ++j) {  // each term within a factor 2 of its simulated Tc
    const double truth = r.truth.markov[j].tc_s;
    EXPECT_GT(f.markov[j].tc_s, truth / 2) << j;
    EXPECT_LT(f.markov[j].tc_s, truth * 2) << j;
  }
}

TEST(Recovery, AModelTheRecordCannotTellApartWidensTheTermsBothHold) {
  // --seed 8053062980868484603: run 81 of the study's "ARW + two Markov terms" (its seeds, the
  // scenario alone). The model chosen is one Markov term (20 s) and B, not resolved; a second Markov
  // term in B's place (about 400 s) describes the curve as well. Stated with the chosen model's
  // uncertainties alone, N lay 2.04 and the Markov term's sigma 2.40 stated sigma below the truth;
  // with the two models' difference in their uncertainties, both lie within two. Oracle: the
  // simulator's N and sigma.
  const Recovery r = recover(study_gyro("ARW + two Markov terms", 8053062980868484603u));
  const Ieee952Fit& f = r.fit();
  ASSERT_TRUE(f.ok()) << name(f.status) << ", chi2/dof " << f.chi2_per_dof();
  ASSERT_EQ(f.n_markov, 1u) << "the case: one Markov term";
  ASSERT_TRUE(f.p[2].fitted) << "the case: B beside it";
  EXPECT_FALSE(f.p[2].resolved);
  EXPECT_GT(f.p[2].markov_in_place_tc_s, f.markov[0].tc_s * 4) << "the second term lies above the first";
  const Ieee952Parameter& n = f.p[1];
  EXPECT_NEAR(n.value, r.truth.n_rad_sqrt_s, 2 * n.uncertainty);
  const Ieee952Parameter& sigma = f.markov[0].sigma;
  EXPECT_NEAR(sigma.value, r.truth.markov[0].sigma_rad_s, 2 * sigma.uncertainty);
}

TEST(Recovery, BIsNotResolvedWhereAMarkovTermInItsPlaceHasTheSameChi2) {
  // --seed 2793117216776941401: a run of the study's "ARW + two Markov terms" (20 s and 1 500 s, no
  // flicker). The model is the 20 s term and B; a Markov term in B's place has a chi2 1.6 lower, but
  // its correlation time and sigma cost three parameters against B's one, so by the criterion it
  // came 9.0 behind, and B was "resolved" at 0.172(31) deg/h where none was simulated. The record
  // cannot tell the two apart: by chi2 they are within 2 ln 19. Oracle: the simulator (no B).
  const Recovery r = recover(study_gyro("ARW + two Markov terms", 2793117216776941401u));
  const Ieee952Fit& f = r.fit();
  ASSERT_TRUE(f.ok()) << name(f.status) << ", chi2/dof " << f.chi2_per_dof();
  ASSERT_EQ(r.truth.b_rad_s, 0.0);
  ASSERT_EQ(f.n_markov, 1u) << "the case: one Markov term";
  ASSERT_TRUE(f.p[2].fitted) << "the case: B beside it";
  EXPECT_FALSE(f.p[2].resolved) << f.p[2].value << " +- " << f.p[2].uncertainty;
  EXPECT_GT(f.p[2].markov_in_place_tc_s, f.markov[0].tc_s * 4) << "the other model's term lies above the first";
}

TEST(Recovery, ATermTheModelDifferenceLeavesNearZeroIsNotResolved) {
  // --seed 3664443773633945612: a run of the study's "ARW + Markov, periodic quantization". The
  // model is the Markov term and K, and a second Markov term in K's place does as well, so the
  // Markov term's sigma takes the difference between the two models into its uncertainty. It was
  // "resolved" at 0.422(136) deg/h, judged before that: its square 1.6 of its wider standard
  // uncertainties above zero. Oracle: the definition of resolved (ieee952.hpp), a square more than
  // two standard uncertainties above zero, value > 4 u, for every term.
  const Recovery r = recover(study_gyro("ARW + Markov, periodic quantization", 3664443773633945612u));
  const Ieee952Fit& f = r.fit();
  ASSERT_TRUE(f.ok()) << name(f.status) << ", chi2/dof " << f.chi2_per_dof();
  ASSERT_EQ(f.n_markov, 1u) << "the case: one Markov term";
  ASSERT_GT(f.p[3].markov_in_place_tc_s, 0) << "the case: a Markov term in K's place does as well";
  EXPECT_FALSE(f.markov[0].sigma.resolved) << f.markov[0].sigma.value << " +- " << f.markov[0].sigma.uncertainty;
  for (std::size_t t = 0; t < f.p.size(); ++t) {
    if (f.p[t].resolved) {
      EXPECT_GT(f.p[t].value, 4 * f.p[t].uncertainty) << "term " << t;
    }
  }
}

}  // namespace
}  // namespace gyrochar::test_support
