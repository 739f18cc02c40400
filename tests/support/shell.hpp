#pragma once
// Running the programs from a test as a user would, through the shell: the command's stdout, its
// stderr (through a file) and its exit code; per-process temporary names (CTest runs the tests
// of one file in parallel processes) and whole files read back.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <iterator>
#include <string>

namespace gyrochar::test_support {

struct ShellOutcome {
  int code = -1;  // exit code; -1 when the command did not exit normally
  std::string out, err;
};

/// A name in the test's temporary folder, unique to this process.
inline std::string temp_path(const std::string& name) {
  return ::testing::TempDir() + std::to_string(getpid()) + "_" + name;
}

/// Runs `command` with sh; stderr goes through temp_path(err_name).
inline ShellOutcome run_shell(const std::string& command, const std::string& err_name = "shell_err.txt") {
  const std::string err_file = temp_path(err_name);
  ShellOutcome r;
  FILE* p = popen(("(" + command + ") 2>" + err_file).c_str(), "r");
  char buf[65536];
  while (const std::size_t n = fread(buf, 1, sizeof buf, p)) r.out.append(buf, n);
  const int status = pclose(p);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream e(err_file);
  r.err.assign(std::istreambuf_iterator<char>(e), {});
  return r;
}

/// The bytes of a file ("" when it cannot be read).
inline std::string slurp(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(f), {}};
}

}  // namespace gyrochar::test_support
