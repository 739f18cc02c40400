// Acceptance limits (common/limits.hpp): the file's parser, the guard-banded decision rule and the
// production summary's rows. Oracles: the unit sizes by hand (N: 0.003 deg/sqrt(h) = 0.003 x
// (pi/180) / 60 rad/s^0.5 = 8.726646259971648e-07, as in test_kalibr.cpp; B: 0.01 deg/h = 0.01 x
// (pi/180) / 3600 rad/s = 4.84813681109536e-08; 0.005 deg/h = 2.42406840554768e-08 rad/s;
// K: 0.001 deg/h/sqrt(h) = 0.001 x (pi/180) / 216000 = 8.080228018492267e-11 rad/s^1.5), the normal
// quantile 1.959963984540054 (Phi^-1(0.975), every table), the chi-squared quantiles of 100 degrees
// of freedom chi2_0.025 = 74.22193, chi2_0.975 = 129.5612 (NIST/SEMATECH e-Handbook table 1.3.6.7.4),
// and the decision time T (d / gap)^2 of the header worked by hand.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>

#include <unistd.h>

#include "limits.hpp"
#include "verdict_output.hpp"

namespace gyrochar {
namespace {

std::string error_of(const std::string& text) {
  try {
    parse_limits(text);
  } catch (const LimitsError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(Limits, ParsesTermsAndDeviationsInTheirUnits) {
  const auto limits = parse_limits(
      "# acceptance of the RLG-3 series\n"
      "N <= 0.003 deg/sqrt(h)   # angle random walk\n"
      "\n"
      "B<=0.01 deg/h\n"
      "K <= 0.001 deg/h/sqrt(h)\n"
      "adev(100 s) <= 0.005 deg/h\n"
      "mdev(2 min) <= 2.42406840554768e-08 rad/s\n"
      "Q <= 1 arcsec\n");
  ASSERT_EQ(limits.size(), 6u);
  EXPECT_EQ(limits[0].kind, Limit::Kind::term);
  EXPECT_EQ(limits[0].term, 1u);
  EXPECT_EQ(limits[0].line, 2u);
  EXPECT_EQ(limits[0].text, "N <= 0.003 deg/sqrt(h)");
  EXPECT_NEAR(limits[0].value_si, 8.726646259971648e-07, 1e-21);  // header: by hand
  EXPECT_EQ(limits[1].term, 2u);
  EXPECT_NEAR(limits[1].value_si, 4.84813681109536e-08, 1e-22);   // header: by hand
  EXPECT_NEAR(limits[2].value_si, 8.080228018492267e-11, 1e-25);  // header: by hand
  EXPECT_EQ(limits[3].kind, Limit::Kind::adev);
  EXPECT_EQ(limits[3].tau_s, 100.0);
  EXPECT_EQ(limits[3].quantity(), "adev(100 s)");
  EXPECT_NEAR(limits[3].value_si, 2.42406840554768e-08, 1e-22);  // header: by hand
  EXPECT_EQ(limits[4].kind, Limit::Kind::mdev);
  EXPECT_EQ(limits[4].tau_s, 120.0);                    // 2 min
  EXPECT_EQ(limits[4].value_si, 2.42406840554768e-08);  // given in SI: as written
  EXPECT_EQ(limits[5].term, 0u);
  EXPECT_NEAR(limits[5].value_si, 4.84813681109536e-06, 1e-20);  // 1 arcsec = pi / 648000 rad
  EXPECT_EQ(limits[5].line, 8u);
}

TEST(Limits, RefusesABadFileNamingTheLineAndTheCause) {
  EXPECT_EQ(error_of("N <= 0.003 deg/sqrt(h)\nX <= 1 deg/h\n"),
            "line 2: 'X' is not a limited quantity: Q, N, B, K, R, adev(TAU), mdev(TAU)");
  EXPECT_EQ(error_of("N >= 0.003 deg/sqrt(h)\n"), "line 1: operator '>=': only upper limits, '<=', are supported");
  EXPECT_EQ(error_of("N 0.003 deg/sqrt(h)\n"), "line 1: no operator: write QUANTITY <= VALUE UNIT");
  EXPECT_EQ(error_of("N <= -1 deg/sqrt(h)\n"), "line 1: the limit is not a positive finite number");
  EXPECT_EQ(error_of("N <= 0 deg/sqrt(h)\n"), "line 1: the limit is not a positive finite number");
  EXPECT_EQ(error_of("N <= 0.003\n"), "line 1: the limit has no unit");
  EXPECT_EQ(error_of("# c\nN <= 0.003 deg/h\n"), "line 2: 'deg/h' is not a unit of N: deg/sqrt(h) or rad/s^0.5");
  EXPECT_EQ(error_of("adev(100 s) <= 1 deg/sqrt(h)\n"), "line 1: 'deg/sqrt(h)' is not a rate unit (deg/h, deg/s, rad/s)");
  EXPECT_EQ(error_of("adev <= 1 deg/h\n"), "line 1: adev needs its tau: adev(100 s)");
  EXPECT_EQ(error_of("adev(100 s <= 1 deg/h\n"), "line 1: adev(: no closing ')'");
  EXPECT_EQ(error_of("adev(0 s) <= 1 deg/h\n"), "line 1: the tau of adev is not a positive number of seconds");
  EXPECT_EQ(error_of("mdev(10 d) <= 1 deg/h\n"), "line 1: the tau's unit 'd' is not s, min or h");
  EXPECT_EQ(error_of("N <= 1 rad/s^0.5\nN <= 2 rad/s^0.5\n"), "line 2: N is limited twice (line 1 too)");
  EXPECT_EQ(error_of("N <= 1e-320 rad/s^0.5\n"), "line 1: the limit leaves a double's range in SI units");
  EXPECT_EQ(error_of("N <= 1 rad/s^0.5\x01\n"), "line 1: control byte \\x01");
  EXPECT_EQ(error_of("# only a comment\n\n"), "no limit in the file (only comments and blank lines)");
  EXPECT_EQ(error_of(""), "no limit in the file (only comments and blank lines)");
}

TEST(Limits, ReadsAFileAndRefusesAnUnreadableOrHugeOne) {
  const auto dir = std::filesystem::temp_directory_path() / ("limits_test_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string good = (dir / "good.txt").string(), huge = (dir / "huge.txt").string();
  std::ofstream(good) << "B <= 0.01 deg/h\r\n";  // a CRLF line reads as its LF twin
  EXPECT_EQ(read_limits_file(good).size(), 1u);
  std::ofstream(huge) << std::string(70000, '#');
  EXPECT_THROW(read_limits_file(huge), LimitsError);
  EXPECT_THROW(read_limits_file((dir / "absent.txt").string()), LimitsError);
  std::filesystem::remove_all(dir);
}

Limit upper(double value_si) {
  Limit l;
  l.value_si = value_si;
  return l;
}

TEST(Limits, DecisionRuleIsGuardBanded) {
  // A term 1 +- 0.1 (standard): bounds 1 -+ 1.959963984540054 x 0.1 (header oracle).
  const LimitEstimate e = normal_estimate(1.0, 0.1, 3600);
  ASSERT_TRUE(e.usable);
  EXPECT_NEAR(e.low, 0.8040036015459946, 1e-15);
  EXPECT_NEAR(e.high, 1.1959963984540054, 1e-15);
  EXPECT_EQ(decide(upper(1.3), e).verdict, Verdict::pass);  // upper bound 1.196 within 1.3
  EXPECT_EQ(decide(upper(0.7), e).verdict, Verdict::fail);  // lower bound 0.804 beyond 0.7
  const Decision d = decide(upper(1.1), e);
  EXPECT_EQ(d.verdict, Verdict::undecided);
  // T (d / gap)^2 = 3600 (0.1959963984540054 / 0.1)^2 = 3600 x 3.841458820694124 (by hand).
  EXPECT_NEAR(d.decide_at_s, 13829.251754498846, 1e-8);
  const Decision below = decide(upper(0.9), e);  // beyond the limit: the lower bound must rise past it
  EXPECT_EQ(below.verdict, Verdict::undecided);
  EXPECT_NEAR(below.decide_at_s, 13829.251754498846, 1e-8);  // symmetric: the same distances
  EXPECT_TRUE(std::isinf(decide(upper(1.0), e).decide_at_s)) << "on the limit: never at this estimate";
  EXPECT_EQ(format_run_length(decide(upper(1.0), e).decide_at_s), "never at this estimate");
  EXPECT_EQ(format_run_length(13829.25), "3.84 h");
  // At the limit exactly: the upper bound equal to it passes (<=).
  EXPECT_EQ(decide(upper(e.high), e).verdict, Verdict::pass);
}

TEST(Limits, DeviationBoundsAreTheChiSquaredInterval) {
  const LimitEstimate e = deviation_estimate(1.0, 100, 0, 7200);
  ASSERT_TRUE(e.usable);
  EXPECT_NEAR(e.low, std::sqrt(100 / 129.5612), 2e-6);  // header: chi2 table
  EXPECT_NEAR(e.high, std::sqrt(100 / 74.22193), 2e-6);
  EXPECT_FALSE(deviation_estimate(1.0, 0, 0, 7200).usable) << "no EDF: no verdict";
  EXPECT_EQ(decide(upper(2), deviation_estimate(1.0, 0, 0, 7200)).verdict, Verdict::undecided);
}

TEST(Limits, NoEstimateIsNeverAPass) {
  const Decision d = decide(upper(1e9), no_estimate("N not resolved"));
  EXPECT_EQ(d.verdict, Verdict::undecided);
  EXPECT_EQ(d.reason, "N not resolved");
  EXPECT_TRUE(std::isnan(d.decide_at_s));
  EXPECT_FALSE(normal_estimate(std::numeric_limits<double>::quiet_NaN(), 0.1, 1).usable);
}

TEST(Limits, OverallIsTheWorstVerdict) {
  const LimitEstimate e = normal_estimate(1.0, 0.1, 1);
  EXPECT_EQ(overall({}), Verdict::pass);
  EXPECT_EQ(overall({decide(upper(2), e)}), Verdict::pass);
  EXPECT_EQ(overall({decide(upper(2), e), decide(upper(1.1), e)}), Verdict::undecided);
  EXPECT_EQ(overall({decide(upper(0.5), e), decide(upper(1.1), e)}), Verdict::fail);
}

TEST(ProductionSummary, OneRowPerGyroUnderOneHeader) {
  const auto limits = parse_limits("N <= 0.003 deg/sqrt(h)\nadev(100 s) <= 0.005 deg/h\n");
  const std::string header = summary_header(limits);
  EXPECT_EQ(header,
            "source,node,run_s,samples,fit_status,chi2_per_dof,Q [arcsec],Q u,Q status,N [deg/sqrt(h)],N u,N status,"
            "B [deg/h],B u,B status,K [deg/h/sqrt(h)],K u,K status,R [deg/h/h],R u,R status,verdict,N verdict,"
            "N estimate [deg/sqrt(h)],N lower,N upper,adev(100 s) verdict,adev(100 s) estimate [deg/h],adev(100 s) lower,"
            "adev(100 s) upper");
  GyroSummary g;
  g.source = "run, 1.txt";  // a comma: quoted
  g.run_s = 3600;
  g.samples = 360000;
  g.fit_status = "ok";
  g.chi2_per_dof = 1.25;
  g.terms[1] = {true, 0.0025, 0.0001, "resolved"};
  // N 0.0025 +- 0.0001 deg/sqrt(h): upper bound 0.0025 + 1.96 x 0.0001 = 0.002696 within 0.003: pass.
  g.decisions = {decide(limits[0], normal_estimate(0.0025 * limits[0].unit_si, 0.0001 * limits[0].unit_si, 3600)),
                 decide(limits[1], no_estimate("no oadev at tau = 100 s"))};
  const std::string row = summary_row(g, limits);
  EXPECT_EQ(row.rfind("\"run, 1.txt\",,3600,360000,ok,1.25,,,,0.0025,0.0001,resolved,", 0), 0u) << row;
  // Overall undecided (adev has no estimate), N pass, adev undecided with empty values.
  EXPECT_NE(row.find(",undecided,pass,0.002"), std::string::npos) << row;
  EXPECT_EQ(row.substr(row.size() - 13), ",undecided,,,") << row;
  // Append twice: one header, two rows; another limits file is refused.
  const auto path = std::filesystem::temp_directory_path() / ("summary_test_" + std::to_string(::getpid()) + ".csv");
  std::filesystem::remove(path);
  std::string why;
  ASSERT_TRUE(summary_compatible(path.string(), limits, why));
  ASSERT_TRUE(append_summary(path.string(), limits, {g}, why)) << why;
  ASSERT_TRUE(summary_compatible(path.string(), limits, why));
  ASSERT_TRUE(append_summary(path.string(), limits, {g}, why)) << why;
  std::ifstream in(path);
  std::string line;
  std::size_t lines = 0, headers = 0;
  while (std::getline(in, line)) ++lines, headers += line == header;
  EXPECT_EQ(lines, 3u);
  EXPECT_EQ(headers, 1u);
  EXPECT_FALSE(summary_compatible(path.string(), parse_limits("B <= 1 deg/h\n"), why));
  EXPECT_NE(why.find("header differs"), std::string::npos) << why;
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace gyrochar
