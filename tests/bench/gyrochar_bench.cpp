// gyrochar-bench: the bench's judge, run by the scenarios inside the QEMU guest
// (tests/bench/scenarios, docs/bench.md). It reads what gyrochar-decode recorded from a real
// (emulated) CAN interface and what gyrochar-analyze computed offline, and says whether they agree.
//
//   gyrochar-bench link --jsonl decoded.jsonl --node 17 --node 18 [--expect-gap] [--min-reports 5]
//     Every node was decoded; without --expect-gap no report was lost or incomplete (the last one
//     may be cut by the end of the recording), no restart, no offline event, no rejected frame,
//     and the nodes counted no sample gap or lost edge. With --expect-gap: the link went away
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
// Output: one line per node on stdout; problems as `gyrochar-bench: what: why` on stderr.
// Exit codes: 0 agree, 1 disagree, 2 bad options or unreadable input.
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <cmath>
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
      const std::uint64_t before = reports.empty() ? 0 : reports.back().line["health"]["reports_complete"].get<std::uint64_t>();
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
         " restarts, " + std::to_string(health(r, "offline_events")) + " offline events, " +
         std::to_string(rejected(r)) + " rejected; node faults: " + std::to_string(fault(r, "sample_gaps")) +
         " sample gaps, " + std::to_string(fault(r, "lost_edges")) + " lost edges, " +
         std::to_string(fault(r, "tx_dropped_frames")) + " tx dropped frames";
}

int check_link(const std::string& jsonl, const std::vector<unsigned>& wanted, bool expect_gap, unsigned min_reports) {
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
      if (fault(last, "sample_gaps") != 0 || fault(last, "lost_edges") != 0)
        problem(node, "the node counted sample gaps or lost edges in its input");
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
    std::printf("node %u: gap at report %zu of %zu (%.3f s after the first): %llu reports lost, %llu offline events; "
                "%zu complete reports after it\n",
                node, gap + 1, reports.size(),
                reports[gap].line["time_s"].get<double>() - reports[0].line["time_s"].get<double>(),
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
      std::fprintf(stderr, "gyrochar-bench: node %u: %s m=%llu: decoded %.9g arcsec/s, gyrochar-analyze %.9g (float32 %.9g)\n",
                   node, stat.c_str(), static_cast<unsigned long long>(m), decoded, oracle_arcsec_s,
                   static_cast<double>(want));
      result = exit_disagree;
    }
    ++compared;
    m_max = std::max(m_max, m);
  }
  if (compared == 0) bad_input(analyzed, "no oadev or mdev row");
  std::printf("node %u: report seq %u with %llu samples: %zu ADEV/MDEV values (m = 1..%llu) %s gyrochar-analyze's in float32 "
              "(largest relative difference before rounding %.2g); the CSV holds the same values\n",
              node, seq, static_cast<unsigned long long>(samples), compared, static_cast<unsigned long long>(m_max),
              result == exit_agree ? "equal" : "differ from", worst);
  return result;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"gyrochar-bench: checks gyrochar-decode recordings made on the bench (docs/bench.md).", "gyrochar-bench"};
  app.require_subcommand(1);
  app.footer("Exit codes: 0 agree, 1 disagree, 2 bad options or unreadable input.");

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
  CLI::App* estimates = app.add_subcommand("estimates", "decoded ADEV and MDEV against gyrochar-analyze");
  estimates->add_option("--jsonl", jsonl, "gyrochar-decode --jsonl recording (--rate-unit native)")->required();
  estimates->add_option("--csv", csv, "gyrochar-decode --csv recording of the same run")->required();
  estimates->add_option("--node", node, "node address")->required();
  estimates->add_option("--samples", samples, "samples the node must have counted")->required();
  estimates->add_option("--analyzed", analyzed, "gyrochar-analyze --format csv --rate-unit deg/s output")->required();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    std::fprintf(stderr, "gyrochar-bench: options: %s (see --help)\n", e.what());
    return exit_bad_input;
  }
  if (*link) return check_link(jsonl, nodes, expect_gap, min_reports);
  return check_estimates(jsonl, csv, node, samples, analyzed);
}
