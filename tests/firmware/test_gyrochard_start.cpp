// gyrochard's start-up as an operator meets it: invalid configuration names the key and exits 2
// with nothing started; a missing CAN interface or GPIO chip exits 3 and names it. Oracle: the exit codes in --help.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <string>

namespace {

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

void expect(const std::string& args, int code, const std::string& key) {
  const Outcome r = run(args);
  EXPECT_EQ(r.code, code) << args << ": " << r.err;
  EXPECT_EQ(r.err.rfind("gyrochard: " + key + ":", 0), 0u) << r.err;
}

TEST(GyrochardStart, InvalidConfigurationNamesTheKey) {
  expect("--source can-counter --tau0 -1", 2, "tau0");
  expect("--source can-counter --stride-factor 6", 2, "stride-factor");
  expect("--source can-counter --octaves 41", 2, "octaves");
  expect("--source can-counter --node 254", 2, "node");
  expect("--source can-counter --report-period 0.0001 --tau0 0.01", 2, "report-period");
  expect("--source strobe", 2, "counter-path");
  expect("--source can-counter --bogus 1", 2, "command line");
  const std::string conf = ::testing::TempDir() + std::to_string(getpid()) + "_bad.conf";
  std::ofstream(conf) << "source = can-counter\ntau0 = 0\n";
  expect("--config " + conf, 2, "tau0");
}

TEST(GyrochardStart, MissingHardwareIsNamed) {
  expect("--source can-counter --can-interface nosuchcan9", 3, "can-interface");
  expect("--source quadrature --gpio-chip nosuchchip9", 3, "source");
  expect("--source strobe --gpio-chip nosuchchip9 --counter-path /nonexistent", 3, "source");
  EXPECT_EQ(run("--help").code, 0);
}

}  // namespace
