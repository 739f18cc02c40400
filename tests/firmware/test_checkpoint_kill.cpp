// A characterization run killed with SIGKILL at random instants and restarted, many times, must end
// with exactly the sums of the data it kept: each run resumes from the last checkpoint (written to
// a temporary file, fsynced, renamed), the data between that checkpoint and the kill is lost, the
// downtime is skipped, and no term spans a restart. Oracle: the estimator definitions evaluated by
// brute force (tests/oracle) over the segments the runs logged, on the pyramid's global stride grid.
#include <gtest/gtest.h>
#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <random>
#include <thread>
#include <vector>

#include "board.hpp"
#include "hal/fake/fake_can_bus.hpp"
#include "hal/fake/fake_clock.hpp"
#include "hal/fake/fake_count_source.hpp"
#include "oracle/brute_force.hpp"

namespace gyrochar::firmware {
namespace {

constexpr std::uint64_t ms = 1000000;
constexpr std::uint64_t total_samples = 20000;
constexpr std::uint64_t downtime_samples = 7;  // samples a restart misses

// The gyro's count for sample index i of the uninterrupted run (deterministic).
std::int64_t count_at(std::uint64_t i) {
  std::uint64_t z = i * 0x9E3779B97F4A7C15ull;
  z = (z ^ (z >> 31)) * 0xBF58476D1CE4E5B9ull;
  return 100 + static_cast<std::int64_t>((z >> 40) % 61) - 30 + static_cast<std::int64_t>(i % 7);
}

Config kill_config(const std::string& dir) {
  Config c;
  c.source = SourceKind::quadrature;  // stands for any count source; the fake replaces it
  c.tau0_s = 0.001;
  c.stride_factor = 8;
  c.octaves = 12;
  c.report_period_s = 0.1;
  c.checkpoint_path = dir + "/run.ckpt";
  c.checkpoint_period_s = 0.05;
  return c;
}

// One run, in a child process: resume, log where this segment starts, run until the data ends.
[[noreturn]] void run_child(const std::string& dir) {
  const Config c = kill_config(dir);
  hal::FakeCanBus bus;
  auto node = bus.attach();
  hal::FakeClock clock;
  hal::FakeTimer timer(clock);
  hal::FakeCountSource source;
  Board board(c, BoardIo{*node, &source, clock, timer});
  board.resume();
  std::uint64_t restarts = 0;
  {
    std::ifstream log(dir + "/segments");
    std::uint64_t j = 0, s = 0;
    while (log >> j >> s) ++restarts;
  }
  const std::uint64_t kept = board.characterizer().increments();
  const std::uint64_t first = kept + restarts * downtime_samples;  // index of this segment's first sample
  const std::string line = std::to_string(first) + " " + std::to_string(kept) + "\n";
  const int fd = open((dir + "/segments").c_str(), O_WRONLY | O_APPEND | O_CREAT, 0644);
  if (write(fd, line.data(), line.size()) != static_cast<ssize_t>(line.size()) || fsync(fd) != 0) _exit(3);
  close(fd);
  std::vector<std::int64_t> counts(total_samples - kept);
  for (std::size_t k = 0; k < counts.size(); ++k) counts[k] = count_at(first + k);
  source.script_counts(clock.now_ns(), ms, counts.data(), counts.size());
  for (std::size_t k = 0; k < counts.size(); ++k) {
    clock.advance(ms);
    timer.update();
    board.run_once(0);
  }
  _exit(board.checkpoint() == 0 && board.characterizer().increments() == total_samples ? 0 : 4);
}

TEST(CheckpointKill, RandomSigkillsLoseOnlyTheUncheckpointedData) {
  const std::string dir = ::testing::TempDir() + "gyrochar_kill_" + std::to_string(getpid());
  std::system(("rm -rf " + dir + " && mkdir -p " + dir).c_str());
  std::mt19937_64 rng(2026);
  int kills = 0, runs = 0;
  for (bool done = false; !done && runs < 400; ++runs) {
    const pid_t child = fork();
    ASSERT_GE(child, 0);
    if (child == 0) run_child(dir);
    if (kills < 60) {
      std::this_thread::sleep_for(std::chrono::microseconds(1000 + rng() % 40000));
      if (kill(child, SIGKILL) == 0) ++kills;
    }
    int status = 0;
    waitpid(child, &status, 0);
    done = WIFEXITED(status) && WEXITSTATUS(status) == 0;
    if (WIFEXITED(status)) {
      ASSERT_EQ(WEXITSTATUS(status), 0) << "run " << runs;
    }
  }
  ASSERT_GE(kills, 40) << "most runs must have been killed for the test to mean anything";

  // The segments the runs kept: each starts at its logged index; its length is what the next run
  // found in the checkpoint minus what this one found.
  std::vector<std::pair<std::uint64_t, std::uint64_t>> log;  // (first index, samples kept before)
  std::ifstream in(dir + "/segments");
  for (std::uint64_t j = 0, s = 0; in >> j >> s;) log.emplace_back(j, s);
  ASSERT_GE(log.size(), 2u);
  std::vector<std::vector<std::int64_t>> segments;  // phase points of each segment
  for (std::size_t k = 0; k < log.size(); ++k) {
    const std::uint64_t end = k + 1 < log.size() ? log[k + 1].second : total_samples;
    if (end == log[k].second) continue;  // killed before its first checkpoint: nothing kept
    std::vector<std::int64_t> x{0};
    for (std::uint64_t i = 0; i < end - log[k].second; ++i) x.push_back(x.back() + count_at(log[k].first + i));
    segments.push_back(x);
  }

  // The final state, as a new run would resume it.
  hal::FakeCanBus bus;
  auto node = bus.attach();
  hal::FakeClock clock;
  hal::FakeTimer timer(clock);
  Board final_board(kill_config(dir), BoardIo{*node, nullptr, clock, timer});
  const std::string said = final_board.resume();
  ASSERT_NE(said.find("resumed"), std::string::npos) << said;
  const auto& pyramid = final_board.characterizer();
  std::uint64_t points = 0;
  for (const auto& x : segments) points += x.size();
  EXPECT_EQ(pyramid.phase_points(), points);
  for (std::size_t i = 0; i < pyramid.tau_count(); ++i) {
    oracle::Exact want;
    std::uint64_t offset = 0;
    for (const auto& x : segments) {
      want += oracle::brute_force(x, pyramid.result(i).m, pyramid.result(i).stride, false, offset);
      offset += x.size();
    }
    const auto got = pyramid.result(i);
    for (std::size_t s = 0; s < 3; ++s) {
      EXPECT_EQ(got.n[s], want.n[s]) << "m=" << got.m << " stat=" << s;
      EXPECT_TRUE(((oracle::u128{got.sum[s].hi} << 64) | got.sum[s].lo) == want.sum[s]) << "m=" << got.m << " stat=" << s;
    }
  }
  std::printf("%d runs, %d killed, %zu segments kept\n", runs, kills, segments.size());
  if (!getenv("KEEP")) std::system(("rm -rf " + dir).c_str());
}

}  // namespace
}  // namespace gyrochar::firmware
