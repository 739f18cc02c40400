// gyrochar-analyze and gyrochar-decode with acceptance limits (--limits), the production summary
// (--summary) and the HTML report (--report), as a user meets them. Oracles: the exit codes of
// hal/program/exit_codes.hpp and of host_tools/analyze/acceptance.hpp (5 undecided, 6 fail); the
// simulator's truth (N = 0.003 deg/sqrt(h), a white-angle residue of 1 arcsec): over an hour at
// tau0 0.1 s the fit's N is within a few percent of it, so a limit of 0.006 (twice the truth) is
// met and one of 0.0015 (half) is failed, with the guard band far from either; the decision rule of
// common/limits.hpp recomputed from the JSON's own bounds.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "hal/program/exit_codes.hpp"
#include "support/shell.hpp"

namespace {

using namespace gyrochar;

const std::string analyze = GYROCHAR_BINARY_DIR "/host_tools/gyrochar-analyze";
const std::string sim = GYROCHAR_BINARY_DIR "/host_tools/gyrochar-sim";
const std::string demo = GYROCHAR_BINARY_DIR "/host_tools/gyrochar-demo";
const std::string decode = GYROCHAR_BINARY_DIR "/host_tools/gyrochar-decode";

using test_support::run_shell;
using test_support::slurp;
using Outcome = test_support::ShellOutcome;
std::string temp(const std::string& name) { return test_support::temp_path(name); }

// "16" -> "0x10": a node as the summary names it.
std::string fmt_node(const std::string& decimal) {
  char b[8];
  std::snprintf(b, sizeof b, "0x%02X", std::stoi(decimal) & 0xFF);
  return b;
}

std::string file_with(const std::string& name, const std::string& content) {
  const std::string path = temp(name);
  std::ofstream(path) << content;
  return path;
}

// An hour of a simulated gyro at 10 Hz: N = 0.003 deg/sqrt(h) and a white angle residue.
const std::string& counts() {
  static const std::string path = [] {
    const std::string p = temp("gyro.txt");
    const Outcome r = run_shell(sim + " --duration 3600 --tau0 0.1 --arw 0.003 --white-angle 1 --seed 5 > " + p);
    EXPECT_EQ(r.code, 0) << r.err;
    return p;
  }();
  return path;
}

const std::string analyze_counts = " --type counts --tau0 0.1 --pulse-weight 1arcsec --fit ieee952 ";

TEST(AcceptanceCli, VerdictsSetTheExitCode) {
  const std::string pass = file_with("pass.txt", "# twice the truth\nN <= 0.006 deg/sqrt(h)\n");
  const std::string fail = file_with("fail.txt", "N <= 0.0015 deg/sqrt(h)  # half the truth\n");
  const std::string open = file_with("open.txt", "N <= 0.006 deg/sqrt(h)\nK <= 1 deg/h/sqrt(h)\n");  // K: no such term
  Outcome r = run_shell(analyze + analyze_counts + "--limits " + pass + " " + counts());
  EXPECT_EQ(r.code, 0) << r.err << r.out;
  EXPECT_NE(r.out.find("Acceptance: pass"), std::string::npos) << r.out;
  r = run_shell(analyze + analyze_counts + "--limits " + fail + " " + counts());
  EXPECT_EQ(r.code, 6) << "a failed limit: 6\n" << r.err << r.out;
  EXPECT_NE(r.out.find("Acceptance: fail"), std::string::npos) << r.out;
  r = run_shell(analyze + analyze_counts + "--limits " + open + " --format json " + counts());
  EXPECT_EQ(r.code, 5) << "an undecided limit: 5\n" << r.err;
  const auto j = nlohmann::json::parse(r.out);
  const auto& a = j.at("acceptance");
  EXPECT_EQ(a.at("verdict"), "undecided");
  ASSERT_EQ(a.at("limits").size(), 2u);
  const auto& n = a.at("limits")[0];
  EXPECT_EQ(n.at("quantity"), "N");
  EXPECT_EQ(n.at("verdict"), "pass");
  // The rule recomputed from the JSON's own numbers: the upper bound within the limit.
  EXPECT_LE(n.at("upper").get<double>(), 0.006);
  EXPECT_LE(n.at("lower").get<double>(), n.at("estimate").get<double>());
  // The estimate is the fit's unconstrained N (the same JSON, same unit), within a few of its
  // standard uncertainties of the non-negative fit's value.
  const auto& fit_n = j.at("fit")[0].at("N");
  EXPECT_DOUBLE_EQ(n.at("estimate").get<double>(), fit_n.at("unconstrained").at("value").get<double>());
  EXPECT_NEAR(n.at("estimate").get<double>(), fit_n.at("value").get<double>(),
              3 * fit_n.at("unconstrained").at("uncertainty").get<double>());
  const auto& k = a.at("limits")[1];
  EXPECT_EQ(k.at("verdict"), "undecided");
  EXPECT_TRUE(k.at("estimate").is_null()) << "a term not resolved has no estimate to decide on";
  EXPECT_NE(k.at("why").get<std::string>().find("K not"), std::string::npos) << k;
}

TEST(AcceptanceCli, DeviationLimitsAreReadAtTheirTauAndInCsv) {
  // adev(50 s): m = 500 is no octave; the analyzer adds it to the taus.
  const std::string lim = file_with("adev.txt", "adev(50 s) <= 1 deg/h\nmdev(1 min) <= 1e-9 deg/h\n");
  const Outcome r = run_shell(analyze + analyze_counts + "--limits " + lim + " --format csv " + counts());
  EXPECT_EQ(r.code, 6) << r.err;  // mdev below 1e-9 deg/h is impossible for this gyro: fail
  const auto blank = r.out.find("\n\n");
  ASSERT_NE(blank, std::string::npos) << r.out;
  const std::string verdicts = r.out.substr(blank + 2);
  EXPECT_EQ(verdicts.substr(0, verdicts.find('\n')), "limit,limit_value,unit,estimate,lower,upper,verdict,decides_at_s,why");
  EXPECT_NE(verdicts.find("adev(50 s),1,deg/h,"), std::string::npos) << verdicts;
  EXPECT_NE(verdicts.find(",pass,"), std::string::npos) << verdicts;
  EXPECT_NE(verdicts.find("mdev(60 s),1e-09,deg/h,"), std::string::npos) << verdicts;
  EXPECT_NE(verdicts.find(",fail,"), std::string::npos) << verdicts;
  EXPECT_NE(r.out.find("\noadev,500,50,"), std::string::npos) << "the limited tau is a row of its own";
}

TEST(AcceptanceCli, BadLimitsFilesAreBadInput) {
  const std::regex one_line("gyrochar-analyze: [^\n]+: [^\n]+\n");
  const struct {
    std::string content, why;
  } cases[] = {
      {"N <= 0.003 deg/h\n", "line 1: 'deg/h' is not a unit of N"},
      {"# nothing\n", "no limit in the file"},
      {"N <= 0.003 deg/sqrt(h)\nN >= 1 deg/sqrt(h)\n", "line 2: operator '>='"},
      {"Z <= 1 deg/h\n", "line 1: 'Z' is not a limited quantity"},
  };
  for (const auto& c : cases) {
    const std::string lim = file_with("bad_limits.txt", c.content);
    const Outcome r = run_shell(analyze + analyze_counts + "--limits " + lim + " " + counts());
    EXPECT_EQ(r.code, exit_code::bad_input) << c.content << r.err;
    EXPECT_TRUE(std::regex_match(r.err, one_line)) << r.err;
    EXPECT_NE(r.err.find(c.why), std::string::npos) << r.err;
    EXPECT_TRUE(r.out.empty());
  }
  Outcome r = run_shell(analyze + analyze_counts + "--limits " + temp("absent_limits.txt") + " " + counts());
  EXPECT_EQ(r.code, exit_code::bad_input) << r.err;
  EXPECT_NE(r.err.find("cannot be read"), std::string::npos) << r.err;
  // A fitted term without the fit.
  const std::string n = file_with("n.txt", "N <= 0.003 deg/sqrt(h)\n");
  r = run_shell(analyze + " --type counts --tau0 0.1 --pulse-weight 1arcsec --limits " + n + " " + counts());
  EXPECT_EQ(r.code, exit_code::bad_input);
  EXPECT_NE(r.err.find("add --fit ieee952"), std::string::npos) << r.err;
  // Clock data have no gyro units.
  const std::string phase = file_with("phase.txt", "0\n1e-9\n3e-9\n2e-9\n5e-9\n4e-9\n6e-9\n8e-9\n");
  const std::string b = file_with("b.txt", "adev(1 s) <= 1 deg/h\n");
  r = run_shell(analyze + " --type phase --tau0 1 --limits " + b + " " + phase);
  EXPECT_EQ(r.code, exit_code::bad_input);
  EXPECT_NE(r.err.find("needs gyro data"), std::string::npos) << r.err;
  // The decoder reads the same format and refuses the same way.
  const std::string bad = file_with("bad_for_decode.txt", "N <= 1\n");
  r = run_shell(decode + " " + counts() + " --limits " + bad);
  EXPECT_EQ(r.code, exit_code::bad_input);
  EXPECT_NE(r.err.find("gyrochar-decode: --limits: "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("line 1: the limit has no unit"), std::string::npos) << r.err;
}

TEST(AcceptanceCli, SummaryAppendsOneRowPerRunUnderOneHeader) {
  const std::string lim = file_with("summary_limits.txt", "N <= 0.006 deg/sqrt(h)\n");
  const std::string summary = temp("summary.csv");
  std::remove(summary.c_str());
  for (int i = 0; i < 2; ++i) {
    const Outcome r = run_shell(analyze + analyze_counts + "--limits " + lim + " --summary " + summary + " " + counts());
    EXPECT_EQ(r.code, 0) << r.err;
  }
  const std::string text = slurp(summary);
  EXPECT_EQ(text.rfind("source,node,run_s,samples,fit_status,", 0), 0u) << text;
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 3) << text;
  EXPECT_NE(text.find(counts() + ",,3600,36000,ok,"), std::string::npos) << text;
  // Other limits, the same summary file: refused before the analysis.
  const std::string other = file_with("other_limits.txt", "B <= 1 deg/h\n");
  const Outcome r = run_shell(analyze + analyze_counts + "--limits " + other + " --summary " + summary + " " + counts());
  EXPECT_EQ(r.code, exit_code::bad_input);
  EXPECT_NE(r.err.find("header differs"), std::string::npos) << r.err;
  EXPECT_EQ(slurp(summary), text) << "nothing appended";
  const Outcome no_limits = run_shell(analyze + analyze_counts + "--summary " + summary + " " + counts());
  EXPECT_EQ(no_limits.code, exit_code::bad_input);
}

TEST(AcceptanceCli, ReportIsSelfContained) {
  const std::string lim = file_with("report_limits.txt", "N <= 0.006 deg/sqrt(h)\nadev(100 s) <= 1 deg/h\n");
  const std::string report = temp("report.html");
  const Outcome r = run_shell(analyze + analyze_counts + "--stats oadev,mdev,tdev --limits " + lim + " --report " + report +
                              " " + counts());
  EXPECT_EQ(r.code, 0) << r.err;
  const std::string html = slurp(report);
  EXPECT_EQ(html.rfind("<!DOCTYPE html>", 0), 0u);
  EXPECT_EQ(html.find("http://"), std::string::npos) << "no external reference";
  EXPECT_EQ(html.find("https://"), std::string::npos) << "no external reference";
  EXPECT_EQ(html.find("<script"), std::string::npos) << "no script needed";
  EXPECT_EQ(html.find(" src="), std::string::npos) << "nothing loaded";
  EXPECT_NE(html.find("@media print"), std::string::npos);
  EXPECT_EQ(std::count(html.begin(), html.end(), '<') - std::count(html.begin(), html.end(), '>'), 0)
      << "every tag closed on its line (no stray bracket)";
  for (const char* id : {"id=\"provenance-facts\"", "id=\"verdicts\"", "id=\"fit\"", "id=\"readoff\"", "id=\"stat-oadev\"",
                         "id=\"stat-mdev\"", "id=\"stat-tdev\"", "<svg class=\"plot\""})
    EXPECT_NE(html.find(id), std::string::npos) << id;
  EXPECT_LT(html.size(), 2u << 20) << "under 2 MB";
  EXPECT_EQ(access((report + ".part").c_str(), F_OK), -1) << "the temporary file is renamed";
}

TEST(AcceptanceCli, ReportRefusesToOverwriteAnInput) {
  const std::string lim = file_with("same_limits.txt", "N <= 0.006 deg/sqrt(h)\n");
  Outcome r = run_shell(analyze + analyze_counts + "--report " + counts() + " " + counts());
  EXPECT_EQ(r.code, exit_code::bad_input);
  EXPECT_NE(r.err.find("--report"), std::string::npos) << r.err;
  r = run_shell(analyze + analyze_counts + "--limits " + lim + " --report " + lim + " " + counts());
  EXPECT_EQ(r.code, exit_code::bad_input) << "the limits file is an input too";
  r = run_shell(analyze + analyze_counts + "--limits " + lim + " --summary " + lim + " " + counts());
  EXPECT_EQ(r.code, exit_code::bad_input);
  EXPECT_NE(slurp(counts()).find('\n'), std::string::npos) << "the input is whole";
  r = run_shell(analyze + analyze_counts + "--report " + temp("no_such_dir") + "/r.html " + counts());
  EXPECT_EQ(r.code, exit_code::output_failed) << r.err;
}

TEST(AcceptanceCli, DecoderGivesVerdictsAndReportPerNode) {
  // The demo's two simulated gyros for 20 minutes, decoded from its candump log.
  const std::string log = temp("demo.log");
  Outcome r = run_shell(demo + " --hours 0.34 --window 0 --view-every 0 --csv '' --plot '' --candump " + log +
                        " > /dev/null");
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string lim = file_with("decode_limits.txt", "N <= 1 deg/sqrt(h)\nadev(10.24 s) <= 1e-9 deg/h\n");
  const std::string report = temp("decode_report.html"), jsonl = temp("decode.jsonl"), summary = temp("decode_summary.csv");
  std::remove(summary.c_str());
  r = run_shell(decode + " " + log + " --view final --limits " + lim + " --report " + report + " --jsonl " + jsonl +
                " --summary " + summary);
  EXPECT_EQ(r.code, 0) << "the decoder's exit code does not depend on the verdicts\n" << r.err;
  EXPECT_NE(r.out.find("Acceptance: "), std::string::npos) << r.out;
  const std::string html = slurp(report);
  EXPECT_EQ(html.find("http://"), std::string::npos);
  EXPECT_EQ(html.find("https://"), std::string::npos);
  EXPECT_NE(html.find("-verdicts\""), std::string::npos);
  EXPECT_NE(html.find("<svg class=\"plot\""), std::string::npos);
  std::ifstream in(jsonl);
  std::size_t records = 0;
  for (std::string line; std::getline(in, line);)
    if (line.find("\"type\":\"acceptance\"") != std::string::npos) {
      const auto j = nlohmann::json::parse(line);
      EXPECT_EQ(j.at("limits").size(), 2u);
      if (!j.at("final").get<bool>()) continue;  // a record when a verdict changed (next test)
      ++records;
      EXPECT_EQ(j.at("limits")[1].at("verdict"), "fail") << "no gyro has an ADEV below 1e-9 deg/h: " << line;
    }
  EXPECT_GE(records, 1u);
  const std::string rows = slurp(summary);
  EXPECT_EQ(static_cast<std::size_t>(std::count(rows.begin(), rows.end(), '\n')), records + 1) << rows;
}

TEST(AcceptanceCli, DemoEndsWithNoReportCutOff) {
  // The demo lets each board finish the report it is sending when the run ends. Oracle: on a bus
  // that loses nothing (no --loss) every report the decoder closed arrived whole, the last one too
  // (its link health on stderr: "0 incomplete" and "frames missing 0" for both nodes), so the last
  // view shows no "missing" value.
  const Outcome r = run_shell(demo + " --hours 0.1 --window 0 --view-every 0 --csv '' --plot ''");
  ASSERT_EQ(r.code, 0) << r.err;
  for (const char* node : {"node 0x10: ", "node 0x11: "}) {
    const std::size_t at = r.err.find(std::string("gyrochar-demo: ") + node);
    ASSERT_NE(at, std::string::npos) << r.err;
    const std::string line = r.err.substr(at, r.err.find('\n', at) - at);
    EXPECT_NE(line.find(" 0 incomplete,"), std::string::npos) << line;
    EXPECT_NE(line.find("frames missing 0;"), std::string::npos) << line;
  }
  EXPECT_EQ(r.out.find("missing  "), std::string::npos) << "a value of the last report shown as missing";
}

// Fields of a CSV line (the decoder's names and values hold no comma or quote).
std::vector<std::string> csv_fields(const std::string& line) {
  std::vector<std::string> f(1);
  for (const char c : line) {
    if (c == ',') f.emplace_back();
    else f.back().push_back(c);
  }
  return f;
}

// The decoder with --limits judges every report: its per-tau CSV's verdict columns and its JSON
// lines records against the decoder's own --summary of the same run (the oracle: each node's row,
// written at the end from its final state), and the CSV without --limits, which must be the same
// file with the verdict columns taken off. N <= 1 deg/sqrt(h) is far above the demo's gyros (N a
// few 1e-3), adev(10.24 s) <= 1e-9 deg/h far below any gyro's: both are decided as soon as there
// is an estimate, the ADEV at 10.24 s within the run's first minutes (its first EDF is there after
// a few taus). The demo's board speaks protocol version 5: its terms are judged by the unconstrained
// estimates it sends. The demo's own CSV with the same --limits (its in-process decoder, the same
// frames) must carry the same verdict columns as the decoder's.
TEST(AcceptanceCli, DecoderJudgesEveryReportInCsvAndJsonLines) {
  const std::string log = temp("demo_judged.log"), demo_csv = temp("demo_judged.csv");
  const std::string lim = file_with("judged_limits.txt",
                                    "N <= 1 deg/sqrt(h)\nadev(10.24 s) <= 1e-9 deg/h\nB <= 1e3 deg/h\n");
  Outcome r = run_shell(demo + " --hours 0.34 --window 0 --view-every 0 --csv " + demo_csv + " --limits " + lim +
                        " --plot '' --candump " + log + " > /dev/null");
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string csv = temp("judged.csv"), plain = temp("plain.csv"), jsonl = temp("judged.jsonl"),
                    summary = temp("judged_summary.csv");
  std::remove(summary.c_str());
  r = run_shell(decode + " " + log + " --view none --limits " + lim + " --csv " + csv + " --jsonl " + jsonl + " --summary " +
                summary);
  ASSERT_EQ(r.code, 0) << r.err;
  r = run_shell(decode + " " + log + " --view none --csv " + plain);
  ASSERT_EQ(r.code, 0) << r.err;

  // Without --limits: the same bytes as with them, less the 18 verdict columns (1 + 5 a limit, and
  // the estimate kind of each of the 2 term limits).
  std::istringstream judged_lines(slurp(csv));
  std::string stripped, line;
  while (std::getline(judged_lines, line)) {
    std::size_t cut = line.size();
    for (int k = 0; k < 18; ++k) cut = line.rfind(',', cut - 1);
    stripped += line.substr(0, cut) + "\n";
  }
  EXPECT_TRUE(stripped == slurp(plain)) << "the CSV without --limits is byte for byte the CSV less its verdict columns";

  // The summary's row of each node, by column name.
  std::istringstream summary_lines(slurp(summary));
  std::getline(summary_lines, line);
  const std::vector<std::string> summary_header = csv_fields(line);
  std::map<std::string, std::map<std::string, std::string>> final_row;  // node "0x10" -> column -> field
  while (std::getline(summary_lines, line)) {
    const auto f = csv_fields(line);
    ASSERT_EQ(f.size(), summary_header.size()) << line;
    for (std::size_t k = 0; k < f.size(); ++k) final_row[f[1]][summary_header[k]] = f[k];
  }
  ASSERT_EQ(final_row.size(), 2u) << "the demo's two nodes";

  // The CSV: the rows of each node's last report carry the summary's verdicts.
  std::istringstream csv_lines(slurp(csv));
  std::getline(csv_lines, line);
  const std::vector<std::string> header = csv_fields(line);
  const auto column = [&](const std::string& name) {
    const auto it = std::find(header.begin(), header.end(), name);
    EXPECT_NE(it, header.end()) << name;
    return static_cast<std::size_t>(it - header.begin());
  };
  // node -> rows of its last report, from the decoder's CSV and from the demo's
  std::map<std::string, std::vector<std::vector<std::string>>> last_report, demo_last_report;
  const auto last_reports = [&](std::istream& lines, auto& out) {
    while (std::getline(lines, line)) {
      const auto f = csv_fields(line);
      ASSERT_EQ(f.size(), header.size()) << line;
      if (f[column("type")] != "tau") continue;
      auto& rows = out[fmt_node(f[column("node")])];
      if (!rows.empty() && rows.back()[column("seq")] != f[column("seq")]) rows.clear();
      rows.push_back(f);
    }
  };
  last_reports(csv_lines, last_report);
  ASSERT_EQ(last_report.size(), 2u);
  std::istringstream demo_lines(slurp(demo_csv));
  std::getline(demo_lines, line);
  ASSERT_EQ(csv_fields(line), header) << "the demo's CSV has the decoder's columns, verdicts included";
  last_reports(demo_lines, demo_last_report);
  ASSERT_EQ(demo_last_report.size(), 2u);
  for (const auto& [node, rows] : last_report) {
    SCOPED_TRACE(node);
    const auto& want = final_row.at(node);
    std::size_t adev_rows = 0;
    for (const auto& row : rows) {
      EXPECT_EQ(row[column("verdict")], want.at("verdict"));
      for (const std::string q : {"N", "B", "adev(10.24 s)"}) {
        const bool term = q.size() == 1;
        const std::string unit = q == "N" ? "deg/sqrt(h)" : "deg/h";
        const bool applies = !row[column(q + " limit [" + unit + "]")].empty();
        if (q == "B") {
          ASSERT_TRUE(applies) << "a term limit applies to every tau row";
        }
        if (!applies) {
          EXPECT_EQ(row[column(q + " verdict")], "");
          continue;
        }
        if (!term) {
          ++adev_rows;
          EXPECT_NEAR(std::stod(row[column("tau_s")]), 10.24, 1e-5) << "a deviation limit on its tau's row only";
        }
        for (const std::string& c :
             {std::string(" verdict"), " estimate [" + unit + "]", std::string(" lower"), std::string(" upper")})
          EXPECT_EQ(row[column(q + c)], want.at(q + c)) << q + c;
      }
    }
    EXPECT_EQ(adev_rows, 1u) << "the one row of tau 10.24 s";
    EXPECT_EQ(want.at("adev(10.24 s) verdict"), "fail");
    // Version 5: N (free in the board's fit, resolved) is judged by its unconstrained estimate.
    EXPECT_EQ(rows.back()[column("N estimate kind")], "unconstrained");
    // The demo's own CSV: the same verdict columns in its last report (from "verdict" on).
    const auto& demo_rows = demo_last_report.at(node);
    ASSERT_EQ(demo_rows.size(), rows.size());
    for (std::size_t i = 0; i < rows.size(); ++i)
      for (std::size_t c = column("verdict"); c < header.size(); ++c) EXPECT_EQ(demo_rows[i][c], rows[i][c]) << header[c];
  }

  // The JSON lines: each node's verdicts when they change, the decided adev fail long before the
  // end, and the final record equal to the summary.
  std::map<int, std::vector<nlohmann::json>> records;
  double end_s = 0;
  std::ifstream in(jsonl);
  while (std::getline(in, line)) {
    const auto j = nlohmann::json::parse(line);
    if (j.at("type") == "acceptance") records[j.at("node").get<int>()].push_back(j);
    if (j.at("type") == "summary") end_s = j.at("last_s").get<double>();
  }
  ASSERT_EQ(records.size(), 2u);
  for (const auto& [node, list] : records) {
    SCOPED_TRACE(node);
    ASSERT_GE(list.size(), 2u);
    double decided_at = -1;
    for (std::size_t k = 0; k < list.size(); ++k) {
      EXPECT_EQ(list[k].at("final").get<bool>(), k + 1 == list.size());
      if (decided_at < 0 && list[k].at("limits")[1].at("verdict") == "fail") decided_at = list[k].at("time").get<double>();
      if (k == 0 || k + 1 == list.size()) continue;
      bool changed = false;  // a record only when a verdict changed
      for (std::size_t i = 0; i < 3; ++i)
        changed |= list[k].at("limits")[i].at("verdict") != list[k - 1].at("limits")[i].at("verdict");
      EXPECT_TRUE(changed) << list[k - 1] << "\n" << list[k];
    }
    ASSERT_GE(decided_at, 0) << "the adev limit is failed";
    EXPECT_LT(decided_at, end_s - 600) << "decided in the run's first half, not only at its end";
    const auto& want = final_row.at(fmt_node(std::to_string(node)));
    EXPECT_EQ(list.back().at("verdict"), want.at("verdict"));
    EXPECT_EQ(list.back().at("limits")[0].at("verdict"), want.at("N verdict"));
  }
}

// A bad limits file is refused before anything is written: the CSV given keeps its bytes.
TEST(AcceptanceCli, DecoderRefusesABadLimitsFileAndWritesNothing) {
  const std::string csv = file_with("kept.csv", "an earlier run's CSV\n");
  const std::string bad = file_with("bad_for_csv.txt", "N <= 0.003 deg/sqrt(h)\nadev(0 s) <= 1 deg/h\n");
  const Outcome r = run_shell(decode + " " + counts() + " --limits " + bad + " --csv " + csv + " --jsonl " +
                              temp("none.jsonl"));
  EXPECT_EQ(r.code, exit_code::bad_input) << r.err;
  EXPECT_TRUE(std::regex_match(r.err, std::regex("gyrochar-decode: --limits: [^\n]+: line 2: [^\n]+\n"))) << r.err;
  EXPECT_EQ(slurp(csv), "an earlier run's CSV\n");
  EXPECT_EQ(access(temp("none.jsonl").c_str(), F_OK), -1) << "no output opened";
}

// The decoder's report shows what its final view shows beyond the tau table: the model's terms
// beyond the five (the demo's second gyro gets a Markov term over an hour) and the latest window's
// dynamic ADEV. Oracle: the final view of the same log, printed to 4 significant digits.
TEST(AcceptanceCli, DecoderReportHasTheViewsModelAndWindow) {
  const std::string log = temp("demo_window.log"), report = temp("decode_window.html");
  Outcome r = run_shell(demo + " --hours 1 --window 10 --view-every 0 --csv '' --plot '' --candump " + log + " > /dev/null");
  ASSERT_EQ(r.code, 0) << r.err;
  r = run_shell(decode + " " + log + " --view final --report " + report);
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string html = slurp(report);
  // The table with `id`: its cells' exact values, row by row (an empty cell: NaN).
  const auto table = [&](const std::string& id) {
    std::vector<std::vector<double>> rows;
    const std::size_t from = html.find("<table id=\"" + id + "\">");
    if (from == std::string::npos) return rows;
    const std::string body = html.substr(from, html.find("</table>", from) - from);
    const std::regex row_re("<tr><td.*?</tr>"), cell_re(R"re(<td( data-value="([^"]*)")?[^>]*>)re");
    for (auto it = std::sregex_iterator(body.begin(), body.end(), row_re); it != std::sregex_iterator(); ++it) {
      const std::string row = it->str();
      std::vector<double> cells;
      for (auto c = std::sregex_iterator(row.begin(), row.end(), cell_re); c != std::sregex_iterator(); ++c)
        cells.push_back((*c)[2].matched ? std::stod((*c)[2]) : NAN);
      rows.push_back(cells);
    }
    return rows;
  };
  // The view: per node, its "model:" line and its "dynamic ADEV" line.
  std::vector<std::string> model_lines, window_lines;
  for (std::size_t at = 0; (at = r.out.find('\n', at)) != std::string::npos; ++at) {
    const std::string line = r.out.substr(at + 1, r.out.find('\n', at + 1) - at - 1);
    if (line.rfind("  model:", 0) == 0) model_lines.push_back(line);
    if (line.rfind("  dynamic ADEV:", 0) == 0) window_lines.push_back(line);
  }
  ASSERT_EQ(window_lines.size(), 2u) << r.out;
  std::size_t markov_seen = 0;
  for (std::size_t k = 0; k < 2; ++k) {
    const std::string id = k == 0 ? "node-10" : "node-11";
    // The latest window's ADEVs, as the view prints them (%.3e).
    std::vector<double> shown;
    const std::regex value_re(R"re( ([0-9.]+e[-+][0-9]+))re");
    const std::string tail = window_lines[k].substr(window_lines[k].rfind("]:"));
    for (auto it = std::sregex_iterator(tail.begin(), tail.end(), value_re); it != std::sregex_iterator(); ++it)
      shown.push_back(std::stod((*it)[1]));
    const auto rows = table(id + "-window");
    ASSERT_EQ(rows.size(), shown.size()) << id << ": " << window_lines[k];
    for (std::size_t i = 0; i < rows.size(); ++i)
      EXPECT_NEAR(rows[i][1], shown[i], 5e-4 * shown[i]) << id << " window tau " << i;
    // Each Markov term's sigma and Tc, as the view prints them (%.4g).
    std::smatch m;
    const std::regex markov_re(R"re(Markov 1: sigma ([0-9.e+-]+) \S+ .*?Tc ([0-9.e+-]+) s)re");
    if (k < model_lines.size() && std::regex_search(model_lines[k], m, markov_re)) {
      const auto model = table(id + "-model");
      ASSERT_GE(model.size(), 2u) << id << ": " << model_lines[k];
      EXPECT_NEAR(model[0][1], std::stod(m[1]), 5e-4 * std::stod(m[1])) << id << " Markov sigma";
      EXPECT_NEAR(model[1][1], std::stod(m[2]), 5e-4 * std::stod(m[2])) << id << " Markov Tc";
      ++markov_seen;
    }
  }
  EXPECT_GE(markov_seen, 1u) << "the demo's second gyro has a Markov term after an hour:\n" << r.out;
}

}  // namespace
