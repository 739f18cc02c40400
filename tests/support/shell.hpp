#pragma once
// Running the programs from a test as a user would, through the shell: the command's stdout, its
// stderr (through a file) and its exit code; per-process temporary names (CTest runs the tests
// of one file in parallel processes), in a folder that goes when the process ends; whole files
// read back.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

namespace gyrochar::test_support {

struct ShellOutcome {
  int code = -1;  // exit code; -1 when the command did not exit normally
  std::string out, err;
};

/// This process's temporary folder, gyrochar_PID in the test's temporary folder: made at its first
/// use, removed with all it holds when the process ends (kept when GYROCHAR_KEEP_TEMP is set, to
/// look at a failure). A forked child that ends does not remove its parent's.
inline const std::string& temp_folder() {
  struct Folder {
    pid_t owner = getpid();
    std::string path = ::testing::TempDir() + "gyrochar_" + std::to_string(owner);
    Folder() { std::filesystem::create_directories(path); }
    Folder(const Folder&) = delete;
    Folder& operator=(const Folder&) = delete;
    ~Folder() {
      if (getpid() != owner || std::getenv("GYROCHAR_KEEP_TEMP") != nullptr) return;
      std::error_code ignored;
      std::filesystem::remove_all(path, ignored);
    }
  };
  static const Folder folder;
  return folder.path;
}

/// A name in this process's temporary folder.
inline std::string temp_path(const std::string& name) { return temp_folder() + "/" + name; }

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
