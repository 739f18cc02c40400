// gyrochard's start-up as an operator meets it: invalid configuration (command line or file, named
// by file and line) names the key and exits bad_input with nothing started, before any hardware is
// opened; a missing CAN interface or GPIO chip exits no_hardware and names it. Oracle: the exit
// codes of hal/exit_codes.hpp.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <string>

#include "hal/exit_codes.hpp"

namespace {

using namespace gyrochar;

const std::string tool = GYROCHAR_BINARY_DIR "/firmware/gyrochard";

struct Outcome {
  int code = -1;
  std::string err;
};

Outcome run(const std::string& args) {
  const std::string err_file = ::testing::TempDir() + std::to_string(getpid()) + "_gyrochard_err.txt";
  const int status = std::system((tool + " " + args + " >/dev/null 2>" + err_file).c_str());
  std::ifstream e(err_file);
  Outcome r;
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.err.assign(std::istreambuf_iterator<char>(e), {});
  return r;
}

void expect(const std::string& args, int code, const std::string& what) {
  const Outcome r = run(args);
  EXPECT_EQ(r.code, code) << args << ": " << r.err;
  EXPECT_EQ(r.err.rfind("gyrochard: " + what, 0), 0u) << args << ": " << r.err;
}

std::string conf_file(const std::string& name, const std::string& content) {
  const std::string path = ::testing::TempDir() + std::to_string(getpid()) + "_" + name + ".conf";
  std::ofstream(path) << content;
  return path;
}

TEST(GyrochardStart, InvalidConfigurationNamesTheKey) {
  const int bad = exit_code::bad_input;
  expect("--source can-counter --tau0 -1", bad, "tau0: ");
  expect("--source can-counter --stride-factor 6", bad, "stride-factor: ");
  expect("--source can-counter --octaves 41", bad, "octaves: ");
  expect("--source can-counter --node 254", bad, "node: ");
  expect("--source can-counter --report-period 0.0001 --tau0 0.01", bad, "report-period: ");
  expect("--source strobe", bad, "counter-path: ");
  expect("--source can-counter --bogus 1", bad, "command line: ");
}

// The protocol's ReportPeriod is 100..2000 ms (docs/protocol.md): 100 s used to wrap in 16 bits.
TEST(GyrochardStart, ReportPeriodStaysWithinTheProtocolsRange) {
  expect("--source can-counter --report-period 100", exit_code::bad_input, "report-period: must be 0.1..2 s");
  expect("--source can-counter --report-period 2.5", exit_code::bad_input, "report-period: must be 0.1..2 s");
  expect("--source can-counter --report-period 0.05", exit_code::bad_input, "report-period: must be 0.1..2 s");
}

TEST(GyrochardStart, TheConfigurationFileIsCheckedLineByLine) {
  const int bad = exit_code::bad_input;
  std::string f = conf_file("typo", "source = can-counter\ntua0 = 0.5\n");
  expect("--config " + f, bad, f + ":2: tua0: unknown key");
  f = conf_file("no_equals", "source = can-counter\n\n# a comment\ntau0 0.5\n");
  expect("--config " + f, bad, f + ":4: tau0 0.5: not a 'key = value' line");
  f = conf_file("not_a_number", "source = can-counter\ntau0 = fast\n");
  expect("--config " + f, bad, f + ":2: tau0: 'fast' is not valid");
  f = conf_file("twice", "octaves = 8\noctaves = 9\n");
  expect("--config " + f, bad, f + ":2: octaves: given twice (first at line 1)");
  f = conf_file("range", "source = can-counter   # counts from CAN\ntau0 = 0\n");
  expect("--config " + f, bad, f + ":2: tau0: must be a positive number of seconds");
  f = conf_file("nested", "config = other.conf\n");
  expect("--config " + f, bad, f + ":1: config: unknown key");
  expect("--config /nonexistent/gyrochard.conf", bad, "config: /nonexistent/gyrochard.conf: No such file");
  // The command line overrides the file: the bad file value is not in force.
  f = conf_file("overridden", "source = can-counter\ntau0 = 0\n");
  expect("--config " + f + " --tau0 0.01 --stride-factor 3", bad, "stride-factor: ");
}

TEST(GyrochardStart, ConfigurationIsCheckedBeforeAnyHardware) {
  // Both wrong: the configuration is reported (2), not the missing interface (3).
  expect("--source can-counter --can-interface nosuchcan9 --octaves 0", exit_code::bad_input, "octaves: ");
  expect("--source can-counter --can-interface nosuchcan9 --checkpoint /nonexistent-dir/run.ckpt",
         exit_code::bad_input, "checkpoint: /nonexistent-dir: No such file or directory");
  const std::string file = conf_file("plain_file", "");
  expect("--source can-counter --can-interface nosuchcan9 --checkpoint " + file + "/run.ckpt", exit_code::bad_input,
         "checkpoint: " + file + ": not a directory");
}

TEST(GyrochardStart, MissingHardwareIsNamedByItsName) {
  expect("--source can-counter --can-interface nosuchcan9", exit_code::no_hardware, "nosuchcan9: ");
  expect("--source quadrature --gpio-chip nosuchchip9", exit_code::no_hardware, "nosuchchip9: ");
  expect("--source strobe --gpio-chip nosuchchip9 --counter-path /nonexistent", exit_code::no_hardware, "nosuchchip9: ");
  EXPECT_EQ(run("--help").code, exit_code::ok);
}

}  // namespace
