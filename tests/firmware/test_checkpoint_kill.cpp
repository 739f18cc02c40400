// A characterization run killed with SIGKILL at random instants and restarted, many times, must end
// with exactly the sums of the data it kept: each run resumes from the last checkpoint (written to
// a temporary file, fsynced, renamed), the data between that checkpoint and the kill is lost, the
// downtime is skipped, and no term spans a restart. Oracle: the estimator definitions evaluated by
// brute force (tests/oracle) over the segments the runs logged, on the pyramid's global stride grid.
// The same with power cuts: what was not made durable (by fsync of the file, or of the directory
// for a rename) is dropped at each kill (the simulated disk below).
#include <gtest/gtest.h>
#include <dirent.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "board.hpp"
#include "hal/fake/fake_can_bus.hpp"
#include "hal/fake/fake_clock.hpp"
#include "hal/fake/fake_count_source.hpp"
#include "oracle/brute_force.hpp"
#include "support/shell.hpp"

// --- the simulated disk: power loss drops what was not made durable ---------------------------
//
// A file system may keep written data and directory changes in memory until they are synced; a
// power cut loses them. The model here is the strict one (what CrashMonkey and dm-log-writes test
// against): a file's content survives as of its last fsync() (nothing of a never-synced file), a
// directory's names (creations, renames, removals) as of its last fsync(). CheckpointFile::write()
// is correct under it if it fsyncs the temporary file before the rename and the directory after.
//
// This test program defines fsync() itself (the firmware library linked into it calls this one;
// the real one is the system call). In a child that armed it, each fsync() of a checkpoint file or
// of its directory records what is now durable, and writes that durable image (names and contents
// of the run.ckpt* files) to DIR/disk.image, atomically (a SIGKILL cannot lose what was written to
// the page cache, so a real rename suffices for the image itself). After killing the child, the
// test replaces the run.ckpt* files by the image: the disk as the power cut left it.
namespace powerloss {

struct Disk {
  bool armed = false;
  bool drop_file_fsync = false;  // the negative control: a writer that never fsyncs its data
  int cut_before = 0;            // > 0: the power fails just before the checkpoint fsync of this number
  int fsyncs = 0;                // checkpoint fsyncs (of a run.ckpt* file or of the directory) so far
  std::string dir;
  std::map<ino_t, std::string> durable_content;  // per inode, as of its last fsync
  std::map<std::string, ino_t> durable_names;    // run.ckpt* names, as of the last directory fsync
};
Disk disk;

bool is_checkpoint_name(const std::string& name) { return name.rfind("run.ckpt", 0) == 0; }

std::string read_whole(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

std::string fd_path(int fd) {
  char link[64], target[4096];
  std::snprintf(link, sizeof link, "/proc/self/fd/%d", fd);
  const ssize_t n = readlink(link, target, sizeof target - 1);
  return n > 0 ? std::string(target, static_cast<std::size_t>(n)) : std::string();
}

// The run.ckpt* names of the directory now, with their inodes.
std::map<std::string, ino_t> current_names(const std::string& dir) {
  std::map<std::string, ino_t> names;
  if (DIR* d = opendir(dir.c_str())) {
    while (const dirent* e = readdir(d)) {
      struct stat st {};
      if (is_checkpoint_name(e->d_name) && ::stat((dir + "/" + e->d_name).c_str(), &st) == 0) names[e->d_name] = st.st_ino;
    }
    closedir(d);
  }
  return names;
}

// The durable image: each durable name with its inode's durable content (none: an empty file).
void write_image() {
  std::ostringstream image;
  for (const auto& [name, ino] : disk.durable_names) {
    const auto it = disk.durable_content.find(ino);
    const std::string content = it == disk.durable_content.end() ? std::string() : it->second;
    image << name << ' ' << content.size() << '\n' << content;
  }
  const std::string staging = disk.dir + "/disk.image.new";
  std::ofstream(staging, std::ios::binary) << image.str();
  ::syscall(SYS_renameat, AT_FDCWD, staging.c_str(), AT_FDCWD, (disk.dir + "/disk.image").c_str());
}

// In a child: the directory as it is now is durable (it is what the previous power cut left).
void arm(const std::string& dir, bool drop_file_fsync, int cut_before) {
  disk.armed = true;
  disk.drop_file_fsync = drop_file_fsync;
  disk.cut_before = cut_before;
  disk.dir = dir;
  disk.durable_names = current_names(dir);
  for (const auto& [name, ino] : disk.durable_names) disk.durable_content[ino] = read_whole(dir + "/" + name);
  write_image();
}

bool is_checkpoint_path(const std::string& path) {
  const auto slash = path.rfind('/');
  return path == disk.dir ||
         (slash != std::string::npos && path.substr(0, slash) == disk.dir && is_checkpoint_name(path.substr(slash + 1)));
}

// Before an fsync: a run told to cut at this one dies here, the data it would make durable not yet
// durable (a random SIGKILL lands in that window rarely: the cuts need not find it by chance).
void before_fsync(int fd) {
  if (disk.cut_before > 0 && is_checkpoint_path(fd_path(fd)) && ++disk.fsyncs == disk.cut_before) raise(SIGKILL);
}

void on_fsync(int fd) {
  const std::string path = fd_path(fd);
  if (path == disk.dir) {
    disk.durable_names = current_names(disk.dir);
  } else if (is_checkpoint_path(path) && !disk.drop_file_fsync) {
    struct stat st {};
    if (fstat(fd, &st) != 0) return;
    disk.durable_content[st.st_ino] = read_whole(path);
  } else {
    return;
  }
  write_image();
}

// After the kill: the run.ckpt* files become the durable image. Returns whether that changed them
// (the cut dropped something not yet durable).
bool cut_power(const std::string& dir) {
  std::map<std::string, std::string> before;
  for (const auto& [name, ino] : current_names(dir)) {
    before[name] = read_whole(dir + "/" + name);
    std::remove((dir + "/" + name).c_str());
  }
  std::ifstream image(dir + "/disk.image", std::ios::binary);
  std::string name;
  std::size_t size = 0;
  while (image >> name >> size) {
    image.get();  // the newline
    std::string content(size, '\0');
    image.read(content.data(), static_cast<std::streamsize>(size));
    std::ofstream(dir + "/" + name, std::ios::binary) << content;
  }
  std::map<std::string, std::string> after;
  for (const auto& [name, ino] : current_names(dir)) after[name] = read_whole(dir + "/" + name);
  return after != before;
}

}  // namespace powerloss

extern "C" int fsync(int fd) {
  if (powerloss::disk.armed) powerloss::before_fsync(fd);
  const long r = ::syscall(SYS_fsync, fd);
  if (r == 0 && powerloss::disk.armed) powerloss::on_fsync(fd);
  return static_cast<int>(r);
}

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

// How a run started: resumed, fresh (no checkpoint), or fresh with the checkpoint refused.
enum Start { resumed = 1, fresh = 0, refused = 2 };

// One run, in a child process: resume, log where this segment starts and how, run until the data
// ends. With power loss armed, the disk's durable image follows every fsync.
// `ready` (a pipe) gets a byte once the start is logged: the kill's random instant counts from there,
// so that a loaded machine does not shift the kills before the runs' loops. A run that is not the
// `last` waits for its kill once its data are done: on a fast machine a run could otherwise finish
// the record before its kill and end the test with fewer kills than it asks for. With `cut_before`
// set, the run cuts its own power just before that checkpoint fsync instead.
[[noreturn]] void run_child(const std::string& dir, int ready, bool last, bool power_loss = false,
                            bool drop_file_fsync = false, int cut_before = 0) {
  if (power_loss) powerloss::arm(dir, drop_file_fsync, cut_before);
  const Config c = kill_config(dir);
  hal::FakeCanBus bus;
  auto node = bus.attach();
  hal::FakeClock clock;
  hal::FakeTimer timer(clock);
  hal::FakeCountSource source;
  Board board(c, BoardIo{*node, &source, clock, timer});
  const std::string said = board.resume();
  const Start start = said.find("resumed") != std::string::npos         ? resumed
                      : said.find("no checkpoint") != std::string::npos ? fresh
                                                                        : refused;
  std::uint64_t restarts = 0;
  {
    std::ifstream log(dir + "/segments");
    std::uint64_t j = 0, s = 0;
    int how = 0;
    while (log >> j >> s >> how) ++restarts;
  }
  const std::uint64_t kept = board.characterizer().increments();
  const std::uint64_t first = kept + restarts * downtime_samples;  // index of this segment's first sample
  const std::string line = std::to_string(first) + " " + std::to_string(kept) + " " + std::to_string(start) + "\n";
  const int fd = open((dir + "/segments").c_str(), O_WRONLY | O_APPEND | O_CREAT, 0644);
  if (write(fd, line.data(), line.size()) != static_cast<ssize_t>(line.size()) || fsync(fd) != 0) _exit(3);
  close(fd);
  if (write(ready, "r", 1) != 1) _exit(3);
  close(ready);
  std::vector<std::int64_t> counts(total_samples - kept);
  for (std::size_t k = 0; k < counts.size(); ++k) counts[k] = count_at(first + k);
  source.script_counts(clock.now_ns(), ms, counts.data(), counts.size());
  for (std::size_t k = 0; k < counts.size(); ++k) {
    clock.advance(ms);
    timer.update();
    board.run_once(0);
  }
  const bool complete = board.checkpoint() == 0 && board.characterizer().increments() == total_samples;
  while (!last) pause();
  _exit(complete ? 0 : 4);
}

struct Tally {
  int runs = 0, kills = 0;
  int resumed = 0, fresh = 0, refused = 0;     // how the runs that got to log their start started
  int fresh_after_resume = 0;                  // fresh starts after a resume: a durable checkpoint was lost
  int during_write = 0;                        // kills that left the temporary file: inside CheckpointFile::write()
  int dropped = 0;                             // power cuts that dropped something not yet durable
  int cuts_in_write = 0, dropped_by_them = 0;  // runs cut inside a checkpoint write on purpose
};

// Runs until one completes, killing the first `kills` runs at random instants (and, with power
// loss, dropping what was not durable after each kill). With power loss, every tenth run instead
// cuts its power inside its third checkpoint write: before the file's fsync, or (the next time)
// after the rename and before the directory's fsync, the two windows where a write is not durable. Then checks the final state, as a new run
// resumes it, against brute force over the segments kept since the last fresh start.
Tally kill_and_check(const std::string& name, int kills_wanted, bool power_loss, bool drop_file_fsync = false) {
  Tally t;
  const std::string dir = test_support::temp_path(name);
  std::system(("rm -rf " + dir + " && mkdir -p " + dir).c_str());
  std::mt19937_64 rng(2026);
  for (bool done = false; !done && t.runs < 2 * kills_wanted + 100; ++t.runs) {
    const bool cut = power_loss && !drop_file_fsync && t.kills < kills_wanted && t.runs % 10 == 9;
    const int cut_before = cut ? 5 + (t.runs / 10) % 2 : 0;  // checkpoint fsyncs go file, directory, file, ...
    int ready[2];
    EXPECT_EQ(pipe(ready), 0);
    const pid_t child = fork();
    EXPECT_GE(child, 0);
    if (child == 0) {
      close(ready[0]);
      run_child(dir, ready[1], t.kills >= kills_wanted, power_loss, drop_file_fsync, cut_before);
    }
    close(ready[1]);
    char byte = 0;
    EXPECT_EQ(read(ready[0], &byte, 1), 1);
    if (cut) {
      ++t.kills;  // it kills itself
      ++t.cuts_in_write;
    } else if (t.kills < kills_wanted) {
      std::this_thread::sleep_for(std::chrono::microseconds(rng() % 40000));
      if (kill(child, SIGKILL) == 0) ++t.kills;
    }
    close(ready[0]);
    int status = 0;
    waitpid(child, &status, 0);
    EXPECT_TRUE(!cut || (WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL)) << "run " << t.runs << " did not cut";
    done = WIFEXITED(status) && WEXITSTATUS(status) == 0;
    if (WIFEXITED(status)) {
      EXPECT_EQ(WEXITSTATUS(status), 0) << "run " << t.runs;
      continue;
    }
    t.during_write += access((dir + "/run.ckpt.tmp").c_str(), F_OK) == 0;
    if (power_loss) {
      const bool dropped = powerloss::cut_power(dir);
      t.dropped += dropped;
      t.dropped_by_them += cut && dropped;
    }
  }

  // The segments the runs kept since the last fresh start: each starts at its logged index; its
  // length is what the next run found in the checkpoint minus what this one found.
  struct Logged {
    std::uint64_t first, kept;
    int start;
  };
  std::vector<Logged> log;
  std::ifstream in(dir + "/segments");
  for (Logged l{}; in >> l.first >> l.kept >> l.start;) log.push_back(l);
  EXPECT_GE(log.size(), 2u);
  std::vector<std::vector<std::int64_t>> segments;  // phase points of each segment
  for (std::size_t k = 0; k < log.size(); ++k) {
    t.resumed += log[k].start == resumed;
    t.fresh += log[k].start == fresh;
    t.refused += log[k].start == refused;
    t.fresh_after_resume += log[k].start != resumed && t.resumed > 0;
    if (log[k].start != resumed) {
      segments.clear();  // a fresh start: what came before is not in the state
      EXPECT_EQ(log[k].kept, 0u);
    }
    const std::uint64_t end = k + 1 < log.size() ? log[k + 1].kept : total_samples;
    if (k + 1 < log.size() && log[k + 1].start != resumed) continue;  // the next run starts afresh
    EXPECT_GE(end, log[k].kept) << "run " << k << ": resumed with fewer samples than the one before kept";
    if (end <= log[k].kept) continue;  // killed before its first durable checkpoint: nothing kept
    std::vector<std::int64_t> x{0};
    for (std::uint64_t i = 0; i < end - log[k].kept; ++i) x.push_back(x.back() + count_at(log[k].first + i));
    segments.push_back(x);
  }

  // The final state, as a new run would resume it.
  hal::FakeCanBus bus;
  auto node = bus.attach();
  hal::FakeClock clock;
  hal::FakeTimer timer(clock);
  Board final_board(kill_config(dir), BoardIo{*node, nullptr, clock, timer});
  const std::string said = final_board.resume();
  EXPECT_NE(said.find("resumed"), std::string::npos) << said;
  const auto& pyramid = final_board.characterizer();
  std::uint64_t points = 0;
  for (const auto& x : segments) points += x.size();
  EXPECT_EQ(pyramid.phase_points(), points);
  EXPECT_EQ(pyramid.increments(), points - segments.size());  // each segment: one point more than samples
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
  std::printf(
      "%s: %d runs, %d killed (%d inside a checkpoint write, %d power cuts dropped unsynced data, %d of the %d "
      "cut inside a write on purpose); of the %zu that logged their start %d resumed, %d fresh (%d after a resume), %d "
      "refused; %zu segments kept\n",
      name.c_str(), t.runs, t.kills, t.during_write, t.dropped, t.dropped_by_them, t.cuts_in_write, log.size(), t.resumed,
      t.fresh, t.fresh_after_resume, t.refused, segments.size());
  if (!getenv("KEEP")) std::system(("rm -rf " + dir).c_str());
  return t;
}

TEST(CheckpointKill, RandomSigkillsLoseOnlyTheUncheckpointedData) {
  const Tally t = kill_and_check("kill", 200, false);
  EXPECT_EQ(t.kills, 200) << "every run but the last must have been killed for the test to mean anything";
  EXPECT_GT(t.resumed, 150);
  EXPECT_EQ(t.fresh_after_resume, 0) << "fresh starts only before the first checkpoint";
  EXPECT_EQ(t.refused, 0) << "a SIGKILL never leaves a torn checkpoint";
}

// Power cuts at random instants: what was not fsynced is lost, yet every run resumes the last
// durable checkpoint exactly (never a torn or refused one), and the final state is exact.
TEST(CheckpointKill, PowerCutsDropOnlyWhatWasNotDurable) {
  const Tally t = kill_and_check("power", 100, true);
  EXPECT_EQ(t.kills, 100);
  EXPECT_EQ(t.cuts_in_write, 10);
  EXPECT_EQ(t.dropped_by_them, t.cuts_in_write) << "a cut inside a checkpoint write loses what was not yet durable";
  EXPECT_GT(t.resumed, 75);
  EXPECT_EQ(t.fresh_after_resume, 0) << "a durable checkpoint is never lost";
  EXPECT_EQ(t.refused, 0) << "a power cut never leaves a torn checkpoint";
}

// The simulated disk has teeth: a writer whose data is never fsynced leaves, after a power cut,
// a checkpoint name pointing at nothing durable (an empty file), refused, and the run starts
// afresh: data lost, which the correct writer never lets happen.
TEST(CheckpointKill, WithoutTheFileFsyncAPowerCutLosesTheRun) {
  const Tally t = kill_and_check("nofsync", 15, true, true);
  EXPECT_GT(t.refused, 0);
  EXPECT_EQ(t.resumed, 0);
}

}  // namespace
}  // namespace gyrochar::firmware
