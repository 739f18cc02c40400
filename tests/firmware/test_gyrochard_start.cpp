// gyrochard's start-up as an operator meets it: invalid configuration (command line or file, named
// by file and line) names the key and exits bad_input with nothing started, before any hardware is
// opened; a missing CAN interface or GPIO chip exits no_hardware and names it; reads of the
// configuration are bounded; control bytes from it are escaped. Oracle: the exit codes of
// hal/program/exit_codes.hpp.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <string>

#include "hal/program/exit_codes.hpp"
#include "support/shell.hpp"

namespace {

using namespace gyrochar;

const std::string tool = GYROCHAR_BINARY_DIR "/firmware/gyrochard";

struct Outcome {
  int code = -1;
  std::string err;
};

Outcome run(const std::string& args) {
  const std::string err_file = gyrochar::test_support::temp_path("gyrochard_err.txt");
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
  const std::string path = gyrochar::test_support::temp_path(name + ".conf");
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
  expect("--source can-counter --can-interface nosuchcan9 --checkpoint /nonexistent-dir/run.ckpt", exit_code::bad_input,
         "checkpoint: /nonexistent-dir: No such file or directory");
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

// Found by a hostile-input sweep: `--config /dev/zero` grew to 2.1 GB, a 50 MB value took 525 MB. The file is read up
// to 65536 bytes and a line up to 4096 (firmware/config.hpp), under a 256 MB address-space limit
// that the old reads would have exceeded (/dev/zero never ends).
TEST(GyrochardStart, ConfigurationReadsAreBounded) {
  const int bad = exit_code::bad_input;
  Outcome r = run("--config /dev/zero");
  EXPECT_EQ(r.code, bad) << r.err;
  EXPECT_EQ(r.err, "gyrochard: config: /dev/zero: larger than 65536 bytes (the limit for a configuration file)\n");
#if !defined(__SANITIZE_ADDRESS__)  // AddressSanitizer reserves terabytes of address space: not under ulimit -v
  const std::string limit = "ulimit -v 262144; ";
  const int status = std::system(("bash -c '" + limit + tool + " --config /dev/zero' 2>/dev/null").c_str());
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == bad) << status;
#endif
  std::string f = conf_file("long_value", "source = can-counter\ncan-interface = " + std::string(5000, 'x') + "\n");
  expect("--config " + f, bad, f + ":2: config: line longer than 4096 bytes (the limit)");
  f = conf_file("big", "# " + std::string(70000, '#') + "\n");  // a comment too: the file's size counts
  expect("--config " + f, bad, "config: " + f + ": larger than 65536 bytes");
  // At the limits exactly, a 4096-byte line and a 65536-byte file are read to their last line.
  const std::size_t blank = 65536 - 4097 - 12;
  f = conf_file("at_limits", "#" + std::string(4095, 'x') + "\n" + std::string(blank, '\n') + "octaves = 0\n");
  expect("--config " + f, bad, f + ":" + std::to_string(blank + 2) + ": octaves: must be 1..40");
}

TEST(GyrochardStart, TheHelpStatesTheLimitsAndExitFour) {
  const std::string out = gyrochar::test_support::temp_path("help.txt");
  ASSERT_EQ(std::system((tool + " --help >" + out).c_str()), 0);
  std::ifstream in(out);
  const std::string help{std::istreambuf_iterator<char>(in), {}};
  EXPECT_NE(help.find("at most 65536 bytes, a line at\nmost 4096 bytes"), std::string::npos) << help;
  EXPECT_NE(help.find("4 when a\ncheckpoint could not be written"), std::string::npos) << help;
}

// An interface name that can never be valid (more than IFNAMSIZ - 1 = 15 characters, or a '/',
// as hal/linux/can_interface says) is bad input, not missing hardware.
TEST(GyrochardStart, AnImpossibleInterfaceNameIsBadInput) {
  expect("--source can-counter --can-interface abcdefghijklmnop", exit_code::bad_input,
         "can-interface: an interface name has at most 15 characters, this one 16");
  expect("--source can-counter --can-interface can/0", exit_code::bad_input,
         "can-interface: an interface name cannot hold '/', ':', spaces or control characters");
  expect("--source can-counter --can-interface nosuchcan123456", exit_code::no_hardware, "nosuchcan123456: ");
}

// Control bytes from the file (ESC, NUL) reach stderr as \xNN, as the analyzer shows a data file's.
TEST(GyrochardStart, ControlBytesFromTheFileAreEscaped) {
  const std::string f = conf_file("control", std::string("tau0\x1b[2J = 1\n", 14));
  Outcome r = run("--config " + f);
  EXPECT_EQ(r.code, exit_code::bad_input);
  EXPECT_NE(r.err.find("tau0\\x1b[2J: unknown key"), std::string::npos) << r.err;
  const std::string g = conf_file("nul", std::string("source = can-counter\ntau0 = 1\0x\n", 32));
  r = run("--config " + g);
  EXPECT_EQ(r.code, exit_code::bad_input);
  EXPECT_NE(r.err.find("'1\\x00x' is not valid"), std::string::npos) << r.err;
  const std::string h = conf_file("esc_interface", "source = can-counter\ncan-interface = \"x\x1b[31m\"\n");
  r = run("--config " + h);  // a control byte can never be in an interface name: bad input
  EXPECT_EQ(r.code, exit_code::bad_input);
  EXPECT_NE(r.err.find("can-interface: an interface name cannot hold"), std::string::npos) << r.err;
  for (const Outcome& o : {run("--config " + f), run("--config " + g), run("--config " + h)}) {
    for (const char ch : o.err) EXPECT_TRUE(ch == '\n' || (ch >= 0x20 && ch < 0x7f)) << o.err;
  }
}

}  // namespace
