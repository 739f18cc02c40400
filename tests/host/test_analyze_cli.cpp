// gyrochar-analyze as a user meets it: every kind of bad input gets one line
// 'gyrochar-analyze: what: why' on stderr, nothing on stdout and exit code 2; good input gives the
// documented formats and units. Oracles: the exit codes of hal/program/exit_codes.hpp; unit identities; the
// closed-form angle random walk of white rate noise (values themselves: test_analyze_reference);
// for the IEEE-952 read-off, the ADIS16405 data sheet (README beside the records, which are not part
// of the project: support/real_imu.hpp), the measured curve itself and the agreement rule of
// analysis_report.hpp recomputed from the JSON.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <algorithm>
#include <fstream>
#include <map>
#include <sstream>
#include <nlohmann/json.hpp>
#include <random>
#include <regex>
#include <string>
#include <tuple>
#include <vector>

#include "hal/program/exit_codes.hpp"
#include "support/shell.hpp"
#include "oracle/brute_force.hpp"
#include "support/real_imu.hpp"

#include "gyrochar/total.hpp"

namespace {

using namespace gyrochar;

const std::string tool = GYROCHAR_BINARY_DIR "/host_tools/gyrochar-analyze";

using Outcome = gyrochar::test_support::ShellOutcome;

std::string temp(const std::string& name) { return gyrochar::test_support::temp_path(name); }

Outcome run_shell(const std::string& command) { return gyrochar::test_support::run_shell(command, "analyze_err.txt"); }

Outcome run(const std::string& args) { return run_shell(tool + " " + args); }

std::string file_with(const std::string& name, const std::string& content) {
  const std::string path = temp(name);
  std::ofstream(path) << content;
  return path;
}

void expect_bad_input(const std::string& args, const std::string& what, const std::string& before = "") {
  const Outcome r = run_shell(before + tool + " " + args);
  EXPECT_EQ(r.code, exit_code::bad_input) << args << "\n" << r.err;
  static const std::regex one_line("gyrochar-analyze: [^\n]+: [^\n]+\n");
  EXPECT_TRUE(std::regex_match(r.err, one_line)) << "not 'gyrochar-analyze: what: why': " << r.err;
  EXPECT_NE(r.err.find(what), std::string::npos) << "expected '" << what << "' in: " << r.err;
  EXPECT_TRUE(r.out.empty()) << "no data on stdout after an error";
}

std::string good_phase() {
  // (std::to_string's six decimals made these all 0: a constant input, which now gets a note.)
  std::string s = "# phase\n";
  char text[32];
  for (int i = 0; i < 200; ++i) {
    std::snprintf(text, sizeof text, "%.9g\n", (i * 7919 % 101) * 1e-9);
    s += text;
  }
  return file_with("good.txt", s);
}

// 20000 counts of white rate noise: 1000 + U{-3..3} pulses per 1 ms (variance 4 pulses^2).
std::vector<int> white_rate_counts() {
  std::mt19937_64 rng(42);
  std::uniform_int_distribution<int> jitter(-3, 3);
  std::vector<int> c(20000);
  for (int& v : c) v = 1000 + jitter(rng);
  return c;
}

TEST(AnalyzeCli, BadInputsGetExitCodeTwoAndAReason) {
  const std::string good = good_phase();
  expect_bad_input("--type phase --tau0 1 " + file_with("nan.txt", "1\n2\nabc\n"), "line 3");
  expect_bad_input("--type phase --tau0 1 " + file_with("nan2.txt", "1\nnan\n"), "not a finite number");
  expect_bad_input("--type phase --tau0 1 " + file_with("empty.txt", ""), "no data");
  expect_bad_input("--type phase --tau0 1 " + file_with("comments.txt", "# only\n\n"), "no data");
  expect_bad_input("--type phase --tau0 1 - < " + file_with("empty2.txt", ""), "no data");
  expect_bad_input("--type phase --tau0 1 --column 3 " + file_with("cols.txt", "1 2\n3 4\n"), "column 3");
  expect_bad_input("--type phase --tau0 0 " + good, "--tau0");
  expect_bad_input("--type phase --tau0 -1 " + good, "--tau0");
  expect_bad_input("--type phase --tau0 1 --frobnicate " + good, "options");
  expect_bad_input("--tau0 1 " + good, "--type");  // required: no silent default
  expect_bad_input("--type phase " + good, "--tau0");
  expect_bad_input("--type velocity --tau0 1 " + good, "--type");
  expect_bad_input("--type phase --tau0 1 /nonexistent/file.txt", "No such file");
  expect_bad_input("--type phase --tau0 1 --stats adev,foo " + good, "foo");
  expect_bad_input("--type phase --tau0 1 --stride-factor 6 " + good, "--stride-factor");
  expect_bad_input("--type phase --tau0 1 --stats totdev --total-stride-factor 3 " + good, "--total-stride-factor");
  expect_bad_input("--type phase --tau0 1 --fit-long-tau totdev " + good, "--fit-long-tau");  // needs --fit
  expect_bad_input("--type phase --tau0 1 --fit ieee952 --fit-long-tau theo2 " + good, "--fit-long-tau");
  expect_bad_input("--type phase --tau0 1 --alpha 5 " + good, "--alpha");
  expect_bad_input("--type phase --tau0 1 --confidence 1.5 " + good, "--confidence");
  expect_bad_input("--type phase --tau0 1 --taus 4,2 " + good, "--taus");
  expect_bad_input("--type phase --tau0 1 --taus 1,11 --stride-factor 8 " + good, "cannot be formed");
  expect_bad_input("--type phase --tau0 1 --taus 500,600 " + good, "too few");
  expect_bad_input("--type phase --tau0 1 --format xml " + good, "--format");
  expect_bad_input("--type phase --tau0 1 --unit furlong " + good, "--unit");
  expect_bad_input("--type phase --tau0 1 --rate-unit deg/h " + good, "--rate-unit");  // clock data
  expect_bad_input("--type phase --tau0 1 --nominal-hz 1e7 " + good, "--nominal-hz");
  expect_bad_input("--type freq --tau0 1 --unit Hz " + good, "--nominal-hz");
  expect_bad_input("--type counts --tau0 1 " + good, "--pulse-weight");
  expect_bad_input("--type counts --tau0 1 --pulse-weight 1parsec " + good, "unknown angle unit");
  expect_bad_input("--type counts --tau0 1 --pulse-weight 1arcsec --rate-unit mph " + good, "--rate-unit");
  expect_bad_input("--type counts --tau0 1 --pulse-weight 1arcsec " + file_with("frac.txt", "1\n2.5\n"), "integer");
  expect_bad_input("--type counts --tau0 1 --pulse-weight 1arcsec " + file_with("huge.txt", "1\n1e12\n"), "2^31");
  std::string many;
  for (int i = 0; i < 20000; ++i) many += std::to_string(i * 0.001) + "\n";
  const std::string whole = file_with("many.txt", many);
  ASSERT_EQ(std::system(("gzip -kf " + whole + " && head -c 20000 " + whole + ".gz > " + whole + ".cut.gz").c_str()), 0);
  expect_bad_input("--type phase --tau0 1 " + whole + ".cut.gz", "unexpected end of file");  // not a short run
  const std::string dir = temp("a_directory");
  mkdir(dir.c_str(), 0700);
  expect_bad_input("--type phase --tau0 1 " + dir, "directory");
}

// A deviation that is not a finite number is an error naming the statistic, the tau and the cause,
// wherever it arises after reading: never inf, nan or null in the output.
TEST(AnalyzeCli, NonFiniteResultsAreErrorsWithTheirCause) {
  std::string huge;
  for (int i = 0; i < 8; ++i) huge += i % 2 ? "-1e308\n" : "1e308\n";
  expect_bad_input("--type phase --tau0 1 " + file_with("huge.txt", huge),
                   "oadev at tau = 1 s (m = 1): the squared differences of the values overflow a double");
  expect_bad_input(
      "--type phase --tau0 1e-200 --format json " + good_phase(),
      "oadev at tau = 1e-200 s (m = 1): tau0^2 = (1e-200 s)^2 is outside the range of a double: tau0 is too small");
  // Finite deviations, but the output unit takes them out of range (1e308 arcsec pulses in deg/h).
  expect_bad_input("--type counts --pulse-weight 1e308arcsec --tau0 1 " + file_with("c.txt", "100\n-100\n100\n-100\n100\n"),
                   "oadev at tau = 1 s (m = 1): ");
}

// The other end: a result that underflows (every deviation 0, or a few bits the data do not have)
// is an error naming the cause, with the exit code of overflow; a constant input, whose deviations
// are 0 by right, gets a note. Oracle: the range of a double (largest 1.8e308, smallest normal
// 2.2e-308) and the resolution of a double at 1e7 (2^-29 = 1.9e-9).
std::string line_of(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%g\n", v);
  return text;
}

TEST(AnalyzeCli, CollapsedResultsAreErrorsWithTheirCause) {
  std::string fractional, tiny, subnormal, ramp, constant;
  for (int i = 0; i < 200; ++i) {
    const double wobble = (i * 7919 % 101) - 50.0;
    fractional += line_of(1e-11 * wobble);  // fractional frequency, as a clock's
    tiny += line_of(1e-209 * wobble);       // squared differences ~1e-418: 0
    subnormal += line_of(1e-158 * wobble);  // squared differences ~1e-316: subnormal
    ramp += line_of(3 * i + 1);             // a phase line: a constant frequency
    constant += "5\n";
  }
  // Fractional frequency read as Hz around 10 MHz: f - F0 rounds every value to -F0.
  expect_bad_input("--type freq --tau0 1 --nominal-hz 10e6 " + file_with("frac.txt", fractional),
                   "--nominal-hz: the values vary from -5e-10 to 5e-10 Hz, but (f - F0) / F0 with F0 = 1e+07 Hz makes "
                   "every one -1: their differences are below the resolution of a double at F0 (1.9e-09 Hz)");
  for (const std::string type : {"phase", "freq"})
    expect_bad_input("--type " + type + " --tau0 1 " + file_with("tiny.txt", tiny),
                     "every deviation is 0, but the values (from -5e-208 to 5e-208) are not ");
  expect_bad_input("--type phase --tau0 1 " + file_with("subnormal.txt", subnormal),
                   "oadev at tau = 1 s (m = 1): the squared differences of the values underflow a double");
  // tau0^2 overflows: every variance divided by it would be 0; a tau that is not finite.
  expect_bad_input("--type phase --tau0 1e160 " + good_phase(),
                   "oadev at tau = 1e+160 s (m = 1): tau0^2 = (1e+160 s)^2 is outside the range of a double: tau0 is "
                   "too large");
  expect_bad_input("--type counts --pulse-weight 1arcsec --tau0 1e160 " + file_with("c.txt", "3\n5\n4\n6\n2\n"),
                   "tau0 is too large");
  expect_bad_input("--type phase --tau0 1e308 --taus 2 " + good_phase(),
                   "oadev at tau = inf s (m = 2): tau = m tau0 = 2 x 1e+308 s is not a finite number: tau0 is too large");
  // A pulse of 1e-320 arcsec is 0 rad; 1e-300 rad per pulse takes the deviations below 2.2e-308 in deg/h.
  expect_bad_input("--type counts --tau0 1 --pulse-weight 1e-320arcsec " + file_with("c2.txt", "3\n5\n4\n6\n2\n"),
                   "--pulse-weight");
  expect_bad_input("--type counts --tau0 1e10 --pulse-weight 1e-300rad --rate-unit rad/s " +
                       file_with("c3.txt", "3\n5\n4\n6\n2\n"),
                   "underflows a double");
  // Constant inputs: zeros by right, and a note.
  const char* line = "a straight line (a constant frequency)";
  for (const auto& [type, values, shape] :
       {std::tuple{"freq", constant, "constant"}, std::tuple{"phase", constant, line}, std::tuple{"phase", ramp, line}}) {
    const Outcome r = run(std::string("--type ") + type + " --tau0 1 --format csv " + file_with("flat.txt", values));
    EXPECT_EQ(r.code, exit_code::ok) << r.err;
    EXPECT_EQ(r.err, std::string("gyrochar-analyze: note: every deviation is 0: the values are ") + shape + "\n");
  }
  const Outcome counts = run("--type counts --tau0 1 --pulse-weight 1arcsec " + file_with("flat.txt", constant));
  EXPECT_EQ(counts.code, exit_code::ok) << counts.err;
  EXPECT_EQ(counts.err, "gyrochar-analyze: note: every deviation is 0: the values are constant\n");
}

TEST(AnalyzeCli, EachStatisticOnceAndListedTausTooLongForTheDataGetANote) {
  expect_bad_input("--type phase --tau0 1 --stats oadev,oadev " + good_phase(), "--stats: 'oadev' is asked twice");
  // 200 phase points: oadev needs 2m + 1 (m = 90 fits), mdev 3m + 1 (m = 90 does not), m = 1000 neither.
  const Outcome r = run("--type phase --tau0 1 --taus 1,90,1000 --format csv " + good_phase());
  EXPECT_EQ(r.code, exit_code::ok) << r.err;
  EXPECT_EQ(r.err,
            "gyrochar-analyze: note: m = 90 (tau = 90 s) left out of mdev: 200 phase points are too few for a term\n"
            "gyrochar-analyze: note: m = 1000 (tau = 1000 s) left out of oadev, mdev: 200 phase points are too few for a "
            "term\n");
  EXPECT_NE(r.out.find("\noadev,90,"), std::string::npos) << r.out;
  // Generated lists stop where the data end: no note.
  EXPECT_EQ(run("--type phase --tau0 1 " + good_phase()).err, "");
}

// --kalibr writes the recommended fit's N and K in SI: the JSON's N [deg/sqrt(h)] times
// (pi/180) / 60 and K [deg/h/sqrt(h)] times (pi/180) / 3600 / 60 (closed forms, kalibr.hpp).
TEST(AnalyzeCli, KalibrYamlHoldsTheFitsNAndKInSI) {
  const std::string counts = temp("sim_counts.txt"), yaml = temp("imu.yaml");
  ASSERT_EQ(std::system((GYROCHAR_BINARY_DIR "/host_tools/gyrochar-sim --duration 2000 --tau0 0.01 --arw 0.003 "
                                             "--rrw 0.5 --white-angle 2 --seed 3 --out " +
                         counts)
                            .c_str()),
            0);
  const Outcome r = run("--type counts --tau0 0.01 --pulse-weight 1arcsec --fit ieee952 --format json --kalibr " + yaml +
                        " " + counts);
  ASSERT_EQ(r.code, exit_code::ok) << r.err;
  const auto fit = nlohmann::json::parse(r.out)["fit"][0];
  ASSERT_EQ(fit["curve"], "both");
  std::ifstream in(yaml);
  std::map<std::string, double> keys;
  for (std::string line; std::getline(in, line);)
    if (!line.empty() && line[0] != '#' && line.rfind("rostopic", 0) != 0)
      keys[line.substr(0, line.find(':'))] = std::stod(line.substr(line.find(':') + 1));
  const double pi = 3.14159265358979323846;
  EXPECT_NEAR(keys.at("gyroscope_noise_density") / (fit["N"]["value"].get<double>() * pi / 180 / 60), 1.0, 1e-12);
  EXPECT_NEAR(keys.at("gyroscope_random_walk") / (fit["K"]["value"].get<double>() * pi / 180 / 3600 / 60), 1.0, 1e-12);
  EXPECT_EQ(keys.at("update_rate"), 100.0);

  expect_bad_input("--type counts --tau0 0.01 --pulse-weight 1arcsec --kalibr " + yaml + " " + counts,
                   "--kalibr: needs --fit ieee952");
  expect_bad_input("--type phase --tau0 1 --fit ieee952 --kalibr " + yaml + " " + good_phase(), "--kalibr: needs gyro data");
}

// A gyro with white rate noise alone (the simulator's ARW and white angle noise: no rate random
// walk): the fit leaves K out of its model. The analysis is printed all the same (exit 0), the
// Kalibr file holds N (the JSON's N in SI, as above) and K's key commented out with '?' for the
// user to fill, and stderr says so.
TEST(AnalyzeCli, KalibrWithoutKWritesWhatTheFitHasAndPrintsTheAnalysis) {
  const std::string counts = temp("sim_arw.txt"), yaml = temp("imu_arw.yaml");
  ASSERT_EQ(std::system((GYROCHAR_BINARY_DIR "/host_tools/gyrochar-sim --duration 2000 --tau0 0.01 --arw 0.003 "
                                             "--white-angle 2 --seed 3 --out " +
                         counts)
                            .c_str()),
            0);
  const Outcome r = run("--type counts --tau0 0.01 --pulse-weight 1arcsec --fit ieee952 --format json --kalibr " + yaml +
                        " " + counts);
  ASSERT_EQ(r.code, exit_code::ok) << r.err;
  const auto fit = nlohmann::json::parse(r.out)["fit"][0];
  ASSERT_EQ(fit["curve"], "both");
  ASSERT_FALSE(fit["K"]["fitted"].get<bool>()) << fit.dump();
  // The first note is this test's; a second one may name what else of the model Kalibr cannot hold.
  EXPECT_EQ(r.err.substr(0, r.err.find('\n') + 1),
            "gyrochar-analyze: note: " + yaml +
                ": K (rate random walk) is not in the fitted model: its key is "
                "written commented out with '?' for you to fill in (Kalibr needs it > 0)\n");
  std::ifstream in(yaml);
  const std::string text((std::istreambuf_iterator<char>(in)), {});
  const auto at = text.find("\ngyroscope_noise_density: ");
  ASSERT_NE(at, std::string::npos) << text;
  const double pi = 3.14159265358979323846;
  EXPECT_NEAR(std::stod(text.substr(at + 26)) / (fit["N"]["value"].get<double>() * pi / 180 / 60), 1.0, 1e-12);
  EXPECT_NE(text.find("\n#gyroscope_random_walk: ?"), std::string::npos) << text;
  EXPECT_EQ(text.find("\ngyroscope_random_walk"), std::string::npos) << text;
}

// The read-off of a real gyro (ADIS16405, run 1, x; 2.78 h at 100 Hz in deg/s). Oracles: its data
// sheet's angle random walk, 2.0 deg/sqrt(h) typical (N within 20 %); the measured OADEV curve
// itself (the floor is its smallest point, at or below that point's upper bound; N is the point it
// names read at 1 s on the -1/2 line: adev sqrt(tau), deg/h x sqrt(s) / 60 = deg/sqrt(h)); the
// closed form B = floor / sqrt(2 ln 2 / pi). Its last octave rises at slope 0.13, never +1/2: no K.
TEST(AnalyzeCli, ReadoffOfARealGyroIsWhatADataSheetPrints) {
  const std::string record = test::real_imu_record("adis16405_run1_gyro_x.txt.gz");
  if (const std::string why = test::real_imu_absent(record); !why.empty()) GTEST_SKIP() << why;
  const Outcome r = run("--type freq --unit deg/s --tau0 0.01 --format json " + record);
  ASSERT_EQ(r.code, exit_code::ok) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_TRUE(j.contains("readoff"));
  const auto& ro = j["readoff"];
  const auto& n = ro["N"];
  ASSERT_TRUE(n["value"].is_number());
  EXPECT_EQ(n["unit"], "deg/sqrt(h)");
  EXPECT_NEAR(n["value"].get<double>() / 2.0, 1.0, 0.2);
  EXPECT_LE(n["ci_low"].get<double>(), n["value"].get<double>());
  EXPECT_GE(n["ci_high"].get<double>(), n["value"].get<double>());
  EXPECT_TRUE(n["agrees_with_fit"].is_null());  // no --fit
  const nlohmann::json* smallest = nullptr;
  const nlohmann::json* at_n = nullptr;
  for (const auto& row : j["results"]) {
    if (row["stat"] != "oadev") continue;
    if (smallest == nullptr || row["dev"].get<double>() < (*smallest)["dev"].get<double>()) smallest = &row;
    if (row["tau"] == n["tau"]) at_n = &row;
  }
  ASSERT_NE(smallest, nullptr);
  ASSERT_NE(at_n, nullptr) << "N is read at an OADEV point";
  const auto& floor = ro["floor"];
  EXPECT_EQ(floor["unit"], "deg/h");
  EXPECT_LE(floor["value"].get<double>(), (*smallest)["ci_high"].get<double>());
  EXPECT_DOUBLE_EQ(floor["value"].get<double>(), (*smallest)["dev"].get<double>());
  EXPECT_DOUBLE_EQ(floor["tau"].get<double>(), (*smallest)["tau"].get<double>());
  EXPECT_NEAR(n["value"].get<double>(), (*at_n)["dev"].get<double>() * std::sqrt(n["tau"].get<double>()) / 60, 1e-12);
  const double pi = 3.14159265358979323846;
  EXPECT_NEAR(ro["B"]["value"].get<double>(), floor["value"].get<double>() / std::sqrt(2 * std::log(2.0) / pi), 1e-9);
  EXPECT_EQ(ro["B"]["unit"], "deg/h");
  EXPECT_TRUE(ro["K"]["value"].is_null());
  EXPECT_TRUE(ro["K"]["tau"].is_null());
  EXPECT_EQ(ro["K"]["unit"], "deg/h/sqrt(h)");
  // The table says it in one line; the CSV holds rows only.
  const Outcome table = run("--type freq --unit deg/s --tau0 0.01 " + record);
  ASSERT_EQ(table.code, exit_code::ok) << table.err;
  EXPECT_NE(table.out.find("\n# read-off (IEEE-952 graphical, data-sheet style): N = "), std::string::npos) << table.out;
  EXPECT_NE(table.out.find("B = floor/0.664 = "), std::string::npos);
  EXPECT_NE(table.out.find("K not read"), std::string::npos);
  const Outcome csv = run("--type freq --unit deg/s --tau0 0.01 --format csv " + record);
  EXPECT_EQ(csv.out.find("read-off"), std::string::npos);
  // Without OADEV rows there is nothing to read.
  const Outcome mdev = run("--type freq --unit deg/s --tau0 0.01 --stats mdev --format json " + record);
  EXPECT_FALSE(nlohmann::json::parse(mdev.out).contains("readoff"));
}

// Beside an ok recommended fit, agrees_with_fit is |read-off - fit| <= sqrt(u^2 + h^2) (u the fit's
// standard uncertainty, h the read-off's half interval: the rule of analysis_report.hpp, recomputed
// here), null where either side has no value; a disagreement gets its line in the table. The
// simulated gyro (white angle 2 arcsec, ARW 0.003 deg/sqrt(h), RRW 0.5 deg/h/sqrt(h)) has no
// stretch of slope -1/2 to read N on, and the floor read as B holds N and K's share.
TEST(AnalyzeCli, ReadoffSaysWhereItDisagreesWithTheFit) {
  const std::string counts = temp("sim_readoff.txt");
  ASSERT_EQ(std::system((GYROCHAR_BINARY_DIR "/host_tools/gyrochar-sim --duration 2000 --tau0 0.01 --arw 0.003 "
                                             "--rrw 0.5 --white-angle 2 --seed 3 --out " +
                         counts)
                            .c_str()),
            0);
  const std::string args = "--type counts --tau0 0.01 --pulse-weight 1arcsec --fit ieee952 ";
  const Outcome r = run(args + "--format json " + counts);
  ASSERT_EQ(r.code, exit_code::ok) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  const auto& fit = j["fit"][0];
  ASSERT_EQ(fit["curve"], "both");
  ASSERT_TRUE(fit["ok"].get<bool>());
  const Outcome table = run(args + counts);
  ASSERT_EQ(table.code, exit_code::ok) << table.err;
  int judged = 0;
  for (const char* term : {"N", "B", "K"}) {
    const auto& ro = j["readoff"][term];
    const auto& agrees = ro["agrees_with_fit"];
    const bool line = table.out.find(std::string("#   read-off ") + term + " disagrees") != std::string::npos;
    if (ro["value"].is_null() || !fit[term]["fitted"].get<bool>()) {
      EXPECT_TRUE(agrees.is_null()) << term;
      EXPECT_FALSE(line) << term;
      continue;
    }
    ++judged;
    const double diff = std::fabs(ro["value"].get<double>() - fit[term]["value"].get<double>());
    const double h = (ro["ci_high"].get<double>() - ro["ci_low"].get<double>()) / 2;
    ASSERT_TRUE(agrees.is_boolean()) << term;
    EXPECT_EQ(agrees.get<bool>(), diff <= std::hypot(fit[term]["uncertainty"].get<double>(), h)) << term;
    EXPECT_EQ(line, !agrees.get<bool>()) << term << "\n" << table.out;
  }
  EXPECT_GE(judged, 1);
  EXPECT_FALSE(j["readoff"]["B"]["agrees_with_fit"].get<bool>());
  EXPECT_NE(table.out.find("the read-off B is an upper bound when other terms add at the floor"), std::string::npos);
}

// --format stable32 against the layout of Stable32's own file for PHASE.DAT (tests/data):
// the same header lines but the file's name, the same column line, every row in the same columns
// with AF, Tau and # equal, Sigma within Stable32's 5 printed digits. (Min/Max Sigma: gyrochar's
// intervals use the exact EDF, Stable32's Greenhall's approximation: within 5 % here.)
TEST(AnalyzeCli, Stable32TablesHaveStable32sLayout) {
  for (const std::string stat : {"oadev", "mdev"}) {
    const Outcome r = run("--type phase --tau0 1 --alpha 0 --format stable32 --stats " + stat +
                          " " GYROCHAR_TEST_DATA "/phasedat/PHASE.DAT");
    ASSERT_EQ(r.code, exit_code::ok) << r.err;
    std::ifstream ref(GYROCHAR_TEST_DATA "/phasedat/phase_dat_" + stat + "_octave.txt");
    std::vector<std::string> want, got;
    for (std::string line; std::getline(ref, line);) {
      if (!line.empty() && line.back() == '\r') line.pop_back();
      if (!want.empty() || line.rfind("# STATISTICS", 0) == 0) want.push_back(line);  // from the header on
    }
    std::istringstream out(r.out);
    for (std::string line; std::getline(out, line);) got.push_back(line);
    ASSERT_GE(got.size(), 10u);
    EXPECT_EQ(got[0], "# STATISTICS FOR FILE: PHASE.DAT");
    for (std::size_t i = 0; i < 10; ++i) EXPECT_EQ(got[i], want[i]) << stat << " header line " << i;
    std::size_t compared = 0;
    for (std::size_t i = 10; i < want.size(); ++i) {
      const auto row = std::find_if(got.begin() + 10, got.end(),
                                    [&](const std::string& g) { return g.substr(0, 5) == want[i].substr(0, 5); });
      if (row == got.end()) continue;
      ++compared;
      ASSERT_EQ(row->size(), want[i].size()) << *row << "\n" << want[i];
      for (std::size_t c = 0; c < row->size(); ++c)  // fields end in the same columns
        EXPECT_EQ((*row)[c] == ' ', want[i][c] == ' ') << stat << ": column " << c << "\n" << *row << "\n" << want[i];
      EXPECT_EQ(row->substr(0, 33), want[i].substr(0, 33)) << "AF, Tau, #, Alpha";
      std::istringstream g(*row), w(want[i]);
      double gv[7], wv[7];
      for (int k = 0; k < 7; ++k) g >> gv[k], w >> wv[k];
      EXPECT_NEAR(gv[5] / wv[5], 1.0, 1e-4) << *row;
      EXPECT_NEAR(gv[4] / wv[4], 1.0, 0.05) << *row;
      EXPECT_NEAR(gv[6] / wv[6], 1.0, 0.05) << *row;
    }
    EXPECT_GE(compared, 8u) << stat;
  }
}

TEST(AnalyzeCli, HelpHasExamplesAndExitCodes) {
  const Outcome r = run("--help");
  EXPECT_EQ(r.code, 0);
  for (const char* part : {"Examples:", exit_code::help, "--type", "--pulse-weight", "--stride-factor", "2^16"})
    EXPECT_NE(r.out.find(part), std::string::npos) << part;
}

TEST(AnalyzeCli, TotalFamilyInEveryFormat) {
  // 20000 counts of white rate noise (white FM): every statistic of the family gives rows in the
  // table, CSV and JSON. Oracles: white FM's TOTDEV, MTOTDEV and Theo1 follow ADEV's 1/sqrt(tau)
  // shape (SP 1065: all of them estimate it, Theo1 at tau = 0.75 m tau0) and their unbiased
  // expectation at m = 1 is 2 pulses / 1 ms = ADEV; ttotdev is in the angle unit.
  std::string s;
  for (const int c : white_rate_counts()) s += std::to_string(c) + "\n";
  const std::string path = file_with("white_total.txt", s);
  const std::string args =
      "--type counts --tau0 0.001 --pulse-weight 1arcsec --rate-unit deg/h "
      "--stats oadev,totdev,mtotdev,ttotdev,htotdev,theo1,theoh ";
  const Outcome table = run(args + path);
  ASSERT_EQ(table.code, 0) << table.err;
  for (const char* stat : {"\ntotdev ", "\nmtotdev ", "\nttotdev ", "\nhtotdev ", "\ntheo1 ", "\ntheoh "})
    EXPECT_NE(table.out.find(stat), std::string::npos) << stat;
  const Outcome csv = run(args + "--format csv " + path);
  ASSERT_EQ(csv.code, 0) << csv.err;
  EXPECT_NE(csv.out.find("\nttotdev,1,0.001,"), std::string::npos);
  EXPECT_NE(csv.out.find(",arcsec,"), std::string::npos) << "ttotdev in the angle unit";
  const Outcome js = run(args + "--format json " + path);
  ASSERT_EQ(js.code, 0) << js.err;
  const auto j = nlohmann::json::parse(js.out);
  std::map<std::string, std::vector<nlohmann::json>> by_stat;
  for (const auto& row : j["results"]) by_stat[row["stat"]].push_back(row);
  for (const char* stat : {"totdev", "mtotdev", "ttotdev", "htotdev", "theo1", "theoh"})
    EXPECT_GT(by_stat[stat].size(), 5u) << stat;
  const double adev1 = by_stat["oadev"][0]["dev"];  // deg/h at m = 1
  EXPECT_NEAR(by_stat["totdev"][0]["dev"].get<double>() / adev1, 1.0, 0.02);
  for (const auto& row : by_stat["theo1"]) {  // 1/sqrt(tau) from ADEV at m = 1, within 25 % (EDF >= 30 here)
    const double want = adev1 / std::sqrt(row["tau"].get<double>() / 0.001);
    if (row["edf"].get<double>() > 30) {
      EXPECT_NEAR(row["dev"].get<double>() / want, 1.0, 0.25) << row["m"];
    }
    EXPECT_DOUBLE_EQ(row["tau"].get<double>(), 0.75 * row["m"].get<double>() * 0.001);
  }
  // Each row says which estimator made it: every one exact here (stride 1), mtotdev, ttotdev,
  // htotdev, theo1 and theoh by lag sums (total_fast.hpp); the decimated plan under
  // --total-decimated is MtotRowsAreExactUnlessTheDecimatedEstimatorIsAsked's.
  for (const auto& [stat, rows] : by_stat)
    for (const auto& row : rows) EXPECT_EQ(row["stride"].get<std::uint64_t>(), 1u) << stat << " m=" << row["m"];
  EXPECT_EQ(by_stat["htotdev"].back()["m"], 4096) << "m = 4096: exact";
}

TEST(AnalyzeCli, TheoRowsAreExactUnlessTheDecimatedEstimatorIsAsked) {
  // 40000 phase points of white noise: Theo1 from m = 4096 to 32768 costs over 2^26 operations
  // directly. Oracles: the direct exact theo1 (total.hpp) for the default rows, the plan's stride
  // theo1_stride(m, N, 16) for --theo-decimated rows.
  std::mt19937_64 rng(5);
  std::normal_distribution<double> z;
  std::vector<double> x(40000);
  std::string s;
  for (double& v : x) {
    v = z(rng);
    s += std::to_string(v) + "\n";
  }
  x.clear();
  std::istringstream back(s);  // the values as the file holds them
  for (double v; back >> v;) x.push_back(v);
  const std::string path = file_with("white_theo.txt", s);
  const std::string args = "--type phase --tau0 1 --stats oadev,theo1 --format json ";
  for (const bool decimated : {false, true}) {
    const Outcome r = run(args + (decimated ? "--theo-decimated " : "") + path);
    ASSERT_EQ(r.code, 0) << r.err;
    int strided = 0;
    const auto j = nlohmann::json::parse(r.out);
    for (const auto& row : j["results"]) {
      if (row["stat"].get<std::string>() != "theo1") continue;
      const std::uint64_t m = row["m"];
      const std::uint64_t want = decimated ? gyrochar::theo1_stride(m, x.size(), 16) : 1;
      EXPECT_EQ(row["stride"].get<std::uint64_t>(), want) << m;
      strided += want > 1;
      if (!decimated) {
        const double exact = std::sqrt(gyrochar::theo1(x, m, 1.0).var);
        EXPECT_NEAR(row["dev"].get<double>() / exact, 1.0, 1e-9) << m;  // two summation orders
      }
    }
    EXPECT_EQ(strided, decimated ? 4 : 0);  // m = 4096 to 32768
  }
}

TEST(AnalyzeCli, MtotRowsAreExactUnlessTheDecimatedEstimatorIsAsked) {
  // 12000 phase points of a random walk plus white noise: MTOTDEV and HTOTDEV at m = 512 to 2048
  // cost over 2^26 operations directly. Oracles: the direct exact mtotvar and htotvar (total.hpp)
  // for the default rows (mtotdev, ttotdev, htotdev), the plan's block total_block(m, N, 16) for
  // --total-decimated rows.
  std::mt19937_64 rng(6);
  std::normal_distribution<double> z;
  std::string s;
  double walk = 0;
  for (int i = 0; i < 12000; ++i) s += std::to_string((walk += 0.1 * z(rng)) + z(rng)) + "\n";
  std::vector<double> x, scratch;
  std::istringstream back(s);  // the values as the file holds them
  for (double v; back >> v;) x.push_back(v);
  const std::string path = file_with("walk_mtot.txt", s);
  const std::string args = "--type phase --tau0 1 --stats mdev,ohdev,mtotdev,ttotdev,htotdev --alpha 0 --format json ";
  for (const bool decimated : {false, true}) {
    const Outcome r = run(args + (decimated ? "--total-decimated " : "") + path);
    ASSERT_EQ(r.code, 0) << r.err;
    int strided = 0, rows = 0;
    const auto j = nlohmann::json::parse(r.out);
    for (const auto& row : j["results"]) {
      const std::string stat = row["stat"];
      if (stat != "mtotdev" && stat != "ttotdev" && stat != "htotdev") continue;
      const std::uint64_t m = row["m"];
      const std::uint64_t want = decimated ? gyrochar::total_block(m, x.size(), 16) : 1;
      EXPECT_EQ(row["stride"].get<std::uint64_t>(), want) << stat << " m=" << m;
      strided += want > 1, ++rows;
      if (!decimated) {
        scratch.resize(gyrochar::total_scratch_size(m, 1));
        const double md = static_cast<double>(m);
        // HTOTDEV carries Stable32's white-FM bias correction (alpha 0) from m = 2 on.
        const double exact = stat == "htotdev"
                                 ? gyrochar::htotvar(x, 1, m, 1.0, scratch).var / gyrochar::htotvar_bias(0, m)
                                 : gyrochar::mtotvar(x, 1, m, 1.0, scratch).var * (stat == "ttotdev" ? md * md / 3 : 1.0);
        EXPECT_NEAR(row["dev"].get<double>() / std::sqrt(exact), 1.0, 1e-9) << stat << " m=" << m;  // two summation orders
      }
    }
    EXPECT_EQ(rows, 3 * 12);                    // m = 1 .. 2048 for each
    EXPECT_EQ(strided, decimated ? 3 * 3 : 0);  // m = 512, 1024 and 2048
  }
}

TEST(AnalyzeCli, CountsKeepExactMtotRowsUpToM128UnderThePlan) {
  // 80000 counts of a random-walk rate plus white noise under --total-decimated: MTOTDEV and HTOTDEV
  // at m = 64 and 128 cost over 2^26 operations directly, so the plan took them decimated (stride 4
  // and 8); for counts they now come exact from the lag table of the differences (total_lags.hpp),
  // stride 1; m = 256 stays decimated. Oracle: the direct exact mtotvar and htotvar (total.hpp) on
  // the phase, as the ratio of the m = 64 and 128 rows to the m = 16 row (direct and exact either
  // way), free of units; the same for the decimated MTOTDEV rows against the decimated estimator.
  std::mt19937_64 rng(8);
  std::normal_distribution<double> z;
  std::string s;
  std::vector<double> x{0.0};
  double rate = 0;
  for (int i = 0; i < 80000; ++i) {
    rate += 0.05 * z(rng);
    const long count = std::lround(100.0 + rate + 3.0 * z(rng));
    s += std::to_string(count) + "\n";
    x.push_back(x.back() + static_cast<double>(count));
  }
  const std::string path = file_with("counts_mtot.txt", s);
  const Outcome r = run(
      "--type counts --tau0 0.001 --pulse-weight 1arcsec --stats mdev,ohdev,mtotdev,htotdev "
      "--total-decimated --format json " +
      path);
  ASSERT_EQ(r.code, 0) << r.err;
  std::map<std::string, std::map<std::uint64_t, nlohmann::json>> rows;
  const auto j = nlohmann::json::parse(r.out);
  for (const auto& row : j["results"]) rows[row["stat"].get<std::string>()][row["m"].get<std::uint64_t>()] = row;
  std::vector<double> scratch(gyrochar::total_scratch_size(128, 1));
  for (const std::string stat : {"mtotdev", "htotdev"}) {
    const bool h = stat == "htotdev";
    EXPECT_EQ(rows[stat][64]["stride"], 1) << stat;
    EXPECT_EQ(rows[stat][128]["stride"], 1) << stat;
    EXPECT_EQ(rows[stat][256]["stride"], gyrochar::total_block(256, x.size(), 16)) << stat;
    const auto var = [&](std::uint64_t m) {  // HTOTDEV with Stable32's bias correction for the row's alpha
      const nlohmann::json& alpha = rows[stat][m]["alpha"];
      if (!h) return gyrochar::mtotvar(x, 1, m, 1.0, scratch).var;
      return gyrochar::htotvar(x, 1, m, 1.0, scratch).var / (alpha.is_null() ? 1.0 : gyrochar::htotvar_bias(alpha, m));
    };
    for (const std::uint64_t m : {64u, 128u}) {
      const double want = std::sqrt(var(m) / var(16));
      const double got = rows[stat][m]["dev"].get<double>() / rows[stat][16]["dev"].get<double>();
      EXPECT_NEAR(got / want, 1.0, 1e-11) << stat << " m=" << m;  // the direct sums' rounding
    }
  }
  // MTOTDEV's decimated rows come from the lag tables of the block sums (from m = 1024, b = 64, summed
  // from the record's sums over 64 samples held once: GroupSums): the estimator mtotvar(x, b, m)
  // computes (total.hpp, the oracle here, summed directly in double), at every decimated m.
  int decimated = 0;
  for (const auto& [m, row] : rows["mtotdev"]) {
    const std::uint64_t b = gyrochar::total_block(m, x.size(), 16);
    if (m <= 128) continue;  // exact, above
    ++decimated;
    EXPECT_EQ(row["stride"], b) << "m=" << m;
    std::vector<double> own(gyrochar::total_scratch_size(m, b));
    const double want = std::sqrt(gyrochar::mtotvar(x, b, m, 1.0, own).var / gyrochar::mtotvar(x, 1, 16, 1.0, scratch).var);
    const double got = row["dev"].get<double>() / rows["mtotdev"][16]["dev"].get<double>();
    EXPECT_NEAR(got / want, 1.0, 1e-11) << "mtotdev m=" << m;
  }
  EXPECT_EQ(decimated, 7);  // m = 256 .. 16384
}

TEST(AnalyzeCli, UnwritableOutputIsOutputFailed) {
  const Outcome r = run("--type phase --tau0 1 " + good_phase() + " > /dev/full");
  EXPECT_EQ(r.code, exit_code::output_failed) << r.err;
  EXPECT_EQ(r.err, "gyrochar-analyze: standard output: write failed: No space left on device\n");
}

TEST(AnalyzeCli, JsonHasTheDocumentedShape) {
  const Outcome r = run("--type phase --tau0 1 --stats oadev,mdev --format json " + good_phase());
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["tau0"], 1.0);
  EXPECT_EQ(j["n_samples"], 200);
  EXPECT_EQ(j["type"], "phase");
  EXPECT_FALSE(j.contains("fit"));      // only when asked
  EXPECT_FALSE(j.contains("readoff"));  // gyro data only
  ASSERT_FALSE(j["results"].empty());
  for (const auto& row : j["results"]) {
    for (const char* key : {"stat", "m", "tau", "n", "dev", "alpha", "edf", "ci_low", "ci_high"})
      EXPECT_TRUE(row.contains(key)) << key;
  }
  EXPECT_EQ(j["results"][0]["stat"], "oadev");
  EXPECT_EQ(j["results"][0]["n"], 198);  // N - 2m for m = 1 (Stable32's count)
}

TEST(AnalyzeCli, CountsInGyroUnitsFromGzipAndStdin) {
  // Constant 1000 pulses of 1 arcsec per 0.01 s: every deviation is exactly 0 (oracle: a constant
  // rate has no second differences); gzip and standard input give the same rows.
  std::string s;
  for (int i = 0; i < 500; ++i) s += "1000\n";
  const std::string path = file_with("counts.txt", s);
  ASSERT_EQ(std::system(("gzip -kf " + path).c_str()), 0);
  const Outcome a = run("--type counts --tau0 0.01 --pulse-weight 1arcsec --format csv " + path + ".gz");
  ASSERT_EQ(a.code, 0) << a.err;
  EXPECT_EQ(a.out.rfind("stat,m,tau,n,dev,unit,alpha,edf,ci_low,ci_high,stride\n", 0), 0u) << a.out;
  EXPECT_NE(a.out.find("\noadev,1,0.01,499,0,deg/h,"), std::string::npos) << a.out;
  const Outcome b = run("--type counts --tau0 0.01 --pulse-weight 1 --pulse-unit arcsec --format csv - < " + path);
  ASSERT_EQ(b.code, 0) << b.err;
  EXPECT_EQ(a.out, b.out);
}

TEST(AnalyzeCli, CountsAngleAndRateGiveTheSameGyroDeviations) {
  // One gyro run three ways (oracle: unit identities): counts of 1 arcsec per 1 ms; the angle in
  // arcsec, x_0 = 0, x_k = sum of the first k counts; the rate c * 1 arcsec / 1 ms = 1000 c deg/h
  // (1 arcsec/s = 1 deg/h). All in deg/s here, TDEV in deg.
  std::string counts, angle = "0\n", rate;
  long long x = 0;
  for (const int c : white_rate_counts()) {
    counts += std::to_string(c) + "\n";
    angle += std::to_string(x += c) + "\n";
    rate += std::to_string(1000 * c) + "\n";
  }
  const std::string common = " --tau0 0.001 --rate-unit deg/s --stats adev,oadev,mdev,tdev,ohdev --format json ";
  const Outcome a = run("--type counts --pulse-weight '1 arcsec'" + common + file_with("c.txt", counts));
  const Outcome b = run("--type phase --unit arcsec" + common + file_with("a.txt", angle));
  const Outcome c = run("--type freq --unit deg/h" + common + file_with("r.txt", rate));
  ASSERT_EQ(a.code, 0) << a.err;
  ASSERT_EQ(b.code, 0) << b.err;
  ASSERT_EQ(c.code, 0) << c.err;
  const auto ja = nlohmann::json::parse(a.out), jb = nlohmann::json::parse(b.out), jc = nlohmann::json::parse(c.out);
  ASSERT_EQ(ja["results"].size(), jb["results"].size());
  ASSERT_EQ(ja["results"].size(), jc["results"].size());
  ASSERT_GT(ja["results"].size(), 50u);
  for (std::size_t i = 0; i < ja["results"].size(); ++i) {
    const auto &ra = ja["results"][i], &rb = jb["results"][i], &rc = jc["results"][i];
    EXPECT_EQ(ra["unit"], ra["stat"] == "tdev" ? "deg" : "deg/s");
    for (const auto* r : {&rb, &rc}) {
      EXPECT_EQ((*r)["unit"], ra["unit"]);
      EXPECT_EQ((*r)["n"], ra["n"]);
      EXPECT_NEAR((*r)["dev"].get<double>() / ra["dev"].get<double>(), 1.0, 1e-9) << ra["stat"] << " m=" << ra["m"];
    }
  }
}

TEST(AnalyzeCli, FitRecoversTheAngleRandomWalkOfWhiteRateNoise) {
  // White rate noise of variance 4 pulses^2 per tau0 = 1 ms, 1 arcsec per pulse: AVAR = N^2 / tau
  // with N = 2 arcsec / sqrt(1 ms) = 2/3600 deg * sqrt(3600 / 0.001) / sqrt(h) = 1.05409 deg/sqrt(h)
  // (closed form, IEEE Std 952); the fit must find it within 3 of its standard uncertainties. The
  // EDF weights use the generating process's alpha = 0 (white FM), not the identified one.
  std::string counts;
  for (const int c : white_rate_counts()) counts += std::to_string(c) + "\n";
  const Outcome r = run("--type counts --tau0 0.001 --pulse-weight 1arcsec --alpha 0 --fit ieee952 --format json " +
                        file_with("white.txt", counts));
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j["fit"].size(), 3u);  // both curves (recommended), then avar and mvar alone
  EXPECT_EQ(j["fit"][0]["curve"], "both");
  EXPECT_TRUE(j["fit"][0]["recommended"].get<bool>());
  const double n_true = 2.0 / 3600.0 * std::sqrt(3600.0 / 0.001);
  for (const auto& fit : j["fit"]) {
    EXPECT_EQ(fit["N"]["unit"], "deg/sqrt(h)");
    ASSERT_TRUE(fit["N"]["resolved"].get<bool>()) << fit["curve"];
    EXPECT_NEAR(fit["N"]["value"].get<double>(), n_true, 3 * fit["N"]["uncertainty"].get<double>()) << fit["curve"];
  }
  const Outcome table = run("--type counts --tau0 0.001 --pulse-weight 1arcsec --alpha 0 --fit ieee952 " +
                            temp("white.txt"));
  EXPECT_NE(table.out.find("IEEE-952 fit of both curves (recommended)"), std::string::npos) << table.out;
  EXPECT_NE(table.out.find("IEEE-952 fit of the Allan curve alone"), std::string::npos) << table.out;
  EXPECT_NE(table.out.find("deg/sqrt(h)"), std::string::npos) << table.out;
  // With TOTDEV or TheoH at long tau (docs/metrology.md): the same closed form, and the fit says
  // what its Allan curve was made of.
  for (const char* input : {"totdev", "theoh"}) {
    const Outcome t = run(
        "--type counts --tau0 0.001 --pulse-weight 1arcsec --alpha 0 --fit ieee952 --format json "
        "--fit-long-tau " +
        std::string(input) + " " + temp("white.txt"));
    ASSERT_EQ(t.code, 0) << t.err;
    const auto k = nlohmann::json::parse(t.out);
    EXPECT_EQ(k["fit"][0]["long_tau"], input);
    EXPECT_EQ(k["fit"][2]["long_tau"], "oadev");  // the modified Allan curve alone has no Allan points
    const auto& n = k["fit"][0]["N"];
    ASSERT_TRUE(n["resolved"].get<bool>()) << input;
    EXPECT_NEAR(n["value"].get<double>(), n_true, 3 * n["uncertainty"].get<double>()) << input;
  }
}

TEST(AnalyzeCli, ProgressOnRequestForLongInputs) {
  // Progress appears every 2^20 values: a file of 2^20 + 1 values shows it with --progress (one
  // pass: reading), then the counts' taus summed (held counts, the default stride factor);
  // stdout still carries only the table.
  std::string s;
  s.reserve(2u << 21);
  for (int i = 0; i <= (1 << 20); ++i) s += i % 2 ? "2\n" : "1\n";  // not constant: no note
  const std::string path = file_with("long.txt", s);
  const Outcome r = run("--type counts --tau0 1 --pulse-weight 1arcsec --taus 1 --progress " + path);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("reading: 100.0 %"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("summing: 1 of 1 taus\n"), std::string::npos) << r.err;
  EXPECT_EQ(r.out.find("gyrochar-analyze"), std::string::npos);
  const Outcome quiet = run("--type counts --tau0 1 --pulse-weight 1arcsec --taus 1 " + path);
  EXPECT_TRUE(quiet.err.empty()) << quiet.err;  // stderr is a file here, not a terminal
  // --taus all on phase and frequency sums its taus over the held record too, and says how far
  // (200 phase points: m = 1 .. 100; 200 frequency values: 201 points, the same taus).
  for (const std::string type : {"phase", "freq"}) {
    const Outcome all = run("--type " + type + " --tau0 1 --taus all --progress --format csv " + good_phase());
    ASSERT_EQ(all.code, 0) << all.err;
    EXPECT_NE(all.err.find("summing: 100 of 100 taus\n"), std::string::npos) << all.err;
  }
  // The total family says how far each statistic is, each stage ending with all its taus done (as
  // many as its rows; TheoH's Theo1 taus and its bias ratio's, whose counts the rows do not show).
  const Outcome total = run("--type phase --tau0 1 --stats oadev,totdev,mtotdev,theoh --progress --format csv " +
                            good_phase());
  ASSERT_EQ(total.code, 0) << total.err;
  for (const std::string stat : {"totdev", "mtotdev"}) {
    std::size_t rows = 0;
    for (std::size_t at = total.out.find("\n" + stat + ","); at != std::string::npos;
         at = total.out.find("\n" + stat + ",", at + 1))
      ++rows;
    ASSERT_GT(rows, 3u) << total.out;
    const std::string n = std::to_string(rows);
    EXPECT_NE(total.err.find("\rgyrochar-analyze: " + stat + ": " + n + " of " + n + " taus\n"), std::string::npos)
        << stat << "\n"
        << total.err;
  }
  for (const std::string stage : {"theoh bias ratio", "theoh"}) {
    const std::string line = "\rgyrochar-analyze: " + stage + ": ";
    const std::size_t at = total.err.rfind(line);  // the stage's last line
    ASSERT_NE(at, std::string::npos) << stage << "\n" << total.err;
    std::size_t done = 0, of = 0;
    ASSERT_EQ(std::sscanf(total.err.c_str() + at + line.size(), "%zu of %zu taus\n", &done, &of), 2) << total.err;
    EXPECT_EQ(done, of) << stage << "\n" << total.err;
    EXPECT_GT(of, 0u) << stage;
  }
  EXPECT_EQ(total.out.find("gyrochar-analyze"), std::string::npos);
}

// The rows of --format csv: stat, m, n, dev.
struct CsvRow {
  std::string stat;
  std::uint64_t m = 0, n = 0;
  double dev = 0;
};
std::vector<CsvRow> csv_rows(const std::string& csv) {
  std::vector<CsvRow> rows;
  std::istringstream in(csv);
  std::string line;
  std::getline(in, line);  // the column names
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    std::string stat, m, tau, n, dev;
    std::getline(fields, stat, ',');
    std::getline(fields, m, ',');
    std::getline(fields, tau, ',');
    std::getline(fields, n, ',');
    std::getline(fields, dev, ',');
    rows.push_back({stat, std::stoull(m), std::stoull(n), std::stod(dev)});
  }
  return rows;
}

TEST(AnalyzeCli, TheReaderNeverMisreads) {
  const std::string counts = "--type counts --tau0 1 --pulse-weight 1arcsec ";
  // A NUL byte does not join "3" and "4" into 34: the line is refused, the byte named.
  const Outcome nul = run_shell("printf '1\\n2\\n3\\0\\n4\\n5\\n6\\n' | " + tool + " " + counts + "-");
  EXPECT_EQ(nul.code, 2) << nul.err;
  EXPECT_NE(nul.err.find("standard input: line 3: "), std::string::npos) << nul.err;
  EXPECT_NE(nul.err.find("\\x00"), std::string::npos) << nul.err;
  // Decimal commas are not read as their integer part.
  expect_bad_input(counts + file_with("comma.txt", "1,288185\n1,288190\n1,288195\n"), "decimal comma");
  expect_bad_input("--type phase --tau0 1 --column 2 " + file_with("semi.csv", "0,1;1,5\n0,2;1,6\n"), "decimal comma");
  // A binary file's bytes are not echoed: the one line on stderr is printable ASCII.
  std::string bytes = "\x89PNG\r\n";
  for (int i = 0; i < 2000; ++i) bytes += static_cast<char>((i * 131 + 7) % 256);
  const Outcome binary = run(counts + file_with("image.png", bytes));
  EXPECT_EQ(binary.code, 2);
  for (const char c : binary.err) EXPECT_TRUE((c >= 0x20 && c < 0x7f) || c == '\n') << binary.err;
  // A gzip error on standard input names standard input.
  std::string many;
  for (int i = 0; i < 20000; ++i) many += std::to_string(1000 + i * 7919 % 1013) + "\n";
  const std::string whole = file_with("stdin.txt", many);
  ASSERT_EQ(std::system(("gzip -kf " + whole + " && head -c 2000 " + whole + ".gz > " + whole + ".cut.gz").c_str()), 0);
  const Outcome cut = run(counts + "- < " + whole + ".cut.gz");
  EXPECT_EQ(cut.code, 2);
  EXPECT_EQ(cut.err.rfind("gyrochar-analyze: standard input: ", 0), 0u) << cut.err;
  EXPECT_NE(cut.err.find("unexpected end of file"), std::string::npos) << cut.err;
  EXPECT_EQ(cut.err.find("<fd:"), std::string::npos) << cut.err;
}

TEST(AnalyzeCli, TimeAndValueTableIsReadFromItsValueColumnAndSaysSo) {
  std::string table = "# time, count\n";
  for (int i = 0; i < 3000; ++i) table += std::to_string(i * 0.01) + "," + std::to_string(1000 + (i * 7919) % 13) + "\n";
  const std::string path = file_with("time_value.csv", table);
  const std::string args = "--type counts --tau0 0.01 --pulse-weight 1arcsec --format csv ";
  const Outcome chosen = run(args + path);
  ASSERT_EQ(chosen.code, 0) << chosen.err;
  EXPECT_NE(chosen.err.find("column 2"), std::string::npos) << chosen.err;  // said, on stderr
  const Outcome asked = run(args + "--column 2 " + path);
  ASSERT_EQ(asked.code, 0) << asked.err;
  EXPECT_TRUE(asked.err.empty()) << asked.err;
  EXPECT_EQ(chosen.out, asked.out);
  // Time stamps that do not increase: no guess, a hint.
  expect_bad_input(args + file_with("two.txt", "5 1000\n3 1001\n4 1002\n"), "--column");
}

TEST(AnalyzeCli, HugeStrideFactorOnStandardInputIsNoAllocationFailure) {
  // S = 2^24 with octave taus for an input of unknown length: the taus stop where the history
  // fits the memory the process may use (here an address space of 4 GB); below 2 GB not even
  // the first level fits, which is said, not a std::bad_alloc.
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "AddressSanitizer reserves terabytes of address space: it cannot run under ulimit -v";
#endif
  const std::string args = "--type counts --tau0 1 --pulse-weight 1arcsec --stride-factor 16777216 --format csv - ";
  const Outcome fits = run_shell("ulimit -v 4000000; printf '1\\n2\\n3\\n4\\n5\\n6\\n7\\n' | " + tool + " " + args);
  EXPECT_EQ(fits.code, 0) << fits.err;
  EXPECT_EQ(csv_rows(fits.out).size(), 4u) << fits.out;  // 8 phase points: oadev and mdev at m = 1, 2
  expect_bad_input(args + "< " + good_phase(), "--stride-factor", "ulimit -v 1000000; ");
}

TEST(AnalyzeCli, AFileBeyondTheMemoryLimitNamesTheLimit) {
  // Under ulimit -v 524288 (512 MiB) the process may use 256 MiB. A file of 1 GiB (sparse: the plan
  // reads only its size) may hold 2^29 + 1 values (its bound), whose default plan (every tau up to
  // N/4 fully overlapped: S = 2^24, 3 x 2^24 history entries of 24 bytes = 1152 MiB) does not fit: the
  // message names the limit and the sizes (exit 1: memory exhausted), not a --stride-factor the
  // user never gave.
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "AddressSanitizer reserves terabytes of address space: it cannot run under ulimit -v";
#endif
  const std::string big = temp("big.txt");
  ASSERT_EQ(std::system(("truncate -s 1G " + big).c_str()), 0);
  for (const std::string type : {"counts --pulse-weight 1arcsec", "phase", "freq"}) {
    const Outcome r = run_shell("ulimit -v 524288; " + tool + " --type " + type + " --tau0 1 " + big);
    EXPECT_EQ(r.code, exit_code::internal) << r.err;
    EXPECT_NE(r.err.find("gyrochar-analyze: " + big +
                         ": 536870913 values (at most, from the file's size) need 1152 MiB "
                         "of memory with every tau up to N/4 fully overlapped (--stride-factor full, the default), more "
                         "than the 256 MiB this process may use (half of its address-space limit, ulimit -v 524288 "
                         "KiB)"),
              std::string::npos)
        << r.err;
    EXPECT_EQ(r.err.find("--stride-factor:"), std::string::npos) << r.err;
    EXPECT_TRUE(r.out.empty());
  }
  std::remove(big.c_str());
}

TEST(AnalyzeCli, AllTausEqualTheirBruteForceFromFileStdinAndGzip) {
  // 300 counts (301 phase points): every m up to 150 for oadev, up to 100 for mdev and ohdev. The
  // oracle sums the definitions exactly (tests/oracle/brute_force.hpp); with 1 arcsec pulses and
  // tau0 = 1 s the deviations in deg/h are those in pulses per second.
  std::mt19937_64 rng(11);
  std::uniform_int_distribution<int> count(900, 1100);
  std::string text;
  std::vector<std::int64_t> x{0};
  for (int i = 0; i < 300; ++i) {
    const int c = count(rng);
    text += std::to_string(c) + "\n";
    x.push_back(x.back() + c);
  }
  const std::string path = file_with("all.txt", text);
  ASSERT_EQ(std::system(("gzip -kf " + path).c_str()), 0);
  const std::string args = "--type counts --tau0 1 --pulse-weight 1arcsec --taus all --stats oadev,mdev,ohdev --format csv ";
  const Outcome file = run(args + path);
  ASSERT_EQ(file.code, 0) << file.err;
  const auto rows = csv_rows(file.out);
  ASSERT_EQ(rows.size(), 150u + 100u + 100u);
  for (const CsvRow& r : rows) {
    const auto exact = gyrochar::oracle::brute_force(x, r.m, 1);
    const double m = static_cast<double>(r.m);
    const int k = r.stat == "oadev" ? 0 : r.stat == "mdev" ? 1 : 2;
    const double scale = k == 0 ? 2 * m * m : k == 1 ? 2 * m * m * m * m : 6 * m * m;
    EXPECT_EQ(r.n, exact.n[k]) << r.stat << " m=" << r.m;
    EXPECT_NEAR(r.dev / std::sqrt(static_cast<double>(exact.sum[k]) / (scale * static_cast<double>(exact.n[k]))), 1.0, 1e-12)
        << r.stat << " m=" << r.m;
  }
  EXPECT_EQ(run(args + "- < " + path).out, file.out);
  EXPECT_EQ(run(args + path + ".gz").out, file.out);
}

// --- the dynamic Allan deviation -------------------------------------------------------------

TEST(AnalyzeCli, DynamicWritesTheSurfaceAndTheHeatMaps) {
  // 20000 counts of 1 ms; windows of 5 s (5000 values) every 2.5 s: 7 windows. Oracle for the
  // values: the same analysis of one window's counts cut out into a file of its own.
  const std::vector<int> c = white_rate_counts();
  std::string all, window3;
  for (std::size_t k = 0; k < c.size(); ++k) {
    all += std::to_string(c[k]) + "\n";
    if (k >= 7500 && k < 12500) window3 += std::to_string(c[k]) + "\n";
  }
  const std::string path = file_with("dynamic.txt", all), alone = file_with("window3.txt", window3);
  const std::string common = "--type counts --tau0 0.001 --pulse-weight 1arcsec --stats oadev,mdev ";
  const Outcome j = run(common + "--dynamic 5,2.5 --format json " + path);
  ASSERT_EQ(j.code, 0) << j.err;
  const nlohmann::json doc = nlohmann::json::parse(j.out);
  EXPECT_EQ(doc["dynamic"]["window"], 5000);
  EXPECT_EQ(doc["dynamic"]["step"], 2500);
  ASSERT_EQ(doc["windows"].size(), 7u);
  const nlohmann::json& w3 = doc["windows"][3];
  EXPECT_EQ(w3["index"], 3);
  EXPECT_DOUBLE_EQ(w3["start"].get<double>(), 7.5);
  EXPECT_DOUBLE_EQ(w3["end"].get<double>(), 12.5);
  // Taus up to a quarter of the window: octaves 1 .. 1024 (4 x 1024 <= 5000 < 4 x 2048).
  const Outcome ref = run(common + "--taus 1,2,4,8,16,32,64,128,256,512,1024 --format json " + alone);
  ASSERT_EQ(ref.code, 0) << ref.err;
  const nlohmann::json expected = nlohmann::json::parse(ref.out)["results"];
  ASSERT_EQ(w3["results"].size(), expected.size());
  for (std::size_t i = 0; i < expected.size(); ++i) {
    EXPECT_EQ(w3["results"][i]["m"], expected[i]["m"]);
    EXPECT_EQ(w3["results"][i]["dev"], expected[i]["dev"]) << i;
    EXPECT_EQ(w3["results"][i]["ci_low"], expected[i]["ci_low"]) << i;
  }
  // The CSV: one row per window, statistic and tau, after its header.
  const Outcome csv = run(common + "--dynamic 5,2.5 --format csv " + path);
  ASSERT_EQ(csv.code, 0) << csv.err;
  EXPECT_EQ(csv.out.rfind("window,start,end,stat,m,tau,n,dev,unit,", 0), 0u);
  EXPECT_EQ(std::count(csv.out.begin(), csv.out.end(), '\n'), 1 + 7 * 2 * 11);
  // The heat maps, and the table for people.
  const std::string prefix = temp("heat");
  const Outcome table = run(common + "--dynamic 5 --plot " + prefix + " " + path);
  ASSERT_EQ(table.code, 0) << table.err;
  EXPECT_NE(table.out.find("windows of 5000 values (5 s) every 5000 values (5 s), 4 complete"), std::string::npos)
      << table.out;
  struct stat st {};
  for (const char* ext : {".svg", ".png"}) {
    ASSERT_EQ(stat((prefix + ext).c_str(), &st), 0) << ext;
    EXPECT_GT(st.st_size, 1000) << ext;
  }
}

TEST(AnalyzeCli, DynamicRefusesWhatItCannotDo) {
  const std::string good = good_phase();
  expect_bad_input("--type phase --tau0 1 --dynamic x " + good, "--dynamic");
  expect_bad_input("--type phase --tau0 1 --dynamic 100,-1 " + good, "--dynamic");
  expect_bad_input("--type phase --tau0 1 --dynamic 100,50,25 " + good, "--dynamic");
  expect_bad_input("--type phase --tau0 1 --dynamic 3 " + good, "at least 4");
  expect_bad_input(
      "--type phase --tau0 1 --dynamic 1e308 " + good,
      "--dynamic: a window of 1e+308 s is 1e+308 values of tau0 = 1 s, more than the 1e+15 a window or step may span");
  expect_bad_input("--type phase --tau0 1e-9 --dynamic 100,1e7 " + good, "a step of 1e+07 s is 1e+16 values");
  expect_bad_input("--type phase --tau0 1 --dynamic 100,0.4 " + good, "shorter than tau0");
  expect_bad_input("--type phase --tau0 1 --dynamic 500 " + good, "fewer than one window");
  expect_bad_input("--type phase --tau0 1 --dynamic 100 --taus 1,50 " + good, "quarter of the window");
  // (--plot without --dynamic draws the whole record's curves: tests/host/test_psd_cli.cpp.)
  expect_bad_input("--type phase --tau0 1 --dynamic 100 --psd p.csv " + good, "--psd");
  expect_bad_input("--type counts --tau0 1 --pulse-weight 1arcsec --fit ieee952 --dynamic 100 " + good, "--fit");
}

}  // namespace
