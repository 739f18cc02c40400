// gyrochar-sim's truth line: what the writer formats, the parser reads back (every parameter
// exactly, the IEEE-952 truth to the last bits of its unit conversion), what it refuses, and what
// the program itself writes. Oracles: the options given (round trip), the closed-form truth
// Q = sqrt(q^2 + pulse^2 / 12) in arcsec, the identity of N, B, K, R in the fit's units and of the
// Gauss-Markov and sinusoidal terms in SI (deg/h times units::deg_per_h).
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <string>

#include "gyro_sim.hpp"
#include "sim_truth.hpp"
#include "support/shell.hpp"

namespace gyrochar {
namespace {

void expect_same_options(const SimOptions& a, const SimOptions& b) {
  EXPECT_EQ(a.duration_s, b.duration_s);
  EXPECT_EQ(a.tau0_s, b.tau0_s);
  EXPECT_EQ(a.pulse_arcsec, b.pulse_arcsec);
  EXPECT_EQ(a.rate_deg_per_h, b.rate_deg_per_h);
  EXPECT_EQ(a.white_angle_arcsec, b.white_angle_arcsec);
  EXPECT_EQ(a.arw_deg_per_sqrt_h, b.arw_deg_per_sqrt_h);
  EXPECT_EQ(a.rrw_deg_per_h_sqrt_h, b.rrw_deg_per_h_sqrt_h);
  EXPECT_EQ(a.bias_deg_per_h, b.bias_deg_per_h);
  EXPECT_EQ(a.bias_time_s, b.bias_time_s);
  EXPECT_EQ(a.ramp_deg_per_h2, b.ramp_deg_per_h2);
  EXPECT_EQ(a.dither_arcsec, b.dither_arcsec);
  EXPECT_EQ(a.dither_hz, b.dither_hz);
  EXPECT_EQ(a.seed, b.seed);
  EXPECT_EQ(a.segments, b.segments);
  EXPECT_EQ(a.markov, b.markov);
  EXPECT_EQ(a.sinusoids, b.sinusoids);
}

// `line` with its first `from` replaced by `to` (a failure when there is none).
std::string replaced_in(std::string line, const std::string& from, const std::string& to) {
  const auto at = line.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return at == std::string::npos ? line : line.replace(at, from.size(), to);
}

SimOptions awkward() {
  SimOptions o;
  o.duration_s = 14400.000000000002;
  o.tau0_s = 0.1;
  o.pulse_arcsec = 1.0 / 3;
  o.rate_deg_per_h = -15.041;
  o.white_angle_arcsec = 2.5e-7;
  o.arw_deg_per_sqrt_h = 0.005;
  o.rrw_deg_per_h_sqrt_h = 0.15;
  o.bias_deg_per_h = 0.05;
  o.bias_time_s = 3.3e4;
  o.ramp_deg_per_h2 = 1e-3;
  o.dither_arcsec = 120;
  o.dither_hz = 437.3;
  o.seed = std::numeric_limits<std::uint64_t>::max();
  return o;
}

// awkward() with two Gauss-Markov terms and two sinusoids (tau0 0.1 s: below 5 Hz).
SimOptions with_rate_terms() {
  SimOptions o = awkward();
  o.markov = {{0.05, 300}, {1.0 / 3, 0.07}};
  o.sinusoids = {{0.02, 0.01}, {2e-3, 4.999}};
  return o;
}

TEST(SimHeader, RoundTripKeepsEveryParameterExactly) {
  for (const SimOptions& o : {SimOptions{}, awkward(), with_rate_terms()}) {
    const std::string line = format_sim_truth_line(o);
    ASSERT_EQ(line.rfind("# gyrochar-sim truth: format=1 ", 0), 0u) << line;
    const auto t = parse_sim_truth_line(line);
    ASSERT_TRUE(t) << line;
    expect_same_options(t->options, o);
    const Ieee952Truth want = ieee952_truth(o);
    EXPECT_NEAR(t->truth.q_rad, want.q_rad, 1e-15 * want.q_rad);
    EXPECT_NEAR(t->truth.n_rad_sqrt_s, want.n_rad_sqrt_s, 1e-15 * want.n_rad_sqrt_s);
    EXPECT_NEAR(t->truth.b_rad_s, want.b_rad_s, 1e-15 * want.b_rad_s);
    EXPECT_NEAR(t->truth.k_rad_s_sqrt_s, want.k_rad_s_sqrt_s, 1e-15 * want.k_rad_s_sqrt_s);
    EXPECT_NEAR(t->truth.r_rad_s2, want.r_rad_s2, 1e-15 * want.r_rad_s2);
    EXPECT_EQ(t->truth.quantization_white, want.quantization_white);
    EXPECT_EQ(t->truth.markov, want.markov);
    EXPECT_EQ(t->truth.sinusoids, want.sinusoids);
    EXPECT_TRUE(parse_sim_truth_line(line + "\r\n"));
  }
}

TEST(SimHeader, RateTermsAreListedOnlyWhenThereAreSome) {
  // Without terms the line is what it always was (no key added), and it reads back without terms.
  const std::string plain = format_sim_truth_line(awkward());
  EXPECT_EQ(plain.find("markov"), std::string::npos);
  EXPECT_EQ(plain.find("sinusoid"), std::string::npos);
  const auto old = parse_sim_truth_line(plain);
  ASSERT_TRUE(old);
  EXPECT_TRUE(old->options.markov.empty() && old->truth.markov.empty());
  EXPECT_TRUE(old->options.sinusoids.empty() && old->truth.sinusoids.empty());
  // With terms: counts and indexed keys in the options' units, the truth in SI.
  const SimOptions o = with_rate_terms();
  const std::string line = format_sim_truth_line(o);
  EXPECT_NE(line.find(" Q_white=yes markov_terms=2 markov1_sigma_deg_per_h=0.05 markov1_tc_s=300"
                      " markov2_sigma_deg_per_h=0.3333333333333333 markov2_tc_s=0.07 sinusoid_terms=2"
                      " sinusoid1_amplitude_deg_per_h=0.02 sinusoid1_frequency_hz=0.01"
                      " sinusoid2_amplitude_deg_per_h=0.002 sinusoid2_frequency_hz=4.999"),
            std::string::npos)
      << line;
  const Ieee952Truth t = ieee952_truth(o);
  ASSERT_EQ(t.markov.size(), 2u);
  EXPECT_DOUBLE_EQ(t.markov[0].sigma_rad_s, 0.05 * units::deg_per_h);
  EXPECT_EQ(t.markov[0].tc_s, 300);
  ASSERT_EQ(t.sinusoids.size(), 2u);
  EXPECT_DOUBLE_EQ(t.sinusoids[1].amplitude_rad_s, 2e-3 * units::deg_per_h);
  EXPECT_EQ(t.sinusoids[1].frequency_hz, 4.999);
  // What a reader refuses: a term without its count, a count without its terms, an index beyond
  // the count or beyond 4, a term missing a number, a number twice, terms check_parameters refuses.
  auto replaced = [&line](const std::string& from, const std::string& to) { return replaced_in(line, from, to); };
  EXPECT_FALSE(parse_sim_truth_line(replaced(" markov_terms=2", "")));
  EXPECT_FALSE(parse_sim_truth_line(plain + " markov_terms=1"));
  EXPECT_FALSE(parse_sim_truth_line(plain + " sinusoid1_amplitude_deg_per_h=1 sinusoid1_frequency_hz=1"));
  EXPECT_FALSE(parse_sim_truth_line(replaced("markov_terms=2", "markov_terms=1")));
  EXPECT_FALSE(parse_sim_truth_line(replaced("markov_terms=2", "markov_terms=3")));
  EXPECT_FALSE(parse_sim_truth_line(replaced("markov_terms=2", "markov_terms=0")));
  EXPECT_FALSE(parse_sim_truth_line(line + " markov_terms=2"));
  EXPECT_FALSE(parse_sim_truth_line(replaced(" markov2_tc_s=0.07", "")));
  EXPECT_FALSE(parse_sim_truth_line(replaced(" sinusoid1_frequency_hz=0.01", "")));
  EXPECT_FALSE(parse_sim_truth_line(line + " markov1_tc_s=300"));
  EXPECT_FALSE(parse_sim_truth_line(replaced("markov_terms=2", "markov_terms=5") +
                                    " markov3_sigma_deg_per_h=1 markov3_tc_s=1 markov4_sigma_deg_per_h=1 markov4_tc_s=1"
                                    " markov5_sigma_deg_per_h=1 markov5_tc_s=1"));
  EXPECT_FALSE(parse_sim_truth_line(replaced("markov1_tc_s=300", "markov1_tc_s=0")));
  EXPECT_FALSE(parse_sim_truth_line(replaced("markov1_tc_s=300", "markov1_tc_s=x")));
  EXPECT_FALSE(parse_sim_truth_line(replaced("sinusoid2_frequency_hz=4.999", "sinusoid2_frequency_hz=5")));  // Nyquist
  // A field of a later format is ignored, as any unknown key.
  const auto later = parse_sim_truth_line(line + " markov1_phase_rad=1");
  ASSERT_TRUE(later);
  EXPECT_EQ(later->options.markov, o.markov);
}

TEST(SimHeader, RateTermOptionsAndTheirLimits) {
  std::string why;
  const auto m = parse_markov_option("0.05,300", why);
  ASSERT_TRUE(m) << why;
  EXPECT_EQ(*m, (SimMarkov{0.05, 300}));
  const auto g = parse_sinusoid_option("2e-3,4.999", why);
  ASSERT_TRUE(g) << why;
  EXPECT_EQ(*g, (SimSinusoid{2e-3, 4.999}));
  for (const char* bad : {"", "1", "1,", ",1", "1,2,3", "1;2", "x,1", "1,nan", "inf,1", "1 ,2"}) {
    why.clear();
    EXPECT_FALSE(parse_markov_option(bad, why)) << bad;
    EXPECT_NE(why.find("SIGMA,TC"), std::string::npos) << why;
    EXPECT_FALSE(parse_sinusoid_option(bad, why)) << bad;
  }
  // check_parameters: each limit, naming the option (tau0 0.01 s: the Nyquist frequency is 50 Hz).
  const auto problem = [](auto change) {
    SimOptions o;
    change(o);
    const auto p = check_parameters(o);
    return p ? std::string(p->what) + ": " + p->why : std::string();
  };
  EXPECT_EQ(problem([](SimOptions& o) { o.markov = {{1, 10}, {1, 10}, {1, 10}, {1, 10}}; }), "");
  EXPECT_EQ(problem([](SimOptions& o) { o.markov.assign(5, {1, 10}); }), "--markov: at most 4 Gauss-Markov terms");
  EXPECT_EQ(problem([](SimOptions& o) { o.markov = {{0, 10}}; }), "--markov: SIGMA must be positive and at most 10^9 deg/h");
  EXPECT_EQ(problem([](SimOptions& o) {
              o.markov = {{2e9, 10}};
            }),
            "--markov: SIGMA must be positive and at most 10^9 deg/h");
  EXPECT_EQ(problem([](SimOptions& o) { o.markov = {{1, 0}}; }), "--markov: TC must be positive and finite (s)");
  EXPECT_EQ(problem([](SimOptions& o) { o.markov = {{1, -1}}; }), "--markov: TC must be positive and finite (s)");
  EXPECT_EQ(problem([](SimOptions& o) { o.sinusoids = {{0, 49.99}}; }), "");
  EXPECT_EQ(problem([](SimOptions& o) { o.sinusoids.assign(5, {1, 1}); }), "--sinusoid: at most 4 sinusoids");
  EXPECT_EQ(problem([](SimOptions& o) { o.sinusoids = {{-1, 1}}; }), "--sinusoid: AMP must be between 0 and 10^9 deg/h");
  for (double f : {0.0, -1.0, 50.0, 1e300})
    EXPECT_EQ(problem([f](SimOptions& o) {
                o.sinusoids = {{1, f}};
              }),
              "--sinusoid: FREQ must be above 0 and below the Nyquist frequency 1/(2 tau0) = 50 Hz")
        << f;
}

TEST(SimHeader, TruthIsTheIeee952Model) {
  // Q = sqrt(q^2 + pulse^2 / 12); N, B, K, R as given, in SI.
  const SimOptions o = awkward();
  const Ieee952Truth t = ieee952_truth(o);
  const double q_arcsec = std::sqrt(o.white_angle_arcsec * o.white_angle_arcsec + o.pulse_arcsec * o.pulse_arcsec / 12);
  EXPECT_NEAR(t.q_rad, q_arcsec * units::arcsec, 1e-15 * t.q_rad);
  EXPECT_DOUBLE_EQ(t.n_rad_sqrt_s, 0.005 * units::deg_per_sqrt_h);
  EXPECT_DOUBLE_EQ(t.b_rad_s, 0.05 * units::deg_per_h);
  EXPECT_DOUBLE_EQ(t.k_rad_s_sqrt_s, 0.15 * units::deg_per_h_sqrt_h);
  EXPECT_DOUBLE_EQ(t.r_rad_s2, 1e-3 * units::deg_per_h_per_h);
  // 1 arcsec pulses, nothing else: Q = 1/sqrt(12) arcsec = 0.288675 arcsec, written as such.
  const SimOptions plain;
  EXPECT_NE(format_sim_truth_line(plain).find(" Q_arcsec=0.28867513459481287 "), std::string::npos);
}

TEST(SimHeader, QuantizationWhitenessFlag) {
  SimOptions o;  // earth rate, 1 arcsec pulses, tau0 0.01 s: 0.15 pulse per sample, periodic
  EXPECT_FALSE(quantization_expected_white(o));
  o.arw_deg_per_sqrt_h = 0.003;  // 0.018 arcsec per sample
  EXPECT_FALSE(quantization_expected_white(o));
  o.arw_deg_per_sqrt_h = 1.0 / 60 / std::sqrt(o.tau0_s);  // one pulse per sample
  EXPECT_TRUE(quantization_expected_white(o));
  o = SimOptions{};
  o.white_angle_arcsec = 0.7;  // increment 0.99 pulse
  EXPECT_FALSE(quantization_expected_white(o));
  o.white_angle_arcsec = 1 / std::sqrt(2.0);  // increment sqrt(2) q = 1 pulse
  EXPECT_TRUE(quantization_expected_white(o));
  o = SimOptions{};
  o.dither_arcsec = 5;
  o.dither_hz = 437.3;  // 0.373 cycle per sample after aliasing: up to 9 pulses per sample
  EXPECT_TRUE(quantization_expected_white(o));
  o.dither_hz = 400;  // synchronous with the sampling: invisible
  EXPECT_FALSE(quantization_expected_white(o));
  o.dither_hz = 100.3;  // 0.003 cycle per sample: 0.09 pulse per sample
  EXPECT_FALSE(quantization_expected_white(o));
  // A sinusoidal rate moves the angle as a dither of angle amplitude A / (2 pi f) would.
  o = SimOptions{};
  o.sinusoids = {{2 * units::pi * 37.3 * 5, 37.3}};  // 5 arcsec at 0.373 cycle per sample: 9 pulses
  EXPECT_TRUE(quantization_expected_white(o));
  o.sinusoids = {{1, 0.01}};  // 16 arcsec at 1e-4 cycle per sample: 0.01 pulse per sample
  EXPECT_FALSE(quantization_expected_white(o));
  o.sinusoids = {};
  o.markov = {{1e6, 10}};  // a Gauss-Markov rate, however large, is not counted (as RRW and B are not)
  EXPECT_FALSE(quantization_expected_white(o));
}

TEST(SimHeader, RefusesWhatIsNotATruthLine) {
  const std::string good = format_sim_truth_line(SimOptions{});
  auto replaced = [&good](const std::string& from, const std::string& to) { return replaced_in(good, from, to); };
  EXPECT_FALSE(parse_sim_truth_line(""));
  EXPECT_FALSE(parse_sim_truth_line("# gyrochar-sim counts: tau0 0.01 s"));
  EXPECT_FALSE(parse_sim_truth_line(good.substr(1)));                           // no '#'
  EXPECT_FALSE(parse_sim_truth_line(replaced(" seed=1", "")));                  // missing key
  EXPECT_FALSE(parse_sim_truth_line(good + " seed=2"));                         // repeated key
  EXPECT_FALSE(parse_sim_truth_line(replaced("format=1", "format=2")));         // unknown format
  EXPECT_FALSE(parse_sim_truth_line(replaced("tau0_s=0.01", "tau0_s=0.01x")));  // trailing garbage
  EXPECT_FALSE(parse_sim_truth_line(replaced("tau0_s=0.01", "tau0_s=")));
  EXPECT_FALSE(parse_sim_truth_line(replaced("tau0_s=0.01", "tau0_s=nan")));
  EXPECT_FALSE(parse_sim_truth_line(replaced("tau0_s=0.01", "tau0_s=-0.01")));  // check_parameters
  EXPECT_FALSE(parse_sim_truth_line(replaced("arw_deg_per_sqrt_h=0", "arw_deg_per_sqrt_h=inf")));
  EXPECT_FALSE(parse_sim_truth_line(replaced("seed=1", "seed=-1")));
  EXPECT_FALSE(parse_sim_truth_line(replaced("Q_white=no", "Q_white=maybe")));
  EXPECT_FALSE(parse_sim_truth_line(replaced("B_deg_per_h=0", "B_deg_per_h=-1")));
  EXPECT_FALSE(parse_sim_truth_line(good + " orphan"));  // a token without '='
  EXPECT_FALSE(parse_sim_truth_line(good + " =3"));
  // Later formats may add keys; blanks may be tabs; order does not matter.
  EXPECT_TRUE(parse_sim_truth_line(good + " temperature_C=25"));
  EXPECT_TRUE(parse_sim_truth_line(replaced(" seed=1", "\tseed=1\t")));
  const auto moved = parse_sim_truth_line(replaced(" seed=1", "") + " seed=1");
  ASSERT_TRUE(moved);
  EXPECT_EQ(moved->options.seed, 1u);
}

TEST(SimHeader, TheProgramWritesTheTruthLine) {
  const std::string out = gyrochar::test_support::temp_path("sim_header.txt");
  const std::string command =
      GYROCHAR_BINARY_DIR
      "/host_tools/gyrochar-sim --duration 2 --tau0 0.1 --pulse-weight 0.5 --rate -3 --white-angle 0.25 --arw 0.005 "
      "--rrw 0.15 --bias-instability 0.05 --bias-time 2000 --ramp 0.01 --dither 7 --dither-hz 437.3 --seed 99 "
      "--markov 0.05,300 --sinusoid 0.02,0.01 --markov 1,0.3 --out " +
      out;
  ASSERT_EQ(std::system(command.c_str()), 0);
  std::ifstream in(out);
  std::string first, second, value;
  std::getline(in, first);
  std::getline(in, second);
  int values = 0;
  while (std::getline(in, value)) ++values;
  std::remove(out.c_str());
  EXPECT_EQ(first.rfind("# gyrochar-sim counts: tau0 0.1 s, pulse weight 0.5 arcsec", 0), 0u) << first;
  const auto t = parse_sim_truth_line(second);
  ASSERT_TRUE(t) << second;
  SimOptions want;
  want.duration_s = 2;
  want.tau0_s = 0.1;
  want.pulse_arcsec = 0.5;
  want.rate_deg_per_h = -3;
  want.white_angle_arcsec = 0.25;
  want.arw_deg_per_sqrt_h = 0.005;
  want.rrw_deg_per_h_sqrt_h = 0.15;
  want.bias_deg_per_h = 0.05;
  want.bias_time_s = 2000;
  want.ramp_deg_per_h2 = 0.01;
  want.dither_arcsec = 7;
  want.dither_hz = 437.3;
  want.seed = 99;
  want.markov = {{0.05, 300}, {1, 0.3}};  // in the order given
  want.sinusoids = {{0.02, 0.01}};
  expect_same_options(t->options, want);
  EXPECT_NE(first.find(", seed 99, Gauss-Markov rate 0.05 deg/h over 300 s, Gauss-Markov rate 1 deg/h over 0.3 s, "
                       "sinusoidal rate 0.02 deg/h at 0.01 Hz"),
            std::string::npos)
      << first;
  EXPECT_EQ(second, format_sim_truth_line(want));
  EXPECT_EQ(values, 20);
}

// --- segments (the gyro changes during the run) ------------------------------------------------

SimOptions doubling() {
  SimOptions o;
  o.duration_s = 20;
  o.arw_deg_per_sqrt_h = 0.002;
  o.segments = {{10, std::nullopt, std::nullopt, 0.004, std::nullopt}, {15, -20.0, 0.5, std::nullopt, 0.1}};
  return o;
}

TEST(SimSegments, TheTruthLineSaysFormatTwoAndCarriesEverySegmentExactly) {
  const SimOptions o = doubling();
  const std::string line = format_sim_truth_line(o);
  ASSERT_EQ(line.rfind("# gyrochar-sim truth: format=2 ", 0), 0u) << line;
  EXPECT_NE(line.find(" segments=2 segment1_start_s=10 segment1_arw_deg_per_sqrt_h=0.004 segment2_start_s=15 "),
            std::string::npos)
      << line;
  const auto t = parse_sim_truth_line(line);
  ASSERT_TRUE(t) << line;
  expect_same_options(t->options, o);
  EXPECT_EQ(t->truth.n_rad_sqrt_s, 0.002 * units::deg_per_sqrt_h) << "the truth keys describe the first segment";
  // Each segment's options: what it names, the rest carried over.
  EXPECT_EQ(segment_options(o, 1).arw_deg_per_sqrt_h, 0.004);
  EXPECT_EQ(segment_options(o, 2).arw_deg_per_sqrt_h, 0.004);
  EXPECT_EQ(segment_options(o, 2).rate_deg_per_h, -20.0);
  EXPECT_TRUE(segment_options(o, 2).segments.empty());
  // A format-1 line never has segment keys; a format-2 line needs them all.
  auto replaced = [&line](const std::string& from, const std::string& to) { return replaced_in(line, from, to); };
  EXPECT_FALSE(parse_sim_truth_line(replaced("format=2", "format=1")));
  EXPECT_FALSE(parse_sim_truth_line(replaced(" segments=2", " segments=3")));
  EXPECT_FALSE(parse_sim_truth_line(replaced(" segment1_start_s=10", "")));
  EXPECT_FALSE(parse_sim_truth_line(line + " segment1_start_s=10"));                          // repeated
  EXPECT_FALSE(parse_sim_truth_line(line + " segment2_rrw_deg_per_h_sqrt_h=1"));              // a key twice in a segment
  EXPECT_FALSE(parse_sim_truth_line(line + " segment2_bias_deg_per_h=1"));                    // not a level that may change
  EXPECT_FALSE(parse_sim_truth_line(replaced("segment2_start_s=15", "segment2_start_s=5")));  // out of order
}

TEST(SimSegments, TheOptionReadsTimeAndChanges) {
  std::string why;
  const auto g = parse_segment_option("3600:arw=0.004,rate=-15", why);
  ASSERT_TRUE(g) << why;
  EXPECT_EQ(g->start_s, 3600);
  EXPECT_EQ(g->arw_deg_per_sqrt_h, 0.004);
  EXPECT_EQ(g->rate_deg_per_h, -15);
  EXPECT_FALSE(g->rrw_deg_per_h_sqrt_h);
  for (const char* bad :
       {"3600", "x:arw=1", "3600:", "3600:arw", "3600:arw=", "3600:bias=1", "3600:arw=1,arw=2", "3600:arw=nan"}) {
    EXPECT_FALSE(parse_segment_option(bad, why)) << bad;
    EXPECT_FALSE(why.empty());
  }
  SimOptions o = doubling();
  o.segments[1].start_s = 10;  // not after the one before
  EXPECT_TRUE(check_parameters(o));
  o = doubling();
  o.segments[1].start_s = 20;  // at the end
  EXPECT_TRUE(check_parameters(o));
  o = doubling();
  o.segments[0] = SimSegment{};  // changes nothing
  o.segments[0].start_s = 10;
  EXPECT_TRUE(check_parameters(o));
  o = doubling();
  o.segments[1].white_angle_arcsec = -1;
  EXPECT_TRUE(check_parameters(o));
}

TEST(SimSegments, TheProgramWritesItsSegmentsAndTheirCounts) {
  // Oracle: SimRun of the same options (the program's own loop) gives the counts it writes.
  const std::string out = gyrochar::test_support::temp_path("sim_segments.txt");
  const std::string sim = GYROCHAR_BINARY_DIR "/host_tools/gyrochar-sim";
  ASSERT_EQ(std::system((sim +
                         " --duration 20 --arw 0.002 --segment 10:arw=0.004 --segment 15:rate=-20,white-angle=0.5"
                         ",rrw=0.1 --out " +
                         out)
                            .c_str()),
            0);
  std::ifstream in(out);
  std::string first, second;
  std::getline(in, first);
  std::getline(in, second);
  EXPECT_NE(first.find("; from 10 s: arw 0.004; from 15 s: rate -20 white-angle 0.5 rrw 0.1"), std::string::npos) << first;
  const auto t = parse_sim_truth_line(second);
  ASSERT_TRUE(t) << second;
  expect_same_options(t->options, doubling());
  SimRun run(doubling());
  long long count = 0;
  std::uint64_t k = 0;
  for (; in >> count; ++k) ASSERT_EQ(count, run.next_count()) << k;
  EXPECT_EQ(k, run.samples());
  std::remove(out.c_str());
  const std::string err = gyrochar::test_support::temp_path("sim_segments.err");
  EXPECT_EQ(WEXITSTATUS(std::system((sim + " --duration 20 --segment 25:arw=1 > /dev/null 2> " + err).c_str())), 2);
  std::ifstream e(err);
  const std::string why{std::istreambuf_iterator<char>(e), {}};
  EXPECT_EQ(why.rfind("gyrochar-sim: --segment: ", 0), 0u) << why;
  std::remove(err.c_str());
}

TEST(SimSegments, ARunChangesAtItsSegmentAndNowhereElse) {
  // Oracle: the simulator alone, retuned by hand at the same sample: the same counts, every one;
  // before the change, the counts of the run without segments.
  const SimOptions o = doubling();
  SimRun run(o);
  ASSERT_EQ(run.samples(), 2000u);
  GyroSimulator by_hand(gyro_parameters(o)), unchanged(gyro_parameters(o));
  for (std::uint64_t k = 0; k < run.samples(); ++k) {
    if (k == 1000) by_hand.retune(gyro_parameters(segment_options(o, 1)));
    if (k == 1500) by_hand.retune(gyro_parameters(segment_options(o, 2)));
    const std::int64_t c = run.next_count(), h = by_hand.next_count(), u = unchanged.next_count();
    ASSERT_EQ(c, h) << k;
    if (k < 1000) {
      ASSERT_EQ(c, u) << k;
    }
  }
}

TEST(SimSegments, RateTermsLastTheWholeRun) {
  // Oracle: the simulator retuned by hand (as above): the Gauss-Markov and sinusoidal terms carry
  // over every change, on the format-2 line and in the run.
  SimOptions o = doubling();
  o.markov = {{2, 0.5}};
  o.sinusoids = {{3, 0.7}};
  const std::string line = format_sim_truth_line(o);
  const auto t = parse_sim_truth_line(line);
  ASSERT_TRUE(t) << line;
  expect_same_options(t->options, o);
  EXPECT_EQ(segment_options(o, 2).markov, o.markov);
  EXPECT_EQ(segment_options(o, 2).sinusoids, o.sinusoids);
  SimRun run(o);
  GyroSimulator by_hand(gyro_parameters(o));
  for (std::uint64_t k = 0; k < run.samples(); ++k) {
    if (k == 1000) by_hand.retune(gyro_parameters(segment_options(o, 1)));
    if (k == 1500) by_hand.retune(gyro_parameters(segment_options(o, 2)));
    ASSERT_EQ(run.next_count(), by_hand.next_count()) << k;
  }
}

}  // namespace
}  // namespace gyrochar
