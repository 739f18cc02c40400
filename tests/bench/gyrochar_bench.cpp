// gyrochar-bench: the bench's judge, run by the scenarios inside the QEMU guest
// (tests/bench/scenarios, docs/bench.md). It reads what gyrochar-decode recorded from a real
// (emulated) CAN interface and what gyrochar-analyze computed offline, and says whether they agree.
//
//   gyrochar-bench link --jsonl decoded.jsonl --node 17 --node 18 [--expect-gap] [--min-reports 5]
//                       [--lost-edges N]
//     Every node was decoded; without --expect-gap no report was lost or incomplete (the last one
//     may be cut by the end of the recording), no restart, no offline event, no rejected frame,
//     and the nodes counted no sample gap and exactly N (default 0) lost edges. With --expect-gap: the link went away
//     (lost reports or an offline event), the node did not restart, and at least --min-reports
//     complete reports followed.
//   gyrochar-bench estimates --jsonl decoded.jsonl --csv decoded.csv --node 17 --samples 3000
//                            --analyzed analyzed.csv
//     The last complete report of the node holding exactly --samples samples carries, for every
//     tau the analyzer computed, ADEV and MDEV equal to the analyzer's rounded to float32 (the wire
//     format); the oracle is gyrochar-analyze on the same counts (--format csv, --rate-unit
//     deg/s, pulse weight 1 arcsec; the node reports in arcsec/s, recorded with --rate-unit
//     native). The CSV recording must hold the same values as the JSON lines.
//
//   gyrochar-bench quadrature --chip /dev/gpiochip0 --sim /sys/devices/platform/gpio-sim.0/gpiochip0
//                             --tau0 0.2 --counts counts.txt --expected expected.txt [--overflow-every K]
//     The quadrature signal generator: plays the counts as 4x quadrature A/B edges on two gpio-sim
//     lines, one tau0 interval per count, by writing pull-up / pull-down to the lines' sysfs
//     `pull` attributes; it runs SCHED_FIFO, like a generator that does not wait for its DUT. The
//     intervals are gyrochard's own: gyrochard takes its grid's origin just before it requests
//     line A, and the kernel timestamps that request (line info watch, GPIO uAPI v2), so each
//     interval's edges are played in the first 45 % of that interval. --expected gets the sample
//     stream gyrochard must count, from the times the edges were actually made (an emulator stall
//     may push edges late): silent intervals before the first edge as zeros, then every interval
//     up to the last edge gyrochard sees.
//     --overflow-every K: every K-th interval also gets 17 back-and-forth edges on line A, made
//     once gyrochard (--reader) sleeps with nothing left to read (else in the next interval) and
//     without letting it run in between: the kernel's 16-event buffer per line (uAPI v1, what libgpiod 1.6 uses) keeps 16
//     and drops the 17th, and the toggle that brings A back shows gyrochard a change to the level
//     A already had: exactly one lost edge per burst, and no count changes (the 16 kept edges go
//     back and forth, the lost one and its detection cancel).
//
// Output: one line per node (or the playback summary) on stdout; problems as
// `gyrochar-bench: what: why` on stderr.
// Exit codes: 0 agree (played), 1 disagree (an edge's interval not known), 2 bad options or input.
#include <fcntl.h>
#include <linux/gpio.h>
#include <poll.h>
#include <sched.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

namespace {

using Json = nlohmann::json;

constexpr int exit_agree = 0;
constexpr int exit_disagree = 1;
constexpr int exit_bad_input = 2;

[[noreturn]] void bad_input(const std::string& what, const std::string& why) {
  std::fprintf(stderr, "gyrochar-bench: %s: %s\n", what.c_str(), why.c_str());
  std::exit(exit_bad_input);
}

std::vector<std::string> read_lines(const std::string& path) {
  std::ifstream in(path);
  if (!in) bad_input(path, "cannot read");
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);)
    if (!line.empty()) lines.push_back(line);
  return lines;
}

std::vector<std::string> split_csv(const std::string& line) {
  std::vector<std::string> fields;
  std::stringstream s(line);
  for (std::string field; std::getline(s, field, ',');) fields.push_back(field);
  if (!line.empty() && line.back() == ',') fields.emplace_back();
  return fields;
}

// A CSV file with a header line: rows as column name -> text.
std::vector<std::map<std::string, std::string>> read_csv(const std::string& path) {
  const std::vector<std::string> lines = read_lines(path);
  if (lines.empty()) bad_input(path, "empty, no header");
  const std::vector<std::string> header = split_csv(lines[0]);
  std::vector<std::map<std::string, std::string>> rows;
  for (std::size_t k = 1; k < lines.size(); ++k) {
    const std::vector<std::string> fields = split_csv(lines[k]);
    if (fields.size() != header.size())
      bad_input(path, "line " + std::to_string(k + 1) + " has " + std::to_string(fields.size()) + " fields, the header " +
                          std::to_string(header.size()));
    std::map<std::string, std::string>& row = rows.emplace_back();
    for (std::size_t c = 0; c < header.size(); ++c) row[header[c]] = fields[c];
  }
  return rows;
}

double number(const std::string& text, const std::string& where) {
  std::size_t used = 0;
  double v = 0;
  try {
    v = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size()) bad_input(where, "'" + text + "' is not a number");
  return v;
}

// One closed report of one node in a gyrochar-decode JSON lines recording: its `report` line
// and the `tau` lines written just before it.
struct Report {
  Json line;
  std::vector<Json> taus;
  bool complete = false;  // every expected frame arrived (health.reports_complete went up)
};

std::map<unsigned, std::vector<Report>> read_reports(const std::string& path) {
  std::map<unsigned, std::vector<Report>> nodes;
  std::map<unsigned, std::vector<Json>> pending;
  std::size_t number = 0;
  for (const std::string& text : read_lines(path)) {
    ++number;
    Json j;
    try {
      j = Json::parse(text);
    } catch (const Json::exception& e) {
      bad_input(path, "line " + std::to_string(number) + ": " + e.what());
    }
    const std::string type = j.value("type", "");
    if (type == "tau") {
      pending[j.at("node").get<unsigned>()].push_back(j);
    } else if (type == "report") {
      const auto node = j.at("node").get<unsigned>();
      std::vector<Report>& reports = nodes[node];
      const std::uint64_t before = reports.empty() ? 0
                                                   : reports.back().line["health"]["reports_complete"].get<std::uint64_t>();
      Report& r = reports.emplace_back();
      r.complete = j["health"]["reports_complete"].get<std::uint64_t>() > before;
      r.line = std::move(j);
      r.taus = std::move(pending[node]);
      pending[node].clear();
    }
  }
  return nodes;
}

std::uint64_t health(const Json& report, const char* key) { return report["health"][key].get<std::uint64_t>(); }
std::uint64_t fault(const Json& report, const char* key) { return report["faults"][key].get<std::uint64_t>(); }
std::uint64_t rejected(const Json& report) {
  std::uint64_t n = 0;
  for (const auto& [reason, count] : report["health"]["rejected"].items()) n += count.get<std::uint64_t>();
  return n;
}

std::string link_text(const Json& r) {
  return std::to_string(health(r, "reports_complete")) + " complete, " + std::to_string(health(r, "reports_incomplete")) +
         " incomplete, " + std::to_string(health(r, "reports_lost")) + " lost, " +
         std::to_string(health(r, "frames_missing")) + " frames missing, " + std::to_string(health(r, "restarts")) +
         " restarts, " + std::to_string(health(r, "offline_events")) + " offline events, " + std::to_string(rejected(r)) +
         " rejected; node faults: " + std::to_string(fault(r, "sample_gaps")) + " sample gaps, " +
         std::to_string(fault(r, "lost_edges")) + " lost edges, " + std::to_string(fault(r, "tx_dropped_frames")) +
         " tx dropped frames";
}

int check_link(const std::string& jsonl, const std::vector<unsigned>& wanted, bool expect_gap, unsigned min_reports,
               std::uint64_t lost_edges) {
  const auto nodes = read_reports(jsonl);
  int result = exit_agree;
  const auto problem = [&](unsigned node, const std::string& why) {
    std::fprintf(stderr, "gyrochar-bench: node %u: %s\n", node, why.c_str());
    result = exit_disagree;
  };
  for (const unsigned node : wanted) {
    const auto it = nodes.find(node);
    if (it == nodes.end() || it->second.empty()) {
      problem(node, "never decoded (no report in " + jsonl + ")");
      continue;
    }
    const std::vector<Report>& reports = it->second;
    const Json& last = reports.back().line;
    std::printf("node %u: %zu reports: %s\n", node, reports.size(), link_text(last).c_str());
    if (health(last, "restarts") != 0) problem(node, "restarted");
    if (health(last, "duplicates") != 0) problem(node, "address conflict (duplicate slots)");
    if (rejected(last) != 0) problem(node, "frames rejected by the codec");
    if (!expect_gap) {
      // The recording may end in the middle of the last report: judge the one before.
      const Json& judged = reports.size() >= 2 ? reports[reports.size() - 2].line : last;
      if (health(last, "reports_lost") != 0) problem(node, "reports lost");
      if (health(last, "offline_events") != 0) problem(node, "went offline");
      if (health(judged, "reports_incomplete") != 0 || health(judged, "frames_missing") != 0)
        problem(node, "incomplete reports before the last one");
      if (fault(last, "sample_gaps") != 0) problem(node, "the node counted sample gaps in its input");
      if (fault(last, "lost_edges") != lost_edges)
        problem(node, "the node counted " + std::to_string(fault(last, "lost_edges")) + " lost edges, not " +
                          std::to_string(lost_edges));
      if (health(judged, "reports_complete") < min_reports)
        problem(node, "only " + std::to_string(health(judged, "reports_complete")) + " complete reports");
      continue;
    }
    // A gap: the first report after which reports were lost or the node went offline.
    std::size_t gap = reports.size();
    for (std::size_t k = 0; k < reports.size(); ++k) {
      if (health(reports[k].line, "reports_lost") != 0 || health(reports[k].line, "offline_events") != 0) {
        gap = k;
        break;
      }
    }
    if (gap == reports.size()) {
      problem(node, "no gap: no report lost and never offline");
      continue;
    }
    std::size_t after = 0;
    for (std::size_t k = gap; k + 1 < reports.size(); ++k) after += reports[k].complete ? 1 : 0;
    std::printf(
        "node %u: gap at report %zu of %zu (%.3f s after the first): %llu reports lost, %llu offline events; "
        "%zu complete reports after it\n",
        node, gap + 1, reports.size(), reports[gap].line["time_s"].get<double>() - reports[0].line["time_s"].get<double>(),
        static_cast<unsigned long long>(health(last, "reports_lost")),
        static_cast<unsigned long long>(health(last, "offline_events")), after);
    if (after < min_reports) problem(node, "did not resume: " + std::to_string(after) + " complete reports after the gap");
  }
  return result;
}

int check_estimates(const std::string& jsonl, const std::string& csv, unsigned node, std::uint64_t samples,
                    const std::string& analyzed) {
  const auto nodes = read_reports(jsonl);
  const auto it = nodes.find(node);
  if (it == nodes.end()) bad_input(jsonl, "no report of node " + std::to_string(node));
  const Report* chosen = nullptr;
  for (const Report& r : it->second)
    if (r.complete && r.line["sample_count"].get<std::uint64_t>() == samples) chosen = &r;
  if (chosen == nullptr) {
    std::fprintf(stderr, "gyrochar-bench: node %u: no complete report holds exactly %llu samples (last: %llu)\n", node,
                 static_cast<unsigned long long>(samples),
                 static_cast<unsigned long long>(it->second.back().line["sample_count"].get<std::uint64_t>()));
    return exit_disagree;
  }
  const auto seq = chosen->line["seq"].get<unsigned>();
  if (chosen->line["rate_unit"] != "arcsec/s")
    bad_input(jsonl, "node " + std::to_string(node) + " recorded in " + chosen->line["rate_unit"].dump() +
                         ", not arcsec/s (a 1 arcsec pulse weight, --rate-unit native)");
  std::map<std::uint64_t, const Json*> by_m;
  for (const Json& t : chosen->taus)
    if (!t["m"].is_null()) by_m[t["m"].get<std::uint64_t>()] = &t;

  // The CSV holds the same rows: node, seq and time_s (6 decimals, as in the tau lines).
  std::map<std::uint64_t, std::map<std::string, std::string>> csv_by_m;
  for (auto& row : read_csv(csv)) {
    if (number(row["node"], csv) != node || number(row["seq"], csv) != seq || row["m"].empty()) continue;
    if (chosen->taus.empty() || std::fabs(number(row["time_s"], csv) - chosen->taus[0]["time_s"].get<double>()) > 1e-6)
      continue;
    csv_by_m[static_cast<std::uint64_t>(number(row["m"], csv))] = row;
  }

  int result = exit_agree;
  std::size_t compared = 0;
  std::uint64_t m_max = 0;
  double worst = 0;
  for (auto& row : read_csv(analyzed)) {
    const std::string stat = row["stat"];
    if (stat != "oadev" && stat != "mdev") continue;
    if (row["unit"] != "deg/s") bad_input(analyzed, "values in " + row["unit"] + ", not deg/s");
    const auto m = static_cast<std::uint64_t>(number(row["m"], analyzed));
    const double oracle_arcsec_s = number(row["dev"], analyzed) * 3600.0;
    const char* key = stat == "oadev" ? "adev" : "mdev";
    const auto t = by_m.find(m);
    if (t == by_m.end() || (*t->second)[key]["status"] != "ok") {
      std::fprintf(stderr, "gyrochar-bench: node %u: %s m=%llu: no valid value in report seq %u\n", node, stat.c_str(),
                   static_cast<unsigned long long>(m), seq);
      result = exit_disagree;
      continue;
    }
    const double decoded = (*t->second)[key]["value"].get<double>();
    const auto c = csv_by_m.find(m);
    if (c == csv_by_m.end() || c->second[key].empty() || number(c->second[key], csv) != decoded) {
      std::fprintf(stderr, "gyrochar-bench: node %u: %s m=%llu: the CSV does not hold %.9g\n", node, stat.c_str(),
                   static_cast<unsigned long long>(m), decoded);
      result = exit_disagree;
    }
    const float want = static_cast<float>(oracle_arcsec_s);
    worst = std::max(worst, std::fabs(decoded - oracle_arcsec_s) / oracle_arcsec_s);
    if (static_cast<float>(decoded) != want || static_cast<double>(static_cast<float>(decoded)) != decoded) {
      std::fprintf(stderr,
                   "gyrochar-bench: node %u: %s m=%llu: decoded %.9g arcsec/s, gyrochar-analyze %.9g (float32 %.9g)\n", node,
                   stat.c_str(), static_cast<unsigned long long>(m), decoded, oracle_arcsec_s, static_cast<double>(want));
      result = exit_disagree;
    }
    ++compared;
    m_max = std::max(m_max, m);
  }
  if (compared == 0) bad_input(analyzed, "no oadev or mdev row");
  std::printf(
      "node %u: report seq %u with %llu samples: %zu ADEV/MDEV values (m = 1..%llu) %s gyrochar-analyze's in float32 "
      "(largest relative difference before rounding %.2g); the CSV holds the same values\n",
      node, seq, static_cast<unsigned long long>(samples), compared, static_cast<unsigned long long>(m_max),
      result == exit_agree ? "equal" : "differ from", worst);
  return result;
}

// ---------------------------------------------------------------------------------------------
// Quadrature signal generator on gpio-sim

std::int64_t monotonic_ns() {
  timespec t{};
  clock_gettime(CLOCK_MONOTONIC, &t);
  return static_cast<std::int64_t>(t.tv_sec) * 1000000000LL + t.tv_nsec;
}

void sleep_until_ns(std::int64_t t_ns) {
  const timespec due{static_cast<time_t>(t_ns / 1000000000LL), static_cast<long>(t_ns % 1000000000LL)};
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &due, nullptr) == EINTR) {
  }
}

std::vector<std::int64_t> read_counts(const std::string& path) {
  std::vector<std::int64_t> counts;
  std::size_t number = 0;
  for (const std::string& line : read_lines(path)) {
    ++number;
    if (line[0] == '#') continue;
    std::size_t used = 0;
    long long v = 0;
    try {
      v = std::stoll(line, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != line.size()) bad_input(path, "line " + std::to_string(number) + ": not an integer count");
    counts.push_back(v);
  }
  if (counts.empty()) bad_input(path, "no counts");
  return counts;
}

// Two gpio-sim lines driven through their `pull` attributes. The levels (AB) follow the Gray code
// 00 -> 10 -> 11 -> 01 -> 00 upwards (A leading B), so each change of one line is one quarter
// cycle, +1 or -1 by the sense of that step.
class QuadratureLines {
 public:
  QuadratureLines(const std::string& sim_dir, unsigned line_a, unsigned line_b)
      : fd_{open_pull(sim_dir, line_a), open_pull(sim_dir, line_b)} {
    write_level(0, false);
    write_level(1, false);
  }
  ~QuadratureLines() {
    for (const int fd : fd_) close(fd);
  }
  QuadratureLines(const QuadratureLines&) = delete;
  QuadratureLines& operator=(const QuadratureLines&) = delete;

  /// The line that moves one quarter cycle up (direction > 0) or down.
  int line_for(int direction) const { return (level_[0] == level_[1]) == (direction > 0) ? 0 : 1; }
  /// Changes `line`; returns the step that is: +1 or -1.
  int toggle(int line) {
    write_level(line, !level_[line]);
    const bool up = line == 0 ? level_[0] != level_[1] : level_[1] == level_[0];
    return up ? 1 : -1;
  }

 private:
  static int open_pull(const std::string& sim_dir, unsigned line) {
    const std::string path = sim_dir + "/sim_gpio" + std::to_string(line) + "/pull";
    const int fd = open(path.c_str(), O_WRONLY | O_CLOEXEC);
    if (fd < 0) bad_input(path, std::strerror(errno));
    return fd;
  }
  void write_level(int line, bool high) {
    static constexpr const char up[] = "pull-up", down[] = "pull-down";
    const char* text = high ? up : down;
    const std::size_t size = high ? sizeof up - 1 : sizeof down - 1;
    if (pwrite(fd_[line], text, size, 0) != static_cast<ssize_t>(size)) bad_input("pull", std::strerror(errno));
    level_[line] = high;
  }
  int fd_[2];
  bool level_[2] = {false, false};
};

// What gyrochard must count: every edge it sees, in the interval of its kernel timestamp. The
// timestamp lies between the start and the end of the write that made the edge; the interval grid
// starts at the request of line A less at most `origin_slack_ns` (gyrochard reads its clock, then
// opens the chip and requests the line: microseconds on hardware, tens of milliseconds when the
// emulator is starved). An edge whose interval these bounds do not fix is ambiguous.
class EdgeLedger {
 public:
  EdgeLedger(std::int64_t origin_ns, std::int64_t tau_ns, std::int64_t origin_slack_ns)
      : origin_ns_(origin_ns), tau_ns_(tau_ns), origin_slack_ns_(origin_slack_ns) {}

  /// An edge gyrochard sees; `counted`: it changes the count by `step` (false: a lost-edge detection).
  void seen(std::int64_t before_ns, std::int64_t after_ns, int step, bool counted) {
    const std::int64_t first = (before_ns - origin_ns_) / tau_ns_;
    const std::int64_t last = (after_ns + origin_slack_ns_ - origin_ns_) / tau_ns_;
    if (first != last) ++ambiguous_;
    const auto k = static_cast<std::size_t>(first);
    if (k >= counts_.size()) counts_.resize(k + 1, 0);
    if (counted) counts_[k] += step;
    ++edges_;
  }
  const std::vector<std::int64_t>& counts() const { return counts_; }  // up to the last interval with an edge
  std::uint64_t edges() const { return edges_; }
  std::uint64_t ambiguous() const { return ambiguous_; }

 private:
  std::int64_t origin_ns_, tau_ns_, origin_slack_ns_;
  std::vector<std::int64_t> counts_;
  std::uint64_t edges_ = 0, ambiguous_ = 0;
};

struct PlaybackOptions {
  std::string chip, sim_dir, counts, expected;
  unsigned line_a = 0, line_b = 1;
  double tau0_s = 0.2, lead_s = 1.5, wait_s = 30;
  unsigned overflow_every = 0;
  std::string reader = "gyrochard";
};

// Waits for the first request of line A (gyrochard starting) and returns its kernel timestamp.
std::int64_t wait_for_request(const PlaybackOptions& o) {
  const int fd = open(o.chip.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) bad_input(o.chip, std::strerror(errno));
  gpio_v2_line_info info{};
  info.offset = o.line_a;
  if (ioctl(fd, GPIO_V2_GET_LINEINFO_WATCH_IOCTL, &info) < 0)
    bad_input(o.chip, std::string("line info watch: ") + std::strerror(errno));
  std::printf("gyrochar-bench: watching line %u of %s for its request\n", o.line_a, o.chip.c_str());
  std::fflush(stdout);
  for (;;) {
    pollfd p{fd, POLLIN, 0};
    if (poll(&p, 1, static_cast<int>(o.wait_s * 1000)) <= 0) bad_input(o.chip, "line A was not requested in time");
    gpio_v2_line_info_changed change{};
    if (read(fd, &change, sizeof change) != static_cast<ssize_t>(sizeof change)) bad_input(o.chip, std::strerror(errno));
    if (change.event_type == GPIO_V2_LINE_CHANGED_REQUESTED) {
      close(fd);
      return static_cast<std::int64_t>(change.timestamp_ns);
    }
  }
}

// The process named `name` (gyrochard), by /proc/PID/comm; 0 if there is none.
pid_t find_process(const std::string& name) {
  for (const auto& entry : std::filesystem::directory_iterator("/proc")) {
    const std::string pid = entry.path().filename();
    if (pid.find_first_not_of("0123456789") != std::string::npos) continue;
    std::ifstream comm(entry.path() / "comm");
    std::string text;
    if (comm && std::getline(comm, text) && text == name) return static_cast<pid_t>(std::stol(pid));
  }
  return 0;
}

// True while `pid` sleeps (state S: gyrochard blocks only in epoll_wait, which it enters with
// nothing left to read).
bool sleeping(pid_t pid) {
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  std::string text;
  std::getline(stat, text);
  const std::size_t end = text.rfind(')');
  return end != std::string::npos && end + 2 < text.size() && text[end + 2] == 'S';
}

int play_quadrature(const PlaybackOptions& o) {
  const std::vector<std::int64_t> counts = read_counts(o.counts);
  const auto tau_ns = static_cast<std::int64_t>(std::llround(o.tau0_s * 1e9));
  QuadratureLines lines(o.sim_dir, o.line_a, o.line_b);  // both low before gyrochard starts
  sched_param realtime{};
  realtime.sched_priority = 10;  // above every normal task, below the kernel's interrupt threads (50)
  if (sched_setscheduler(0, SCHED_FIFO, &realtime) != 0) bad_input("SCHED_FIFO", std::strerror(errno));

  const std::int64_t origin_ns = wait_for_request(o);
  const pid_t reader = o.overflow_every != 0 ? find_process(o.reader) : 0;
  if (o.overflow_every != 0 && reader == 0) bad_input("--reader", "no process named " + o.reader);
  // Every edge is played in the first 45 % of its interval; the grid may start up to 30 % of tau0
  // before the request, and stalls may delay an edge by up to 25 % of tau0, without changing its
  // interval.
  EdgeLedger ledger(origin_ns, tau_ns, 30 * tau_ns / 100);
  const auto edge = [&](int line, bool counted) {
    const std::int64_t before = monotonic_ns();
    const int step = lines.toggle(line);
    ledger.seen(before, monotonic_ns(), step, counted);
  };
  const std::int64_t first = (monotonic_ns() + static_cast<std::int64_t>(o.lead_s * 1e9) - origin_ns) / tau_ns + 1;
  std::uint64_t bursts = 0, late = 0;
  std::int64_t longest_burst_ns = 0;
  bool burst_due = false;
  for (std::size_t k = 0; k < counts.size(); ++k) {
    const std::int64_t start_ns = origin_ns + (first + static_cast<std::int64_t>(k)) * tau_ns;
    const std::int64_t c = counts[k];
    const std::int64_t n = c < 0 ? -c : c;
    const int direction = c > 0 ? 1 : -1;
    for (std::int64_t i = 0; i < n; ++i) {  // the count's edges, spread over 0.02 .. 0.25 tau0
      sleep_until_ns(start_ns + tau_ns / 50 + (2 * i + 1) * (23 * tau_ns / 100) / (2 * n));
      edge(lines.line_for(direction), true);
    }
    burst_due = burst_due || (o.overflow_every != 0 && (k + 1) % o.overflow_every == 0);
    if (burst_due) {
      // Once gyrochard has read every earlier event (it sleeps); if it is still busy at 35 % of
      // the interval, the burst waits for the next interval.
      sleep_until_ns(start_ns + 28 * tau_ns / 100);
      while (!sleeping(reader) && monotonic_ns() < start_ns + 35 * tau_ns / 100) sleep_until_ns(monotonic_ns() + 1000000);
      if (sleeping(reader)) {
        const std::int64_t burst_ns = monotonic_ns();
        for (int i = 0; i < 16; ++i) edge(0, true);  // no sleep: gyrochard cannot read in between,
        lines.toggle(0);                             // and the kernel's buffer drops this 17th edge
        longest_burst_ns = std::max(longest_burst_ns, monotonic_ns() - burst_ns);
        sleep_until_ns(std::max(start_ns + 42 * tau_ns / 100, monotonic_ns() + 2000000));
        edge(0, false);  // A back where it was: gyrochard sees a change to the level A already had
        ++bursts;
        burst_due = false;
      }
    }
    if (monotonic_ns() > start_ns + 45 * tau_ns / 100) ++late;  // a stall of the emulator
  }

  // The sample stream gyrochard delivers, up to the last interval with an edge it saw (silent
  // intervals before the first edge are delivered as zeros, those after the last one are not).
  std::FILE* f = std::fopen(o.expected.c_str(), "w");
  if (f == nullptr) bad_input(o.expected, std::strerror(errno));
  std::fprintf(f, "# counts gyrochard must deliver: the edges played from %s, by interval of its grid\n", o.counts.c_str());
  for (const std::int64_t c : ledger.counts()) std::fprintf(f, "%lld\n", static_cast<long long>(c));
  if (std::fclose(f) != 0) bad_input(o.expected, "write failed");
  std::printf(
      "gyrochar-bench: played %zu intervals of %g s from interval %lld of gyrochard's grid: %llu edges seen, "
      "%llu overflow bursts (one lost edge each, longest %.1f ms), %llu intervals ended late (stalls), "
      "%llu edges ambiguous; %zu samples expected\n",
      counts.size(), o.tau0_s, static_cast<long long>(first), static_cast<unsigned long long>(ledger.edges()),
      static_cast<unsigned long long>(bursts), static_cast<double>(longest_burst_ns) / 1e6,
      static_cast<unsigned long long>(late), static_cast<unsigned long long>(ledger.ambiguous()), ledger.counts().size());
  if (ledger.ambiguous() != 0) {
    std::fprintf(stderr,
                 "gyrochar-bench: quadrature: %llu edges were played so near an interval's end that their "
                 "interval is not known (the emulator stalled)\n",
                 static_cast<unsigned long long>(ledger.ambiguous()));
    return exit_disagree;
  }
  return exit_agree;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"gyrochar-bench: checks gyrochar-decode recordings made on the bench (docs/bench.md).", "gyrochar-bench"};
  app.require_subcommand(1);
  app.footer(
      "Run by the bench's scenarios inside the QEMU guest (tests/bench/lib.sh, docs/bench.md).\n\n"
      "Examples:\n"
      "  gyrochar-bench link --jsonl decoded.jsonl --node 17 --node 18 --min-reports 8\n"
      "  gyrochar-bench link --jsonl decoded.jsonl --node 49 --expect-gap --min-reports 5\n"
      "  gyrochar-bench estimates --jsonl decoded.jsonl --csv decoded.csv --node 17 --samples 3000 \\\n"
      "                           --analyzed analyzed.csv\n"
      "  gyrochar-bench quadrature --chip /dev/gpiochip0 --sim /sys/devices/platform/gpio-sim.0/gpiochip0 \\\n"
      "                            --tau0 0.2 --counts counts.txt --expected expected.txt --overflow-every 10\n\n"
      "Exit codes: 0 agree, 1 disagree, 2 bad options or unreadable input.");

  std::string jsonl, csv, analyzed;
  std::vector<unsigned> nodes;
  unsigned node = 0, min_reports = 3;
  std::uint64_t samples = 0;
  bool expect_gap = false;
  CLI::App* link = app.add_subcommand("link", "link health of every node in a JSON lines recording");
  link->add_option("--jsonl", jsonl, "gyrochar-decode --jsonl recording")->required();
  link->add_option("--node", nodes, "node address that must be there (repeatable)")->required();
  link->add_flag("--expect-gap", expect_gap, "the link went away and came back");
  link->add_option("--min-reports", min_reports, "complete reports required (after the gap)")->capture_default_str();
  std::uint64_t lost_edges = 0;
  link->add_option("--lost-edges", lost_edges, "lost edges every node must have counted (without --expect-gap)")
      ->capture_default_str();
  CLI::App* estimates = app.add_subcommand("estimates", "decoded ADEV and MDEV against gyrochar-analyze");
  estimates->add_option("--jsonl", jsonl, "gyrochar-decode --jsonl recording (--rate-unit native)")->required();
  estimates->add_option("--csv", csv, "gyrochar-decode --csv recording of the same run")->required();
  estimates->add_option("--node", node, "node address")->required();
  estimates->add_option("--samples", samples, "samples the node must have counted")->required();
  estimates->add_option("--analyzed", analyzed, "gyrochar-analyze --format csv --rate-unit deg/s output")->required();
  PlaybackOptions q;
  CLI::App* quadrature = app.add_subcommand("quadrature", "play counts as quadrature edges on two gpio-sim lines");
  quadrature->add_option("--chip", q.chip, "GPIO character device, e.g. /dev/gpiochip0")->required();
  quadrature->add_option("--sim", q.sim_dir, "the chip's gpio-sim folder: /sys/devices/platform/DEV/CHIP")->required();
  quadrature->add_option("--line-a", q.line_a, "line offset of channel A")->capture_default_str();
  quadrature->add_option("--line-b", q.line_b, "line offset of channel B")->capture_default_str();
  quadrature->add_option("--tau0", q.tau0_s, "gyrochard's sample interval, s")->capture_default_str();
  quadrature->add_option("--counts", q.counts, "counts per interval (gyrochar-sim output)")->required();
  quadrature->add_option("--expected", q.expected, "write the sample stream gyrochard must count here")->required();
  quadrature->add_option("--overflow-every", q.overflow_every, "a lost-edge burst every K intervals (0: none)")
      ->capture_default_str();
  quadrature->add_option("--reader", q.reader, "with --overflow-every: the program reading the lines")
      ->capture_default_str();
  quadrature->add_option("--lead", q.lead_s, "seconds between gyrochard's request and the first edge")
      ->capture_default_str();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    std::fprintf(stderr, "gyrochar-bench: options: %s (see --help)\n", e.what());
    return exit_bad_input;
  }
  if (*link) return check_link(jsonl, nodes, expect_gap, min_reports, lost_edges);
  if (*quadrature) {
    if (!(q.tau0_s >= 0.01)) bad_input("--tau0", "must be at least 0.01 s (the emulated kernel follows ~1 edge/ms)");
    return play_quadrature(q);
  }
  return check_estimates(jsonl, csv, node, samples, analyzed);
}
