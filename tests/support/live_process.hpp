#pragma once
// A program of the project run in the background by a test of the live page (gyrochar-demo or
// gyrochar-decode with --http): its stderr goes to a file the test reads while it runs, and it is
// stopped with SIGTERM (the programs end cleanly on it). Every wait is bounded.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <fstream>
#include <iterator>
#include <string>
#include <thread>

namespace gyrochar::test {

class Background {
 public:
  /// Runs `command` (a shell command line) with stderr to `err_path`, stdout to /dev/null.
  Background(const std::string& command, std::string err_path) : err_path_(std::move(err_path)) {
    const std::string line = "exec " + command + " >/dev/null 2>" + err_path_;
    pid_ = ::fork();
    if (pid_ == 0) {
      ::execl("/bin/sh", "sh", "-c", line.c_str(), static_cast<char*>(nullptr));
      ::_exit(127);
    }
  }
  ~Background() {
    if (pid_ > 0 && !exited_) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
  }
  std::string err() const {
    std::ifstream in(err_path_);
    return {std::istreambuf_iterator<char>(in), {}};
  }
  /// Waits until stderr holds `text` (true) or `limit_s` passes or the program ends (false).
  bool wait_for(const std::string& text, double limit_s) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(limit_s);
    while (std::chrono::steady_clock::now() < end) {
      if (err().find(text) != std::string::npos) return true;
      if (!exited_ && ::waitpid(pid_, &status_, WNOHANG) == pid_) exited_ = true;
      if (exited_) return err().find(text) != std::string::npos;
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    return false;
  }
  /// The port of the live page it announced ("...: live page: http://127.0.0.1:PORT/"), 0 if none.
  std::uint16_t port(double limit_s = 30.0) {
    if (!wait_for("live page: http://127.0.0.1:", limit_s)) return 0;
    const std::string e = err();
    const auto at = e.find("live page: http://127.0.0.1:") + std::string("live page: http://127.0.0.1:").size();
    return static_cast<std::uint16_t>(std::stoi(e.substr(at)));
  }
  /// SIGTERM, then its exit code (-1: it did not exit normally within `limit_s`).
  int stop(double limit_s = 30.0) {
    if (!exited_) ::kill(pid_, SIGTERM);
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(limit_s);
    while (!exited_ && std::chrono::steady_clock::now() < end) {
      if (::waitpid(pid_, &status_, WNOHANG) == pid_) exited_ = true;
      else std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    if (!exited_) return -1;
    return WIFEXITED(status_) ? WEXITSTATUS(status_) : -1;
  }

 private:
  std::string err_path_;
  pid_t pid_ = -1;
  int status_ = 0;
  bool exited_ = false;
};

}  // namespace gyrochar::test
