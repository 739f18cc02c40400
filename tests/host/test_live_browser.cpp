// The live page in a real browser: headless Chromium (Debian's chromium) loads the demo's page
// while the demo runs, and the numbers the page shows (each ADEV and MDEV cell's exact value, in
// its data-value) equal the decoder's CSV for the same report (node, seq, time), each card's plot
// is drawn by the page's plotting library (Chart.js, served by the demo), and the browser logs no
// script error and no Content-Security-Policy refusal. A screenshot is
// kept in the build folder (tests/live_page.png) for a person to look at. Oracle: the CSV the same
// program wrote. Skipped, saying so, where chromium is not installed (toolchain/build.sh test
// installs it).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "support/http_client.hpp"
#include "support/live_process.hpp"
#include "support/shell.hpp"

namespace gyrochar {
namespace {

using namespace gyrochar::test;

const std::string bin = GYROCHAR_BINARY_DIR "/host_tools/";

std::string temp(const std::string& name) { return gyrochar::test_support::temp_path("browser_" + name); }

std::string chromium() {
  for (const char* path : {"/usr/bin/chromium", "/usr/bin/chromium-browser"})
    if (::access(path, X_OK) == 0) return path;
  return {};
}

std::string output_of(const std::string& command) {
  std::string out;
  FILE* p = popen(command.c_str(), "r");
  char buffer[65536];
  while (const std::size_t n = std::fread(buffer, 1, sizeof buffer, p)) out.append(buffer, n);
  pclose(p);
  return out;
}

TEST(LiveBrowser, PageShowsTheDecodersCsvValues) {
  const std::string browser = chromium();
  if (browser.empty())
    GTEST_SKIP() << "chromium is not installed (Debian package chromium; toolchain/build.sh test installs it)";
  const std::string csv = temp("demo.csv"), limits = temp("limits.txt");
  // A limit no gyro meets (oracle: no gyro's ADEV is below 1e-9 deg/h): each card's verdict fails.
  std::ofstream(limits) << "adev(10.24 s) <= 1e-9 deg/h\n";
  Background demo(bin + "gyrochar-demo --nodes 2 --hours 0.25 --speed 60 --view-every 0 --plot '' --csv " + csv +
                      " --http 127.0.0.1:0 --limits " + limits,
                  temp("demo.err"));
  const std::uint16_t port = demo.port();
  ASSERT_NE(port, 0) << demo.err();
  // The browser is started once both nodes' ADEV at 10.24 s is decided in the server's snapshot (it
  // needs 20.48 s of gyro time, later than the first rows on a loaded machine or under sanitizers).
  const auto decided = [&] {
    const std::string body = body_of(get(port, "/data.json"));
    std::size_t n = 0;
    for (std::size_t at = 0; (at = body.find("\"verdict\":\"fail\",\"why\"", at)) != std::string::npos; ++at) ++n;
    return n == 2;
  };
  for (int k = 0; k < 600 && !decided(); ++k) std::this_thread::sleep_for(std::chrono::milliseconds(100));
  // ?updates=3: the page follows the event stream for 3 snapshots, then closes it and goes idle,
  // so that the headless browser's virtual time runs out and it prints the page.
  const std::string url = "'http://127.0.0.1:" + std::to_string(port) + "/?updates=3'";
  // Bounded: `timeout` ends a browser that hangs. The profile goes to a temporary folder.
  const std::string flags = " --headless --no-sandbox --disable-gpu --no-first-run --user-data-dir=" + temp("profile") +
                            " --virtual-time-budget=10000 ";
  // The browser's log (its console among it) goes to a file: the page's scripts must run clean.
  const std::string log = temp("chromium.log");
  const std::string dom = output_of("timeout 120 " + browser + flags + "--enable-logging=stderr --v=0 --dump-dom " + url +
                                    " 2>" + log);
  const std::string shot = GYROCHAR_BINARY_DIR "/tests/live_page.png";
  std::remove(shot.c_str());
  std::system(
      ("timeout 120 " + browser + flags + "--window-size=1400,1700 --screenshot=" + shot + " " + url + " >/dev/null 2>&1")
          .c_str());
  // The demo goes on to its end (its CSV complete), then is stopped.
  ASSERT_TRUE(demo.wait_for("serves the finished run", 300)) << demo.err();
  EXPECT_EQ(demo.stop(), 0) << demo.err();
  EXPECT_EQ(::access(shot.c_str(), R_OK), 0) << "no screenshot " << shot;

  // The report each node's card shows, then its cells.
  const std::regex report_re(R"re(data-node="(\d+)" data-seq="(\d+)" data-time-s="([^"]+)")re");
  const std::regex cell_re(R"re(data-node="(\d+)" data-tau-index="(\d+)" data-stat="(adev|mdev)" data-value="([^"]+)")re");
  std::map<int, std::pair<int, double>> report;  // node -> seq, time_s
  for (auto it = std::sregex_iterator(dom.begin(), dom.end(), report_re); it != std::sregex_iterator(); ++it)
    report[std::stoi((*it)[1])] = {std::stoi((*it)[2]), std::stod((*it)[3])};
  ASSERT_EQ(report.size(), 2u) << "both nodes' cards: " << dom.substr(0, 2000);
  // Each card's ADEV/MDEV plot is a canvas that Chart.js (served by the demo as /chart.js) took
  // over: it gives the canvas its display style. No script error and no request refused by the
  // Content-Security-Policy (the library needs no inline style and no eval).
  const std::regex chart_re(
      R"re(<canvas (?=[^>]*style="display: block;)(?=[^>]*aria-label="[^"]*: ADEV and MDEV")[^>]*>)re");
  EXPECT_EQ(std::distance(std::sregex_iterator(dom.begin(), dom.end(), chart_re), std::sregex_iterator()), 2)
      << "a plot drawn by Chart.js on each card";
  std::stringstream console;
  console << std::ifstream(log).rdbuf();
  for (const char* error : {"Uncaught", "Refused to", "Content Security Policy"})
    EXPECT_EQ(console.str().find(error), std::string::npos) << error << " in the browser's log: " << console.str();
  std::map<std::tuple<int, int, std::string>, double> shown;  // node, tau index, stat -> value
  for (auto it = std::sregex_iterator(dom.begin(), dom.end(), cell_re); it != std::sregex_iterator(); ++it)
    shown[{std::stoi((*it)[1]), std::stoi((*it)[2]), (*it)[3]}] = std::stod((*it)[4]);
  ASSERT_GE(shown.size(), 20u);
  const std::regex verdict_re(R"re(<tr data-limit="adev\(10.24 s\)" data-verdict="([a-z]+)")re");
  std::vector<std::string> verdicts;
  for (auto it = std::sregex_iterator(dom.begin(), dom.end(), verdict_re); it != std::sregex_iterator(); ++it)
    verdicts.push_back((*it)[1]);
  EXPECT_EQ(verdicts, (std::vector<std::string>{"fail", "fail"})) << "each card's verdict under --limits";

  std::ifstream in(csv);
  std::string line;
  std::getline(in, line);
  std::vector<std::string> header;
  for (std::stringstream h(line); std::getline(h, line, ',');) header.push_back(line);
  const auto column = [&](const char* name) {
    return static_cast<std::size_t>(std::find(header.begin(), header.end(), name) - header.begin());
  };
  // The next tau each card names (oracle: the CSV): the shortest tau of the card's report without
  // an ADEV, its first estimate at most 2 tau of gyro time away (an ADEV at m needs 2m samples).
  const std::regex next_re(R"re(class="meta next-tau" data-node="(\d+)" data-tau-s="([^"]+)" data-wait-s="([^"]+)")re");
  std::map<int, std::pair<double, double>> next;  // node -> tau_s, wait_s
  for (auto it = std::sregex_iterator(dom.begin(), dom.end(), next_re); it != std::sregex_iterator(); ++it)
    next[std::stoi((*it)[1])] = {std::stod((*it)[2]), std::stod((*it)[3])};
  std::map<int, double> first_without;  // node -> shortest tau of its shown report without an ADEV
  std::size_t compared = 0;
  while (std::getline(in, line)) {
    std::vector<std::string> f;
    for (std::stringstream r(line); std::getline(r, line, ',');) f.push_back(line);
    if (f.size() <= column("mdev") || f[column("type")] != "tau") continue;
    const int node = std::stoi(f[column("node")]);
    if (!report.contains(node) || report[node] != std::pair{std::stoi(f[column("seq")]), std::stod(f[column("time_s")])})
      continue;
    const int tau = std::stoi(f[column("tau_index")]);
    const double tau_s = std::stod(f[column("tau_s")]);
    if (f[column("adev")].empty() && tau_s > 0 && (!first_without.contains(node) || tau_s < first_without[node]))
      first_without[node] = tau_s;
    for (const char* stat : {"adev", "mdev"}) {
      const std::string& text = f[column(stat)];
      const auto it = shown.find({node, tau, stat});
      if (text.empty()) {
        EXPECT_EQ(it, shown.end()) << "node " << node << " tau " << tau << " " << stat << ": no value in the CSV";
        continue;
      }
      ASSERT_NE(it, shown.end()) << "node " << node << " tau " << tau << " " << stat;
      EXPECT_EQ(it->second, std::stod(text)) << "node " << node << " tau " << tau << " " << stat;
      ++compared;
    }
  }
  EXPECT_EQ(compared, shown.size()) << "every value the page shows is the CSV's of that report";
  ASSERT_FALSE(first_without.empty()) << "a 15-minute run has taus its ADEV cannot reach yet";
  ASSERT_EQ(next.size(), first_without.size()) << "a next tau on each card whose report has a tau without an ADEV";
  for (const auto& [node, tau_s] : first_without) {
    ASSERT_TRUE(next.contains(node)) << "node " << node;
    EXPECT_NEAR(next[node].first, tau_s, 1e-6 * tau_s) << "node " << node;
    EXPECT_GE(next[node].second, 0.0) << "node " << node;
    EXPECT_LE(next[node].second, 2 * tau_s) << "node " << node;
  }
}

}  // namespace
}  // namespace gyrochar
