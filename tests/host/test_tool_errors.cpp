// Every host program answers bad input with "program: what: why" on stderr and a distinct exit
// code (its --help lists them): unknown options, out-of-range, NaN and huge values, a path that
// cannot be written, an empty or garbage input. gyrochar-analyze and gyrochar-decode have their own
// suites (test_analyze_cli, test_decode_cli); gyrochard's start-up is in tests/firmware.
// Oracle: the exit codes each program's --help states.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fstream>
#include <string>

namespace {

const std::string bin = GYROCHAR_BINARY_DIR "/host_tools/";

struct Outcome {
  int code = -1;
  std::string err;
};

Outcome run(const std::string& command) {
  const std::string err_file = ::testing::TempDir() + std::to_string(getpid()) + "_tool_err.txt";
  const int status = std::system((command + " >/dev/null 2>" + err_file).c_str());
  std::ifstream e(err_file);
  Outcome r;
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.err.assign(std::istreambuf_iterator<char>(e), {});
  return r;
}

void expect(const std::string& program, const std::string& args, int code, const std::string& what) {
  const Outcome r = run(bin + program + " " + args);
  EXPECT_EQ(r.code, code) << program << " " << args << ": " << r.err;
  EXPECT_EQ(r.err.rfind(program + ": " + what, 0), 0u) << program << " " << args << ": " << r.err;
}

TEST(ToolErrors, SimulatorNamesWhatIsWrong) {
  expect("gyrochar-sim", "--bogus", 2, "options:");
  expect("gyrochar-sim", "--duration", 2, "options:");
  expect("gyrochar-sim", "--tau0 0", 2, "--tau0:");
  expect("gyrochar-sim", "--tau0 nan", 2, "--tau0:");
  expect("gyrochar-sim", "--duration -5", 2, "--duration:");
  expect("gyrochar-sim", "--duration 1e300", 2, "--duration:");
  expect("gyrochar-sim", "--rate nan --duration 1", 2, "--rate:");
  expect("gyrochar-sim", "--arw -1 --duration 1", 2, "noise parameters:");
  expect("gyrochar-sim", "--arw inf --duration 1", 2, "noise parameters:");
  expect("gyrochar-sim", "--bias-instability 0.05 --bias-time 0.001 --duration 1", 2, "--bias-time:");
  expect("gyrochar-sim", "--duration 1 --out /nonexistent-dir/counts.txt", 3, "/nonexistent-dir/counts.txt:");
  expect("gyrochar-sim", "--duration 1 --can nosuchcan9", 4, "--can:");
  expect("gyrochar-sim", "--duration 1 --speed 2", 2, "--can-node, --speed:");
  EXPECT_EQ(run(bin + "gyrochar-sim --help").code, 0);
}

TEST(ToolErrors, DemoNamesWhatIsWrong) {
  expect("gyrochar-demo", "--bogus", 2, "options:");
  expect("gyrochar-demo", "--nodes 9", 2, "options:");
  expect("gyrochar-demo", "--hours nan", 2, "options:");
  expect("gyrochar-demo", "--loss 1", 2, "options:");
  expect("gyrochar-demo", "--hours 0.001 --csv /nonexistent-dir/x.csv", 1, "/nonexistent-dir/x.csv:");
  expect("gyrochar-demo", "--hours 0.001 --plot '' --candump /nonexistent-dir/x.log", 1, "/nonexistent-dir/x.log:");
  EXPECT_EQ(run(bin + "gyrochar-demo --help").code, 0);
}

// Runs `command` as an unprivileged user when this test runs as root (root reads and writes
// anything), so that permissions are really checked.
std::string unprivileged(const std::string& command) {
  return getuid() == 0 ? "setpriv --reuid=65534 --regid=65534 --clear-groups " + command : command;
}

TEST(ToolErrors, PermissionDeniedIsNamedWithItsReason) {
  const std::string dir = ::testing::TempDir() + "gyrochar_perm_" + std::to_string(getpid());
  std::system(("rm -rf " + dir + " && mkdir -p " + dir + "/locked && chmod 755 " + dir).c_str());
  std::ofstream(dir + "/secret.txt") << "5\n6\n7\n";
  std::system(("chmod 000 " + dir + "/secret.txt && chmod 555 " + dir + "/locked").c_str());
  const struct {
    std::string program, args;
    int code;
  } cases[] = {
      {"gyrochar-analyze", "--type counts --tau0 1 --pulse-weight 1arcsec " + dir + "/secret.txt", 2},
      {"gyrochar-decode", dir + "/secret.txt", 2},
      {"gyrochar-sim", "--duration 1 --out " + dir + "/locked/counts.txt", 3},
  };
  for (const auto& c : cases) {
    const Outcome r = run(unprivileged(bin + c.program + " " + c.args));
    EXPECT_EQ(r.code, c.code) << c.program << ": " << r.err;
    EXPECT_EQ(r.err.rfind(c.program + ": " + dir, 0), 0u) << r.err;
    EXPECT_NE(r.err.find("Permission denied"), std::string::npos) << r.err;
  }
  std::system(("chmod -R 755 " + dir + " && rm -rf " + dir).c_str());
}

}  // namespace
