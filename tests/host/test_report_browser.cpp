// The HTML report (gyrochar-analyze --report) in a real browser: Debian's chromium, headless, loads
// the file with the network off, dumps the rendered DOM, takes a screenshot and prints it to PDF,
// kept as test artifacts in the build folder (test-artifacts/report.png, report.pdf). Oracle: the analyzer's own JSON for the
// same run: every statistic's tau, m, n, deviation, interval, EDF and alpha in the DOM equal the
// JSON's (both shortest round trips of the same doubles: exact equality), and so do the fit's terms
// and the verdicts. Skipped, saying so, where chromium is not installed (toolchain/build.sh installs
// it for the test job). Label "browser".
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <map>
#include <nlohmann/json.hpp>
#include <regex>
#include <string>
#include <vector>

#include "support/shell.hpp"

namespace {

const std::string analyze = GYROCHAR_BINARY_DIR "/host_tools/gyrochar-analyze";
const std::string sim = GYROCHAR_BINARY_DIR "/host_tools/gyrochar-sim";
const std::string artifacts = GYROCHAR_BINARY_DIR "/test-artifacts";

std::string temp(const std::string& name) { return gyrochar::test_support::temp_path(name); }

// Runs a shell command; its stdout, and its exit code in `code`.
std::string run(const std::string& command, int& code) {
  const auto r = gyrochar::test_support::run_shell(command, "browser_err.txt");
  code = r.code;
  return r.out;
}

std::string chromium() {
  for (const char* c : {"/usr/bin/chromium", "/usr/bin/chromium-browser"})
    if (access(c, X_OK) == 0) return c;
  return {};
}

// The cells of each row of the table with id `id` in `dom`: each cell's data-value, or its text
// when it has none.
std::vector<std::vector<std::string>> table_rows(const std::string& dom, const std::string& id) {
  const auto begin = dom.find("<table id=\"" + id + "\"");
  if (begin == std::string::npos) return {};
  const std::string table = dom.substr(begin, dom.find("</table>", begin) - begin);
  static const std::regex row("<tr>(.*?)</tr>"), cell("<td([^>]*)>([^<]*)</td>"), value("data-value=\"([^\"]*)\"");
  std::vector<std::vector<std::string>> rows;
  for (auto r = std::sregex_iterator(table.begin(), table.end(), row); r != std::sregex_iterator(); ++r) {
    const std::string body = (*r)[1];
    if (body.find("<td") == std::string::npos) continue;  // the header
    std::vector<std::string> cells;
    for (auto c = std::sregex_iterator(body.begin(), body.end(), cell); c != std::sregex_iterator(); ++c) {
      std::smatch v;
      const std::string attrs = (*c)[1];
      cells.push_back(std::regex_search(attrs, v, value) ? v[1].str() : (*c)[2].str());
    }
    rows.push_back(std::move(cells));
  }
  return rows;
}

// The DOM value (a cell's text) equals the JSON number exactly; an empty cell stands for null.
void expect_same(const std::string& cell, const nlohmann::json& j, const std::string& what) {
  if (j.is_null()) {
    EXPECT_EQ(cell, "") << what;
    return;
  }
  ASSERT_FALSE(cell.empty()) << what << ": the DOM has no value, the JSON " << j;
  EXPECT_EQ(std::stod(cell), j.get<double>()) << what;
}

TEST(ReportBrowser, RenderedValuesEqualTheAnalyzersJson) {
  const std::string browser = chromium();
  if (browser.empty())
    GTEST_SKIP() << "chromium is not installed (Debian package chromium; toolchain/build.sh test installs it)";
  int code = 0;
  const std::string counts = temp("browser_gyro.txt"), report = temp("browser_report.html");
  const std::string limits = temp("browser_limits.txt");
  std::ofstream(limits) << "N <= 0.006 deg/sqrt(h)\nadev(100 s) <= 0.5 deg/h\nK <= 1 deg/h/sqrt(h)\n";
  run(sim + " --duration 3600 --tau0 0.1 --arw 0.003 --white-angle 1 --seed 11 > " + counts, code);
  ASSERT_EQ(code, 0);
  const std::string args =
      " --type counts --tau0 0.1 --pulse-weight 1arcsec --fit ieee952 --stats oadev,mdev,tdev --limits " + limits + " " +
      counts;
  const auto json = nlohmann::json::parse(run(analyze + args + " --format json --report " + report, code));
  ASSERT_EQ(code, 5) << "K is not resolved: undecided";

  mkdir(artifacts.c_str(), 0755);
  const std::string flags =
      " --headless --no-sandbox --disable-gpu --no-first-run --disable-extensions"
      " --user-data-dir=" +
      temp("chromium_profile") + " --proxy-server=127.0.0.1:9 ";
  const std::string dom = run(browser + flags + "--dump-dom file://" + report + " 2>/dev/null", code);
  ASSERT_EQ(code, 0) << "chromium --dump-dom";
  ASSERT_NE(dom.find("</html>"), std::string::npos) << dom.substr(0, 500);
  run(browser + flags + "--window-size=1200,2400 --screenshot=" + artifacts + "/report.png file://" + report +
          " >/dev/null 2>&1",
      code);
  EXPECT_EQ(code, 0) << "chromium --screenshot";
  struct stat st {};
  EXPECT_EQ(stat((artifacts + "/report.png").c_str(), &st), 0);
  EXPECT_GT(st.st_size, 10000) << "a screenshot with something in it";
  // Printed to PDF as a browser's print dialog would (the @media print style).
  run(browser + flags + "--no-pdf-header-footer --print-to-pdf=" + artifacts + "/report.pdf file://" + report +
          " >/dev/null 2>&1",
      code);
  EXPECT_EQ(code, 0) << "chromium --print-to-pdf";
  const std::string pdf = gyrochar::test_support::slurp(artifacts + "/report.pdf");
  EXPECT_EQ(pdf.rfind("%PDF-", 0), 0u) << "a PDF";
  EXPECT_GT(pdf.size(), 20000u) << "with the tables and plots in it";

  // Every statistic: the DOM's rows are the JSON's results of that statistic, in order.
  std::map<std::string, std::vector<nlohmann::json>> results;
  for (const auto& r : json.at("results")) results[r.at("stat")].push_back(r);
  ASSERT_EQ(results.size(), 3u);
  for (const auto& [stat, rows] : results) {
    const auto dom_rows = table_rows(dom, "stat-" + stat);
    ASSERT_EQ(dom_rows.size(), rows.size()) << stat;
    for (std::size_t i = 0; i < rows.size(); ++i) {
      const auto& c = dom_rows[i];
      ASSERT_EQ(c.size(), 9u) << stat << " row " << i;
      const std::string at = stat + " tau " + c[0];
      expect_same(c[0], rows[i].at("tau"), at + " tau");
      expect_same(c[1], rows[i].at("m"), at + " m");
      expect_same(c[2], rows[i].at("n"), at + " n");
      expect_same(c[3], rows[i].at("dev"), at + " dev");
      expect_same(c[4], rows[i].at("ci_low"), at + " ci_low");
      expect_same(c[5], rows[i].at("ci_high"), at + " ci_high");
      expect_same(c[6], rows[i].at("edf"), at + " edf");
      expect_same(c[7], rows[i].at("alpha"), at + " alpha");
    }
  }
  // The fit of both curves: each term's value and uncertainty.
  const auto fit_rows = table_rows(dom, "fit");
  ASSERT_GE(fit_rows.size(), 5u);
  const auto& fit = json.at("fit")[0];
  for (std::size_t k = 0; k < 5; ++k) {
    const std::string letter = fit_rows[k][0];
    const auto& term = fit.at(letter);
    if (!term.at("fitted").get<bool>()) continue;
    expect_same(fit_rows[k][1], term.at("value"), letter + " value");
    expect_same(fit_rows[k][2], term.at("uncertainty"), letter + " uncertainty");
  }
  // The verdicts.
  const auto verdicts = table_rows(dom, "verdicts");
  const auto& limits_json = json.at("acceptance").at("limits");
  ASSERT_EQ(verdicts.size(), limits_json.size());
  for (std::size_t i = 0; i < verdicts.size(); ++i) {
    EXPECT_EQ(verdicts[i][0], limits_json[i].at("quantity"));
    expect_same(verdicts[i][1], limits_json[i].at("limit"), "limit");
    expect_same(verdicts[i][3], limits_json[i].at("estimate"), "estimate");
    expect_same(verdicts[i][4], limits_json[i].at("lower"), "lower");
    expect_same(verdicts[i][5], limits_json[i].at("upper"), "upper");
    EXPECT_EQ(verdicts[i][6], limits_json[i].at("verdict"));
  }
  // The plots rendered as inline SVG.
  std::size_t plots = 0;
  for (auto at = dom.find("<svg class=\"plot\""); at != std::string::npos; at = dom.find("<svg class=\"plot\"", at + 1))
    ++plots;
  EXPECT_EQ(plots, 2u) << "ADEV and MDEV";
}

}  // namespace

namespace {

// The fields of a CSV line without quotes (the decoder's rows have none).
std::vector<std::string> fields(const std::string& line) {
  std::vector<std::string> f;
  std::string cur;
  for (const char c : line) {
    if (c == ',') f.push_back(cur), cur.clear();
    else cur += c;
  }
  f.push_back(cur);
  return f;
}

// The decoder's report of the demo's two nodes: each tau's ADEV and MDEV, interval and EDF in the
// rendered DOM equal the decoder's CSV row of the last report (oracle: the CSV of the same run).
TEST(ReportBrowser, DecoderReportEqualsItsCsv) {
  const std::string browser = chromium();
  if (browser.empty())
    GTEST_SKIP() << "chromium is not installed (Debian package chromium; toolchain/build.sh test installs it)";
  int code = 0;
  const std::string log = temp("browser_demo.log"), csv = temp("browser_decode.csv"), report = temp("browser_decode.html");
  run(std::string(GYROCHAR_BINARY_DIR) +
          "/host_tools/gyrochar-demo --hours 0.3 --window 0 --view-every 0 --csv '' --plot '' "
          "--candump " +
          log + " > /dev/null",
      code);
  ASSERT_EQ(code, 0);
  run(std::string(GYROCHAR_BINARY_DIR) + "/host_tools/gyrochar-decode " + log + " --csv " + csv + " --report " + report,
      code);
  ASSERT_EQ(code, 0);
  const std::string flags =
      " --headless --no-sandbox --disable-gpu --no-first-run --disable-extensions"
      " --user-data-dir=" +
      temp("chromium_profile_decode") + " --proxy-server=127.0.0.1:9 ";
  const std::string dom = run(browser + flags + "--dump-dom file://" + report + " 2>/dev/null", code);
  ASSERT_EQ(code, 0);
  mkdir(artifacts.c_str(), 0755);
  run(browser + flags + "--window-size=1200,2400 --screenshot=" + artifacts + "/decode_report.png file://" + report +
          " >/dev/null 2>&1",
      code);
  // The last row of each node and tau.
  std::ifstream in(csv);
  std::string line;
  std::getline(in, line);
  const std::vector<std::string> header = fields(line);
  const auto col = [&](const std::string& name) {
    return static_cast<std::size_t>(std::find(header.begin(), header.end(), name) - header.begin());
  };
  std::map<std::pair<int, int>, std::vector<std::string>> last;
  while (std::getline(in, line)) {
    const auto f = fields(line);
    if (f.size() == header.size() && f[col("type")] == "tau")
      last[{std::stoi(f[col("node")]), std::stoi(f[col("tau_index")])}] = f;
  }
  ASSERT_FALSE(last.empty());
  std::size_t compared = 0;
  for (const auto& [key, f] : last) {
    char id[32];
    std::snprintf(id, sizeof id, "node-%02x-taus", key.first);
    const auto rows = table_rows(dom, id);
    ASSERT_GT(rows.size(), static_cast<std::size_t>(key.second)) << id;
    const auto& c = rows[static_cast<std::size_t>(key.second)];
    ASSERT_EQ(c.size(), 13u) << id;
    EXPECT_EQ(c[1], f[col("m")]) << id;
    std::size_t at = 3;
    for (const char* stat : {"adev", "mdev"}) {
      const std::string s = stat;
      if (f[col(s + "_status")] == "ok") {
        for (const std::string suffix : {"", "_low", "_high", "_edf"}) {
          const std::size_t k = at + (suffix == "" ? 0 : suffix == "_low" ? 1 : suffix == "_high" ? 2 : 3);
          ASSERT_FALSE(c[k].empty()) << id << " " << s + suffix;
          EXPECT_EQ(std::stod(c[k]), std::stod(f[col(s + suffix)])) << id << " tau " << key.second << " " << s + suffix;
        }
        EXPECT_EQ(c[at + 4], f[col(s + "_noise")]);
        ++compared;
      }
      at += 5;
    }
  }
  EXPECT_GE(compared, 2 * 10u) << "two nodes, ten taus or more each";
}

}  // namespace
