// The contract every program keeps (hal/program/exit_codes.hpp): bad input gets one line
// "program: what: why" on stderr and exit_code::bad_input; an output that cannot be written,
// standard output included (`> /dev/full`), exit_code::output_failed; a CAN interface that does
// not exist exit_code::no_hardware, named by its name; every --help and the README state the same
// exit codes. gyrochar-analyze and gyrochar-decode have their own suites for their many options
// (test_analyze_cli, test_decode_cli); gyrochard's start-up is in tests/firmware.
// Oracle: the exit codes of hal/program/exit_codes.hpp.
#include <gtest/gtest.h>
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fstream>
#include <string>

#include "hal/program/exit_codes.hpp"
#include "support/shell.hpp"

namespace {

using namespace gyrochar;

const std::string bin = GYROCHAR_BINARY_DIR "/host_tools/";

struct Outcome {
  int code = -1;
  std::string out, err;
};

std::string temp(const std::string& name) { return gyrochar::test_support::temp_path(name); }

std::string slurp(const std::string& path) {
  std::ifstream in(path);
  return {std::istreambuf_iterator<char>(in), {}};
}

// `command` with stdout to a file unless it redirects stdout itself.
Outcome run(const std::string& command) {
  const std::string out_file = temp("tool_out.txt"), err_file = temp("tool_err.txt");
  const bool own_stdout = command.find(" > ") != std::string::npos;
  const int status = std::system((command + (own_stdout ? "" : " >" + out_file) + " 2>" + err_file).c_str());
  Outcome r;
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = own_stdout ? "" : slurp(out_file);
  r.err = slurp(err_file);
  return r;
}

// The program exits `code` and its first line on stderr is "program: what...".
void expect(const std::string& program, const std::string& args, int code, const std::string& what) {
  const Outcome r = run(bin + program + " " + args);
  EXPECT_EQ(r.code, code) << program << " " << args << ": " << r.err;
  EXPECT_EQ(r.err.rfind(program + ": " + what, 0), 0u) << program << " " << args << ": " << r.err;
}

TEST(ToolErrors, SimulatorNamesWhatIsWrong) {
  const int bad = exit_code::bad_input;
  expect("gyrochar-sim", "--bogus", bad, "options:");
  expect("gyrochar-sim", "--duration", bad, "options:");
  expect("gyrochar-sim", "--tau0 0", bad, "--tau0:");
  expect("gyrochar-sim", "--tau0 nan", bad, "--tau0:");
  expect("gyrochar-sim", "--duration -5", bad, "--duration:");
  expect("gyrochar-sim", "--duration 1e300", bad, "--duration:");
  expect("gyrochar-sim", "--rate nan --duration 1", bad, "--rate:");
  expect("gyrochar-sim", "--arw -1 --duration 1", bad, "noise parameters:");
  expect("gyrochar-sim", "--arw inf --duration 1", bad, "noise parameters:");
  expect("gyrochar-sim", "--bias-instability 0.05 --bias-time 0.001 --duration 1", bad, "--bias-time:");
  expect("gyrochar-sim", "--duration 1 --speed 2", bad, "--can-node, --speed:");
  expect("gyrochar-sim", "--duration 1 --markov 0.1", bad, "--markov: '0.1' is not SIGMA,TC");
  expect("gyrochar-sim", "--duration 1 --markov 0.1,0", bad, "--markov: TC must be positive");
  expect("gyrochar-sim", "--duration 1 --markov 1,1 --markov 1,1 --markov 1,1 --markov 1,1 --markov 1,1", bad,
         "--markov: at most 4");
  expect("gyrochar-sim", "--duration 1 --sinusoid 1,50", bad,
         "--sinusoid: FREQ must be above 0 and below the Nyquist frequency 1/(2 tau0) = 50 Hz");
  expect("gyrochar-sim", "--duration 1 --tau0 0.1 --sinusoid 1,5", bad,
         "--sinusoid: FREQ must be above 0 and below "
         "the Nyquist frequency 1/(2 tau0) = 5 Hz");
  expect("gyrochar-sim", "--duration 1 --seed -1", bad, "options: --seed: must be an integer 0..2^64-1");
  expect("gyrochar-sim", "--duration 1 --seed 18446744073709551616", bad, "options: --seed: must be an integer 0..2^64-1");
  expect("gyrochar-sim", "--duration 1 --out /nonexistent-dir/counts.txt", exit_code::output_failed,
         "/nonexistent-dir/counts.txt: No such file or directory");
  expect("gyrochar-sim", "--duration 10 > /dev/full", exit_code::output_failed,
         "standard output: write failed: No space left on device");
  expect("gyrochar-sim", "--duration 1 --can nosuchcan9", exit_code::no_hardware, "nosuchcan9: ");
  EXPECT_EQ(run(bin + "gyrochar-sim --duration 1 --seed 18446744073709551615").code, exit_code::ok);
}

// A name Linux can never give an interface (17 characters > IFNAMSIZ - 1 = 15, '/', a space,
// "..") is bad input; a possible name no interface has is missing hardware.
TEST(ToolErrors, AnImpossibleInterfaceNameIsBadInputAMissingOneIsHardware) {
  const int bad = exit_code::bad_input;
  expect("gyrochar-sim", "--duration 1 --can abcdefghijklmnopq", bad,
         "--can: 'abcdefghijklmnopq': an interface name has at most 15 characters, this one 17");
  expect("gyrochar-sim", "--duration 1 --can can/0", bad, "--can: 'can/0': an interface name cannot hold '/'");
  expect("gyrochar-sim", "--duration 1 --can ..", bad, "--can: '..': '.' and '..' are not interface names");
  expect("gyrochar-decode", "--interface abcdefghijklmnopq", bad,
         "--interface: 'abcdefghijklmnopq': an interface name has at most 15 characters, this one 17");
  expect("gyrochar-decode", "--interface 'can 0'", bad, "--interface: 'can 0': an interface name cannot hold");
  expect("gyrochar-sim", "--duration 1 --can abcdefghijklmno", exit_code::no_hardware, "abcdefghijklmno: ");
  expect("gyrochar-decode", "--interface abcdefghijklmno", exit_code::no_hardware, "abcdefghijklmno: ");
}

// The reproducers, refused before any count is written, naming the term and the limit.
// Oracle: the angle each term adds (sim_truth.hpp, worst_case_pulses) against 2^53 pulses.
TEST(ToolErrors, SimulatorRefusesParametersBeyondItsCountRange) {
  const int bad = exit_code::bad_input;
  for (const std::string& args :
       {std::string("--duration 5 --tau0 1 --arw 1e20"), std::string("--rate 1e9 --pulse-weight 1e-9")}) {
    const Outcome r = run(bin + "gyrochar-sim " + args);
    EXPECT_EQ(r.code, bad) << args << ": " << r.err;
    const std::string option = args.find("--arw") != std::string::npos ? "--arw" : "--rate";
    EXPECT_EQ(r.err.rfind("gyrochar-sim: " + option + ": the counted angle could reach ", 0), 0u) << r.err;
    EXPECT_NE(r.err.find("limit of 2^53"), std::string::npos) << r.err;
    EXPECT_EQ(r.out, "") << args << ": nothing written";
  }
}

TEST(ToolErrors, DemoGivesEachOptionRuleItsOwnMessage) {
  const int bad = exit_code::bad_input;
  expect("gyrochar-demo", "--bogus", bad, "options:");
  expect("gyrochar-demo", "--nodes 9", bad, "--nodes: must be 1..8, not 9");
  expect("gyrochar-demo", "--hours nan", bad, "--hours: must be a positive number of hours, not nan");
  expect("gyrochar-demo", "--tau0 0", bad, "--tau0: must be a positive number of seconds");
  expect("gyrochar-demo", "--octaves 41", bad, "--octaves: must be 1..40, not 41");
  expect("gyrochar-demo", "--loss 1", bad, "--loss: must be a probability in [0, 1), not 1");
  expect("gyrochar-demo", "--view-every -1", bad, "--view-every: must be a number of minutes >= 0");
  expect("gyrochar-demo", "--hours 0.001 --csv /nonexistent-dir/x.csv", exit_code::output_failed,
         "/nonexistent-dir/x.csv: No such file or directory");
  expect("gyrochar-demo", "--hours 0.001 --plot '' --candump /nonexistent-dir/x.log", exit_code::output_failed,
         "/nonexistent-dir/x.log: No such file or directory");
  // An empty --csv, like an empty --plot, means none.
  const Outcome none = run(bin + "gyrochar-demo --hours 0.001 --plot '' --csv ''");
  EXPECT_EQ(none.code, exit_code::ok) << none.err;
  EXPECT_EQ(none.err.find(": cannot write"), std::string::npos) << none.err;
}

TEST(ToolErrors, EveryToolChecksItsStandardOutput) {
  const std::string log = temp("demo.log");
  ASSERT_EQ(run(bin + "gyrochar-demo --hours 0.01 --plot '' --csv '' --candump " + log).code, exit_code::ok);
  const std::string counts = temp("counts.txt");
  ASSERT_EQ(run(bin + "gyrochar-sim --duration 100 --out " + counts).code, exit_code::ok);
  const std::string lost = "standard output: write failed: ";
  expect("gyrochar-analyze", "--type counts --tau0 0.01 --pulse-weight 1arcsec " + counts + " > /dev/full",
         exit_code::output_failed, lost);
  for (const char* program : {"gyrochar-analyze", "gyrochar-decode", "gyrochar-sim", "gyrochar-demo"})
    expect(program, "--help > /dev/full", exit_code::output_failed, lost);
  // The decoder's and the demo's summaries come first on stderr; the last line says what was lost.
  for (const std::string& command :
       {"gyrochar-decode " + log + " --view final", std::string("gyrochar-demo --hours 0.01 --plot '' --csv ''")}) {
    const Outcome r = run(bin + command + " > /dev/full");
    EXPECT_EQ(r.code, exit_code::output_failed) << command << ": " << r.err;
    const std::string program = command.substr(0, command.find(' '));
    EXPECT_NE(r.err.find(program + ": " + lost), std::string::npos) << r.err;
  }
}

// The decoder's Kalibr file describes one node with an accepted fit; anything else is refused.
TEST(ToolErrors, DecoderKalibrNeedsOneNodeWithAFit) {
  const std::string log = temp("kalibr_demo.log"), yaml = temp("imu.yaml");
  ASSERT_EQ(run(bin + "gyrochar-demo --hours 0.01 --plot '' --csv '' --candump " + log).code, exit_code::ok);
  const Outcome two = run(bin + "gyrochar-decode " + log + " --view none --kalibr " + yaml);
  EXPECT_EQ(two.code, exit_code::bad_input) << two.err;
  EXPECT_NE(two.err.find("gyrochar-decode: --kalibr: nodes 0x10, 0x11 seen: choose one with --node\n"), std::string::npos)
      << two.err;
  // 36 s of gyro time: too short for a fit of N and K.
  const Outcome young = run(bin + "gyrochar-decode " + log + " --view none --node 0x10 --kalibr " + yaml);
  EXPECT_EQ(young.code, exit_code::bad_input) << young.err;
  EXPECT_NE(young.err.find("gyrochar-decode: --kalibr: "), std::string::npos) << young.err;
}

// An output that is the same file as an input (or as another output) is refused before anything
// is opened for writing: the input keeps every byte, and no output is created.
// Oracle: the contract of host_tools/common/output_paths.hpp; exit codes of hal/program/exit_codes.hpp.
TEST(ToolErrors, NoOutputOverwritesAnInputOrAnotherOutput) {
  const int bad = exit_code::bad_input;
  const std::string log = temp("same_file.log"), counts = temp("same_file_counts.txt");
  ASSERT_EQ(run(bin + "gyrochar-demo --hours 0.01 --plot '' --csv '' --candump " + log).code, exit_code::ok);
  ASSERT_EQ(run(bin + "gyrochar-sim --duration 100 --out " + counts).code, exit_code::ok);
  const std::string log_bytes = slurp(log), count_bytes = slurp(counts);
  ASSERT_FALSE(log_bytes.empty());
  ASSERT_FALSE(count_bytes.empty());
  // The same file through a symbolic link, a hard link and another spelling of its path.
  const std::string symbolic = temp("same_file_symlink.log"), hard = temp("same_file_hard.svg");
  std::remove(symbolic.c_str());
  std::remove(hard.c_str());
  ASSERT_EQ(symlink(log.c_str(), symbolic.c_str()), 0);
  ASSERT_EQ(link(log.c_str(), hard.c_str()), 0);
  const std::string respelled = ::testing::TempDir() + "./" + log.substr(::testing::TempDir().size());
  const std::string prefix = hard.substr(0, hard.size() - 4);  // --plot PREFIX writes PREFIX.svg = the log
  const std::string fresh = temp("same_file_fresh.csv");
  std::remove(fresh.c_str());
  const struct {
    std::string program, args, what;
  } cases[] = {
      {"gyrochar-decode", log + " --view none --csv " + log, "--csv: '" + log + "' is the same file as the input LOG"},
      {"gyrochar-decode", log + " --view none --jsonl " + symbolic,
       "--jsonl: '" + symbolic + "' is the same file as the input LOG"},
      {"gyrochar-decode", log + " --view none --node 0x10 --kalibr " + respelled, "--kalibr: "},
      {"gyrochar-decode", log + " --view none --plot " + prefix, "--plot: '" + hard + "' is the same file as the input LOG"},
      {"gyrochar-decode", "- --view none --csv " + hard + " < " + log,
       "--csv: '" + hard + "' is the same file as the input LOG (standard input)"},
      {"gyrochar-decode", log + " --view none --csv " + fresh + " --jsonl " + fresh,
       "--jsonl: '" + fresh + "' is the same file as the output --csv"},
      {"gyrochar-analyze",
       "--type counts --tau0 0.01 --pulse-weight 1arcsec --fit ieee952 --kalibr " + counts + " " + counts,
       "--kalibr: '" + counts + "' is the same file as the input file"},
      {"gyrochar-demo", "--hours 0.001 --plot '' --csv " + fresh + " --candump " + fresh,
       "--candump: '" + fresh + "' is the same file as the output --csv"},
      {"gyrochar-demo", "--hours 0.001 --csv " + prefix + ".png --plot " + prefix,
       "--plot: '" + prefix +
           ".png' is the same "
           "file as the output --csv"},
  };
  for (const auto& c : cases) {
    const Outcome r = run(bin + c.program + " " + c.args);
    EXPECT_EQ(r.code, bad) << c.program << " " << c.args << ": " << r.err;
    EXPECT_EQ(r.err.rfind(c.program + ": " + c.what, 0), 0u) << c.program << " " << c.args << ": " << r.err;
    EXPECT_NE(r.err.find("refused before writing anything"), std::string::npos) << r.err;
    EXPECT_EQ(slurp(log), log_bytes) << c.program << " " << c.args << " changed the log";
    EXPECT_EQ(slurp(counts), count_bytes) << c.program << " " << c.args << " changed the counts";
    EXPECT_NE(access(fresh.c_str(), F_OK), 0) << c.program << " " << c.args << " created " << fresh;
    EXPECT_NE(access((prefix + ".png").c_str(), F_OK), 0) << c.program << " " << c.args << " created a plot";
  }
  // Devices are not files to protect: two outputs to /dev/null are fine.
  const Outcome null = run(bin + "gyrochar-decode " + log + " --view none --csv /dev/null --jsonl /dev/null");
  EXPECT_EQ(null.code, exit_code::ok) << null.err;
  for (const std::string& f : {symbolic, hard, log, counts}) std::remove(f.c_str());
}

TEST(ToolErrors, EveryHelpAndTheReadmeStateTheSameExitCodes) {
  for (const std::string program : {"gyrochar-analyze", "gyrochar-decode", "gyrochar-sim", "gyrochar-demo"}) {
    const Outcome r = run(bin + program + " --help");
    EXPECT_EQ(r.code, exit_code::ok) << program;
    EXPECT_NE(r.out.find(exit_code::help), std::string::npos) << program << ":\n" << r.out;
  }
  const Outcome board = run(GYROCHAR_BINARY_DIR "/firmware/gyrochard --help");
  EXPECT_EQ(board.code, exit_code::ok);
  EXPECT_NE(board.out.find(exit_code::help), std::string::npos) << board.out;
  EXPECT_NE(slurp(GYROCHAR_SOURCE_DIR "/README.md").find(exit_code::help), std::string::npos)
      << "README.md must quote hal/program/exit_codes.hpp's help text verbatim";
}

// Runs `command` as an unprivileged user when this test runs as root (root reads and writes
// anything), so that permissions are really checked.
std::string unprivileged(const std::string& command) {
  return getuid() == 0 ? "setpriv --reuid=65534 --regid=65534 --clear-groups " + command : command;
}

TEST(ToolErrors, PermissionDeniedIsNamedWithItsReason) {
  const std::string dir = temp("perm");
  std::system(("rm -rf " + dir + " && mkdir -p " + dir + "/locked && chmod 755 " + dir).c_str());
  std::ofstream(dir + "/secret.txt") << "5\n6\n7\n";
  std::system(("chmod 000 " + dir + "/secret.txt && chmod 555 " + dir + "/locked").c_str());
  const struct {
    std::string program, args;
    int code;
  } cases[] = {
      {"gyrochar-analyze", "--type counts --tau0 1 --pulse-weight 1arcsec " + dir + "/secret.txt", exit_code::bad_input},
      {"gyrochar-decode", dir + "/secret.txt", exit_code::bad_input},
      {"gyrochar-sim", "--duration 1 --out " + dir + "/locked/counts.txt", exit_code::output_failed},
  };
  for (const auto& c : cases) {
    const Outcome r = run(unprivileged(bin + c.program + " " + c.args));
    EXPECT_EQ(r.code, c.code) << c.program << ": " << r.err;
    EXPECT_EQ(r.err.rfind(c.program + ": " + dir, 0), 0u) << r.err;
    EXPECT_NE(r.err.find("Permission denied"), std::string::npos) << r.err;
  }
  std::system(("chmod -R 755 " + dir + " && rm -rf " + dir).c_str());
}

// The live page's address: a value that is no address is bad usage (2), naming the rule; an
// address that cannot be listened on is an output that cannot be opened (4), refused before any
// input is read. The port in use is held by this test's own socket.
TEST(ToolErrors, LivePageAddressIsCheckedFirst) {
  const int bad = exit_code::bad_input;
  expect("gyrochar-decode", "--interface vcan0 --http http", bad, "--http: port 'http' is not a number 0..65535");
  expect("gyrochar-decode", "x.log --http 70000", bad, "--http: port '70000' is not a number 0..65535");
  expect("gyrochar-decode", "x.log --http ::1:80", bad,
         "--http: '::1:80': an IPv6 address goes in brackets, e.g. [::1]:8080");
  expect("gyrochar-decode", "x.log --http gyro.example:80", bad,
         "--http: 'gyro.example' is not a numeric IPv4 or IPv6 address or localhost");
  expect("gyrochar-demo", "--http :80", bad, "--http: ':80': no address before ':'");
  expect("gyrochar-demo", "--speed -1", bad, "--speed: must be a number >= 0, not -1");
  expect("gyrochar-demo", "--refresh 0", bad, "--refresh: must be a number of seconds > 0, not 0");
  const int held = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(::bind(held, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
  ASSERT_EQ(::listen(held, 1), 0);
  socklen_t length = sizeof a;
  ::getsockname(held, reinterpret_cast<sockaddr*>(&a), &length);
  const std::string port = std::to_string(ntohs(a.sin_port));
  const std::string log = temp("http_demo.log");
  ASSERT_EQ(run(bin + "gyrochar-demo --hours 0.01 --plot '' --csv '' --candump " + log).code, exit_code::ok);
  expect("gyrochar-decode", log + " --http " + port, exit_code::output_failed,
         "--http: 127.0.0.1:" + port + ": Address already in use");
  expect("gyrochar-demo", "--hours 0.01 --plot '' --csv '' --http 127.0.0.1:" + port, exit_code::output_failed,
         "--http: 127.0.0.1:" + port + ": Address already in use");
  // Refused before any output is opened: a CSV from before is kept whole.
  const std::string kept = temp("http_kept.csv");
  std::ofstream(kept) << "an earlier run\n";
  expect("gyrochar-decode", log + " --csv " + kept + " --http " + port, exit_code::output_failed, "--http: ");
  expect("gyrochar-demo", "--hours 0.01 --plot '' --csv " + kept + " --http " + port, exit_code::output_failed, "--http: ");
  EXPECT_EQ(slurp(kept), "an earlier run\n");
  expect("gyrochar-decode", log + " --http 192.0.2.1:0", exit_code::output_failed,
         "--http: 192.0.2.1:0: Cannot assign requested address");
  ::close(held);
}

}  // namespace

// Acceptance limits, the production summary and the report: each rule names its option, before
// anything is read or written (the limits file format itself: test_limits.cpp, test_acceptance_cli.cpp).
TEST(ToolErrors, LimitsSummaryAndReportNameTheirRule) {
  const int bad = exit_code::bad_input;
  const std::string counts = " --type counts --tau0 1 --pulse-weight 1arcsec ";
  expect("gyrochar-analyze", counts + "--limits /nonexistent-dir/limits.txt /dev/null", bad,
         "--limits: /nonexistent-dir/limits.txt: cannot be read");
  expect("gyrochar-analyze", counts + "--summary /tmp/s.csv /dev/null", bad, "--summary: needs --limits");
  expect("gyrochar-analyze", counts + "--dynamic 100 --report /tmp/r.html /dev/null", bad,
         "--report: is about the whole run: not with --dynamic");
  expect("gyrochar-decode", "/dev/null --summary /tmp/s.csv", bad, "--summary: needs --limits");
  expect("gyrochar-decode", "/dev/null --plot-every 5", bad, "--plot-every: needs --plot PREFIX or --report FILE.html");
  expect("gyrochar-decode", "/dev/null --limits /nonexistent-dir/limits.txt", bad,
         "--limits: /nonexistent-dir/limits.txt: cannot be read");
  expect("gyrochar-demo", "--csv '' --limits /dev/null", bad,
         "--limits: the demo shows verdicts on its live page (--http) and in its CSV (--csv): give one of them");
  expect("gyrochar-demo", "--limits /dev/null", bad, "--limits: /dev/null: no limit in the file");
  expect("gyrochar-demo", "--http 127.0.0.1:0 --limits /nonexistent-dir/limits.txt", bad,
         "--limits: /nonexistent-dir/limits.txt: cannot be read");
}
