// gyrochar-decode as a user meets it, on candump logs this test writes with the codec
// (protocol::encode + format_candump_line). Oracle: the values the test encoded (exact in the node's
// own unit; unit conversions are closed forms: 1 rad = 180/pi deg, 1 h = 3600 s), the confidence
// intervals of confidence.hpp (Boost.Math chi-squared, NIST SP 1065 eq. 45), and the frames the
// test removed, reordered or mangled on purpose; exit codes and messages: the CLI contract in --help.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "candump.hpp"
#include "confidence.hpp"
#include "gyrochar/wire/protocol.hpp"
#include "hal/program/exit_codes.hpp"
#include "support/shell.hpp"

namespace gyrochar {
namespace {

using namespace protocol;
using Json = nlohmann::json;

const std::string tool = GYROCHAR_BINARY_DIR "/host_tools/gyrochar-decode";
constexpr double rad_to_deg = 180.0 / std::numbers::pi;

// ---------------------------------------------------------------------------------------------
// Running the program

struct Outcome {
  int code = -1;
  std::string out, err;
};

// Per-process names: CTest runs the tests of this file in parallel processes.
std::string temp(const std::string& name) { return gyrochar::test_support::temp_path("decode_" + name); }

Outcome run(const std::string& args) {
  const std::string err_file = temp("stderr.txt");
  Outcome r;
  FILE* p = popen((tool + " " + args + " 2>" + err_file).c_str(), "r");
  char buf[4096];
  while (std::size_t n = fread(buf, 1, sizeof buf, p)) r.out.append(buf, n);
  const int status = pclose(p);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream e(err_file);
  r.err.assign(std::istreambuf_iterator<char>(e), {});
  return r;
}

std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

// ---------------------------------------------------------------------------------------------
// The nodes' values: simple functions of (node, report, tau), so every row has a known answer

struct NodeSpec {
  std::uint8_t address = 0x10;
  std::uint8_t taus = 6;
  AngleUnit unit = AngleUnit::arcsec;
  float tau0_s = 0.01f;
  std::uint8_t protocol_version = version;  // 1: no fit summary, no Fitted flag
  Ieee952Status fit = Ieee952Status::ok;
  bool quantization_white = true;  // false: AVAR below 8 tau0, MVAR below 4 tau0 left out
  float unconstrained_n = 0;       // > 0: N's unconstrained estimate (version 5), uncertainty 12.5 %
};

float adev_of(const NodeSpec& n, std::uint8_t seq, std::size_t i) {
  return 0.25f * static_cast<float>(n.address) / static_cast<float>(1 + i) + 0.001f * static_cast<float>(seq);
}
float mdev_of(const NodeSpec& n, std::uint8_t seq, std::size_t i) { return 0.75f * adev_of(n, seq, i); }
double edf_of(std::size_t i) { return std::ldexp(1.0, static_cast<int>(i) + 1); }  // 2^k: exact on the wire
NoiseType noise_of(std::size_t i) { return static_cast<NoiseType>(1 + i % 7); }
std::uint64_t n_of(std::uint8_t seq, std::size_t i) { return 1000u * (seq + 1u) + i; }
std::uint64_t m_of(std::size_t i) { return std::uint64_t{1} << i; }
float ieee_of(std::size_t k) { return 0.001f * static_cast<float>(k + 1); }
bool ieee_resolved(std::size_t k) { return k != 4; }             // R not resolved
constexpr float markov_sigma_of = 0.004f, markov_tc_of = 20.0f;  // angle unit/s, s
float chi2_per_dof_of(const NodeSpec& n) { return n.fit == Ieee952Status::rejected ? 7.5f : 0.75f; }

Message message(const NodeSpec& n, std::uint8_t seq, ReportSlot s, std::uint64_t samples) {
  switch (s.slot) {
    case Slot::status: return StatusMsg{seq, NodeState::running, n.taus, samples};
    case Slot::faults: return StatusFaultsMsg{seq, 1, 2, 3, 0};
    case Slot::adev:
      return TauDevMsg{seq, s.index, DevKind::adev, adev_of(n, seq, s.index), edf_of(s.index), noise_of(s.index), true};
    case Slot::mdev:
      return TauDevMsg{seq, s.index, DevKind::mdev, mdev_of(n, seq, s.index), edf_of(s.index), noise_of(s.index), true};
    case Slot::terms: return TauTermsMsg{seq, s.index, n_of(seq, s.index)};
    case Slot::tau_info: return TauInfoMsg{seq, s.index, m_of(s.index), 0};
    case Slot::sampling: return MetaSamplingMsg{seq, n.tau0_s, 8};
    case Slot::clock: return MetaClockMsg{seq, samples * 10, n.protocol_version};
    case Slot::scale: return MetaScaleMsg{seq, 1.0f, n.unit, InputSource::simulated};
    case Slot::config: return MetaConfigMsg{seq, 0xC0FFEEu, 1000};
    case Slot::ieee952: {
      if (s.index == ieee952_summary_page) {
        const std::array<std::uint8_t, 2> left_out = n.quantization_white ? std::array<std::uint8_t, 2>{0, 0}
                                                                          : std::array<std::uint8_t, 2>{3, 2};
        return Ieee952SummaryMsg{seq, n.fit, chi2_per_dof_of(n), 10, n.quantization_white, left_out};
      }
      // A rejected fit resolves nothing; its terms are still in the model. Q is held, not fitted,
      // where quantization is not white.
      const bool held = s.index == 0 && !n.quantization_white;
      const bool fitted = n.protocol_version >= 2 && ieee_resolved(s.index) && !held;
      return Ieee952Msg{seq,
                        static_cast<Ieee952Term>(s.index),
                        ieee_resolved(s.index) && n.fit == Ieee952Status::ok && !held,
                        held ? 0.0f : ieee_of(s.index),
                        held ? 0.0 : 0.125,
                        fitted};
    }
    case Slot::window:  // these nodes have no window taus
    case Slot::window_length:
    case Slot::window_dev: break;
    case Slot::fit_model:  // version 4: the model holds one Markov term
      return Ieee952ModelMsg{seq, 1, 0, false, 0, true, 0, 0, false, 4.5f};
    case Slot::fit_parameter: {
      const FitParameterSlot p = fit_parameter_slot(s.index);
      if (p.index == 0 && p.parameter == FitParameter::markov_sigma)
        return Ieee952ParameterMsg{seq, p.parameter, 0, n.fit == Ieee952Status::ok, markov_sigma_of, 0.125};
      if (p.index == 0 && p.parameter == FitParameter::markov_tc)
        return Ieee952ParameterMsg{seq, p.parameter, 0, false, markov_tc_of, 0.25};
      return Ieee952ParameterMsg{seq, p.parameter, p.index, false, 0.0f, 0.0};
    }
    case Slot::unconstrained:  // version 5: N's unconstrained estimate where the spec gives one
      if (s.index == 1 && n.unconstrained_n > 0)
        return Ieee952UnconstrainedMsg{seq, Ieee952Term::angle_random_walk, n.unconstrained_n, 0.125 * n.unconstrained_n};
      return Ieee952UnconstrainedMsg{seq, static_cast<Ieee952Term>(s.index), 0.0f, 0.0};
  }
  return {};
}

// What a closed report must produce: the oracle of its rows.
struct Expected {
  std::uint8_t node = 0, seq = 0;
  std::uint32_t session = 0;
  std::vector<std::uint64_t> m, n;  // latest received, 0 = unknown
  std::vector<bool> adev, mdev;     // received in this report
};

// Writes a candump log: frames of several nodes, each report paced over one second, lines sorted
// by time; keeps the oracle of every report it wrote.
class LogWriter {
 public:
  using Drop = std::function<bool(const ReportSlot&)>;

  /// Report `seq` of node `n` starting at t_s; frames for which `drop` is true are left out.
  void report(const NodeSpec& n, std::uint8_t seq, double t_s, std::uint64_t samples, const Drop& drop = {}) {
    State& st = state_[n.address];
    st.m.resize(n.taus);
    st.n.resize(n.taus);
    Expected e{n.address, seq, st.session, {}, {}, std::vector<bool>(n.taus), std::vector<bool>(n.taus)};
    const std::size_t frames = report_frame_count(seq, n.taus, n.protocol_version);
    for (std::size_t k = 0; k < frames; ++k) {
      const ReportSlot s = report_slot(seq, n.taus, k, n.protocol_version);
      if (drop && drop(s)) continue;
      CanFrame f;
      EXPECT_EQ(encode(message(n, seq, s, samples), n.address, f), ProtocolError::none);
      lines_.emplace_back(t_s + static_cast<double>(k) / static_cast<double>(frames), format_candump_line(0, "can0", f));
      if (s.slot == Slot::adev) e.adev[s.index] = true;
      if (s.slot == Slot::mdev) e.mdev[s.index] = true;
      if (s.slot == Slot::terms) st.n[s.index] = n_of(seq, s.index);
      if (s.slot == Slot::tau_info) st.m[s.index] = m_of(s.index);
    }
    e.m = st.m;
    e.n = st.n;
    expected_.push_back(e);
  }
  /// The node restarted: the decoder forgets its tau table and counts a new session.
  void restart(std::uint8_t node) {
    State& st = state_[node];
    ++st.session;
    std::fill(st.m.begin(), st.m.end(), 0);
    std::fill(st.n.begin(), st.n.end(), 0);
  }
  void raw(double t_s, const std::string& line) { lines_.emplace_back(t_s, line); }

  /// The log text: lines by time, timestamps put in (raw lines as given).
  std::string text() const {
    std::vector<std::pair<double, std::string>> sorted = lines_;
    std::stable_sort(sorted.begin(), sorted.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    std::string s;
    for (const auto& [t, line] : sorted) {
      // format_candump_line() was called with time 0: replace its "(0.000000)" by the real time.
      s += line.rfind("(0.000000) ", 0) == 0 ? fmt_time(t) + line.substr(10) : line;
      s += '\n';
    }
    return s;
  }
  std::string write(const std::string& name) const {
    const std::string path = temp(name);
    std::ofstream(path, std::ios::binary) << text();
    return path;
  }
  const std::vector<Expected>& expected() const { return expected_; }

 private:
  static std::string fmt_time(double t) {
    char b[64];
    std::snprintf(b, sizeof b, "(%.6f)", t);
    return b;
  }
  struct State {
    std::uint32_t session = 0;
    std::vector<std::uint64_t> m, n;
  };
  std::map<std::uint8_t, State> state_;
  std::vector<Expected> expected_;
  std::vector<std::pair<double, std::string>> lines_;
};

// ---------------------------------------------------------------------------------------------
// Reading the CSV

struct Csv {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
  std::size_t col(const std::string& name) const {
    const auto it = std::find(header.begin(), header.end(), name);
    EXPECT_NE(it, header.end()) << name;
    return static_cast<std::size_t>(it - header.begin());
  }
  const std::string& get(const std::vector<std::string>& row, const std::string& name) const { return row.at(col(name)); }
};

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> fields;
  std::stringstream ss(line);
  std::string f;
  while (std::getline(ss, f, ',')) fields.push_back(f);
  if (!line.empty() && line.back() == ',') fields.emplace_back();
  return fields;
}

Csv read_csv(const std::string& path) {
  Csv csv;
  std::ifstream in(path);
  std::string line;
  if (std::getline(in, line)) csv.header = split(line);
  while (std::getline(in, line)) {
    csv.rows.push_back(split(line));
    EXPECT_EQ(csv.rows.back().size(), csv.header.size()) << line;
  }
  return csv;
}

std::vector<Json> read_jsonl(const std::string& path) {
  std::vector<Json> records;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) records.push_back(Json::parse(line));
  return records;
}

const Expected* find_expected(const LogWriter& log, std::uint8_t node, std::uint8_t seq, std::uint32_t session) {
  for (const Expected& e : log.expected())
    if (e.node == node && e.seq == seq && e.session == session) return &e;
  return nullptr;
}

// Checks one CSV row against the oracle; `rate` converts the node's unit/s into the shown unit.
void expect_row(const Csv& csv, const std::vector<std::string>& row, const LogWriter& log,
                const std::map<std::uint8_t, NodeSpec>& nodes, double rate) {
  const auto node = static_cast<std::uint8_t>(std::stoi(csv.get(row, "node")));
  const auto seq = static_cast<std::uint8_t>(std::stoi(csv.get(row, "seq")));
  const auto session = static_cast<std::uint32_t>(std::stoul(csv.get(row, "session")));
  const std::size_t i = std::stoul(csv.get(row, "tau_index"));
  const Expected* e = find_expected(log, node, seq, session);
  ASSERT_NE(e, nullptr) << "row of a report the log does not hold: node " << int(node) << " seq " << int(seq);
  ASSERT_LT(i, e->m.size());
  const NodeSpec& n = nodes.at(node);
  SCOPED_TRACE(testing::Message() << "node " << int(node) << " seq " << int(seq) << " tau " << i);
  EXPECT_EQ(csv.get(row, "m"), e->m[i] ? std::to_string(e->m[i]) : "");
  EXPECT_EQ(csv.get(row, "n"), e->n[i] ? std::to_string(e->n[i]) : "");
  if (e->m[i]) EXPECT_FLOAT_EQ(std::stof(csv.get(row, "tau_s")), n.tau0_s * static_cast<float>(e->m[i]));
  else EXPECT_EQ(csv.get(row, "tau_s"), "");
  for (const auto& [kind, received, value] : {std::tuple{std::string("adev"), bool(e->adev[i]), adev_of(n, seq, i)},
                                              std::tuple{std::string("mdev"), bool(e->mdev[i]), mdev_of(n, seq, i)}}) {
    if (!received) {
      EXPECT_EQ(csv.get(row, kind + "_status"), "missing");
      EXPECT_EQ(csv.get(row, kind), "");
      EXPECT_EQ(csv.get(row, kind + "_low"), "");
      continue;
    }
    const double want = static_cast<double>(value) * rate;
    EXPECT_EQ(csv.get(row, kind + "_status"), "ok");
    EXPECT_NEAR(std::stod(csv.get(row, kind)), want, 1e-14 * want);
    const Interval ci = confidence_interval(want, edf_of(i), 0.683);
    ASSERT_TRUE(ci.valid);
    EXPECT_NEAR(std::stod(csv.get(row, kind + "_low")), ci.low, 1e-12 * ci.low);
    EXPECT_NEAR(std::stod(csv.get(row, kind + "_high")), ci.high, 1e-12 * ci.high);
    EXPECT_EQ(std::stod(csv.get(row, kind + "_edf")), edf_of(i));
    EXPECT_EQ(csv.get(row, kind + "_noise"), name(noise_of(i)));
  }
}

// ---------------------------------------------------------------------------------------------

// Two nodes of different units, tau0 and tau counts, and nine complete reports of each, node
// 0x2A's 0.3 s after 0x10's.
const std::map<std::uint8_t, NodeSpec> two_nodes{{0x10, {0x10, 6, AngleUnit::arcsec, 0.01f}},
                                                 {0x2A, {0x2A, 4, AngleUnit::rad, 0.5f}}};
LogWriter nine_reports() {
  LogWriter log;
  for (std::uint8_t seq = 0; seq < 9; ++seq)
    for (const auto& [address, n] : two_nodes) log.report(n, seq, 1000.0 + seq + 0.3 * (address == 0x2A), 100u * (seq + 1));
  return log;
}

TEST(DecodeCli, CsvAndJsonLinesCarryTheEncodedValuesOfEveryNode) {
  const std::map<std::uint8_t, NodeSpec>& nodes = two_nodes;
  const LogWriter log = nine_reports();
  const std::string csv_path = temp("values.csv"), jsonl_path = temp("values.jsonl");
  const Outcome r = run(log.write("values.log") + " --view none --rate-unit native --csv " + csv_path + " --jsonl " +
                        jsonl_path);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(r.out.empty()) << "--view none writes nothing on stdout";

  const Csv csv = read_csv(csv_path);
  ASSERT_EQ(csv.rows.size(), 9u * 6 + 9u * 4);  // one row per node, report and tau
  for (const auto& row : csv.rows) {
    expect_row(csv, row, log, nodes, 1.0);  // native: exactly the float on the wire
    const bool arcsec = csv.get(row, "node") == "16";
    EXPECT_EQ(csv.get(row, "rate_unit"), arcsec ? "arcsec/s" : "rad/s");
    EXPECT_EQ(csv.get(row, "ci_level"), "0.683");
    // Version 4: the fit's model from the summary's slow cycle (the first summary closes report 3).
    const bool summary = std::stoi(csv.get(row, "seq")) >= 3;
    EXPECT_EQ(csv.get(row, "fit_model"), summary ? "shown" : "");
    EXPECT_EQ(csv.get(row, "fit_markov_terms"), summary ? "1" : "");
    EXPECT_EQ(csv.get(row, "fit_filter"), summary ? "false" : "");
    if (summary) {  // native: the float on the wire
      EXPECT_EQ(std::stod(csv.get(row, "markov1_sigma")), static_cast<double>(markov_sigma_of));
    } else {
      EXPECT_EQ(csv.get(row, "markov1_sigma"), "");
    }
    EXPECT_EQ(csv.get(row, "markov1_sigma_resolved"), summary ? "true" : "");
    EXPECT_EQ(csv.get(row, "markov1_tc_s"), summary ? "20" : "");
    EXPECT_EQ(csv.get(row, "markov1_tc_s_rel_uncertainty"), summary ? "0.25" : "");
    EXPECT_EQ(csv.get(row, "markov2_sigma"), "");  // not in the model
    EXPECT_EQ(csv.get(row, "filter_tf_s"), "");
    EXPECT_EQ(csv.get(row, "sinusoid1_frequency_hz"), "");
  }

  std::size_t taus = 0, reports = 0, summaries = 0;
  for (const Json& j : read_jsonl(jsonl_path)) {
    const std::string type = j.at("type");
    if (type == "tau") {
      ++taus;
      const NodeSpec& n = nodes.at(j.at("node").get<std::uint8_t>());
      const auto seq = j.at("seq").get<std::uint8_t>();
      const std::size_t i = j.at("tau_index");
      EXPECT_EQ(j.at("adev").at("value").get<double>(), static_cast<double>(adev_of(n, seq, i)));
      EXPECT_EQ(j.at("mdev").at("value").get<double>(), static_cast<double>(mdev_of(n, seq, i)));
      EXPECT_EQ(j.at("mdev").at("edf").get<double>(), edf_of(i));
      EXPECT_EQ(j.at("adev").at("noise"), name(noise_of(i)));
    } else if (type == "report") {
      ++reports;
      EXPECT_EQ(j.at("faults").at("lost_edges"), 1);
      EXPECT_EQ(j.at("faults").at("sample_gaps"), 2);
      EXPECT_EQ(j.at("faults").at("tx_dropped_frames"), 3);
      EXPECT_EQ(j.at("sample_count"), 100 * (j.at("seq").get<int>() + 1));
    } else if (type == "summary") {
      ++summaries;
      EXPECT_EQ(j.at("malformed_lines"), 0);
      EXPECT_EQ(j.at("rejected_frames"), 0);
      ASSERT_EQ(j.at("nodes").size(), 2u);
      for (const Json& node : j.at("nodes")) {
        EXPECT_EQ(node.at("health").at("reports_complete"), 9);
        EXPECT_EQ(node.at("health").at("frames_missing"), 0);
      }
    }
  }
  EXPECT_EQ(taus, csv.rows.size());
  EXPECT_EQ(reports, 18u);
  EXPECT_EQ(summaries, 1u);
}

// --limits: the verdict columns of every tau row and the JSON lines acceptance records written when
// a verdict changes. Oracles: the values encoded (N = 0.002 A/sqrt(s) with a relative uncertainty of
// 12.5 %, A = arcsec for node 0x10 and rad for 0x2A; 1 arcsec/sqrt(s) = 1/60 deg/sqrt(h), 1 rad =
// 180/pi deg, 1 arcsec/s = 1 deg/h), the decision rule of limits.hpp (value -+ 1.959964 u; a
// deviation's two-sided 95 % chi-squared interval of confidence.hpp), and the node's fit summary,
// which first arrives in report 3: before it N is undecided.
TEST(DecodeCli, LimitsAddVerdictColumnsAndRecordsWhenAVerdictChanges) {
  const std::map<std::uint8_t, NodeSpec>& nodes = two_nodes;
  const LogWriter log = nine_reports();
  const std::string limits = temp("limits.txt"), csv_path = temp("limits.csv"), jsonl_path = temp("limits.jsonl"),
                    plain_path = temp("plain.csv");
  // N: 3.3e-5 deg/sqrt(h) for 0x10 (pass), 6.9 deg/sqrt(h) for 0x2A (fail). adev(0.04 s): tau 2 of
  // 0x10 (m = 4), 1.33 deg/h with EDF 8 (pass); 0x2A has no such tau (undecided).
  std::ofstream(limits) << "N <= 1e-4 deg/sqrt(h)\nadev(0.04 s) <= 10 deg/h\n";
  const std::string log_path = log.write("limits.log");
  const Outcome r = run(log_path + " --view none --limits " + limits + " --csv " + csv_path + " --jsonl " + jsonl_path);
  ASSERT_EQ(r.code, 0) << r.err;
  ASSERT_EQ(run(log_path + " --view none --csv " + plain_path).code, 0);

  const Csv csv = read_csv(csv_path);
  const std::vector<std::string> added{"verdict",
                                       "N limit [deg/sqrt(h)]",
                                       "N verdict",
                                       "N estimate [deg/sqrt(h)]",
                                       "N lower",
                                       "N upper",
                                       "N estimate kind",
                                       "adev(0.04 s) limit [deg/h]",
                                       "adev(0.04 s) verdict",
                                       "adev(0.04 s) estimate [deg/h]",
                                       "adev(0.04 s) lower",
                                       "adev(0.04 s) upper"};
  const Csv plain = read_csv(plain_path);
  ASSERT_EQ(csv.header.size(), plain.header.size() + added.size());
  EXPECT_TRUE(std::equal(added.begin(), added.end(), csv.header.end() - static_cast<long>(added.size())));
  ASSERT_EQ(csv.rows.size(), plain.rows.size());
  // Per node, the verdict pairs (N, adev) of its reports in order: each change is a record.
  std::map<int, std::vector<std::pair<std::string, std::string>>> changes;
  for (std::size_t k = 0; k < csv.rows.size(); ++k) {
    const auto& row = csv.rows[k];
    EXPECT_TRUE(std::equal(plain.rows[k].begin(), plain.rows[k].end(), row.begin())) << "the same row, columns added";
    const int node = std::stoi(csv.get(row, "node")), seq = std::stoi(csv.get(row, "seq"));
    const bool arcsec = node == 0x10;
    SCOPED_TRACE(testing::Message() << "node " << node << " seq " << seq << " tau " << csv.get(row, "tau_index"));
    // N: on every tau row; decided once the summary (report 3) says the fit is ok.
    EXPECT_EQ(csv.get(row, "N limit [deg/sqrt(h)]"), "0.0001");
    const std::string n_verdict = seq < 3 ? "undecided" : arcsec ? "pass" : "fail";
    EXPECT_EQ(csv.get(row, "N verdict"), n_verdict);
    if (seq >= 3) {
      const double n = static_cast<double>(ieee_of(1)) * (arcsec ? 1.0 / 60.0 : rad_to_deg * 60.0);
      EXPECT_NEAR(std::stod(csv.get(row, "N estimate [deg/sqrt(h)]")), n, 1e-12 * n);
      EXPECT_NEAR(std::stod(csv.get(row, "N lower")), n * (1 - 1.959963984540054 * 0.125), 1e-12 * n);
      EXPECT_NEAR(std::stod(csv.get(row, "N upper")), n * (1 + 1.959963984540054 * 0.125), 1e-12 * n);
      EXPECT_EQ(csv.get(row, "N estimate kind"), "shown") << "these nodes send no unconstrained estimate";
    } else {
      EXPECT_EQ(csv.get(row, "N estimate [deg/sqrt(h)]"), "");
      EXPECT_EQ(csv.get(row, "N estimate kind"), "");
    }
    // adev(0.04 s): only on the row of that tau, once its m is known.
    const bool at_tau = arcsec && csv.get(row, "tau_index") == "2" && csv.get(row, "m") == "4";
    EXPECT_EQ(csv.get(row, "adev(0.04 s) limit [deg/h]"), at_tau ? "10" : "");
    EXPECT_EQ(csv.get(row, "adev(0.04 s) verdict"), at_tau ? "pass" : "");
    if (at_tau) {
      const double dev = static_cast<double>(adev_of(nodes.at(0x10), static_cast<std::uint8_t>(seq), 2));
      const Interval ci = confidence_interval(dev, edf_of(2), 0.95);
      EXPECT_NEAR(std::stod(csv.get(row, "adev(0.04 s) estimate [deg/h]")), dev, 1e-12 * dev);
      EXPECT_NEAR(std::stod(csv.get(row, "adev(0.04 s) lower")), ci.low, 1e-12 * dev);
      EXPECT_NEAR(std::stod(csv.get(row, "adev(0.04 s) upper")), ci.high, 1e-12 * dev);
    }
    // The node's verdict: 0x2A fails N; 0x10 passes both once the fit and tau 2's m are known.
    const Expected* e = find_expected(log, static_cast<std::uint8_t>(node), static_cast<std::uint8_t>(seq), 0);
    ASSERT_NE(e, nullptr);
    const bool tau2_known = e->m.size() > 2 && e->m[2] != 0;
    EXPECT_EQ(csv.get(row, "verdict"), seq < 3 ? "undecided" : !arcsec ? "fail" : tau2_known ? "pass" : "undecided");
    if (csv.get(row, "tau_index") == "2") {
      auto& c = changes[node];
      const std::pair<std::string, std::string> now{n_verdict, csv.get(row, "adev(0.04 s) verdict")};
      if (c.empty() || c.back() != now) c.push_back(now);
    }
  }
  // The JSON lines: a record at each change (the first report too), then one final record a node.
  std::map<int, std::vector<Json>> records;
  for (const Json& j : read_jsonl(jsonl_path))
    if (j.at("type") == "acceptance") records[j.at("node").get<int>()].push_back(j);
  for (const auto& [node, list] : records) {
    SCOPED_TRACE(node);
    ASSERT_EQ(list.size(), changes[node].size() + 1);
    for (std::size_t k = 0; k + 1 < list.size(); ++k) {
      EXPECT_EQ(list[k].at("final"), false);
      EXPECT_EQ(list[k].at("limits")[0].at("verdict"), changes[node][k].first);
      if (!changes[node][k].second.empty()) {
        EXPECT_EQ(list[k].at("limits")[1].at("verdict"), changes[node][k].second);
      }
    }
    EXPECT_EQ(list.back().at("final"), true);
    EXPECT_EQ(list.back().at("verdict"), node == 0x10 ? "pass" : "fail");
    EXPECT_GE(list.size(), 3u) << "undecided at report 0, decided at report 3, final";
  }
  EXPECT_EQ(records.size(), 2u);
}

// --limits with a version-5 node that sends N's unconstrained estimate (0.0015 arcsec/sqrt(s), its
// term page showing 0.002) and a version-4 node that cannot: the first is judged by the
// unconstrained estimate, the second by the shown value, and the CSV and JSON lines say which.
// Oracles: the values encoded, 1 arcsec/sqrt(s) = 1/60 deg/sqrt(h), the codec's uncertainty grid
// (log2 in 1/256 steps: within 0.136 % of the 12.5 % sent), the decision rule of limits.hpp.
TEST(DecodeCli, LimitsJudgeTheUnconstrainedEstimateWhereTheNodeSendsIt) {
  NodeSpec sends{0x10, 6, AngleUnit::arcsec, 0.01f};
  sends.unconstrained_n = 0.0015f;
  NodeSpec older{0x2A, 6, AngleUnit::arcsec, 0.01f, 4};
  LogWriter log;
  for (std::uint8_t seq = 0; seq < 5; ++seq) {
    log.report(sends, seq, 1000.0 + seq, 100u * (seq + 1));
    log.report(older, seq, 1000.3 + seq, 100u * (seq + 1));
  }
  const std::string limits = temp("unconstrained_limits.txt"), csv_path = temp("unconstrained.csv"),
                    jsonl_path = temp("unconstrained.jsonl"), plain_path = temp("unconstrained_plain.jsonl");
  std::ofstream(limits) << "N <= 1e-4 deg/sqrt(h)\n";
  const std::string log_path = log.write("unconstrained.log");
  const Outcome r = run(log_path + " --view none --limits " + limits + " --csv " + csv_path + " --jsonl " + jsonl_path);
  ASSERT_EQ(r.code, 0) << r.err;
  const double to_deg_sqrt_h = 1.0 / 60.0;
  const double unconstrained = static_cast<double>(0.0015f) * to_deg_sqrt_h,
               shown = static_cast<double>(ieee_of(1)) * to_deg_sqrt_h;
  const Csv csv = read_csv(csv_path);
  std::size_t judged = 0;
  for (const auto& row : csv.rows) {
    if (std::stoi(csv.get(row, "seq")) < 3) continue;  // the fit summary arrives in report 3
    const bool v5 = csv.get(row, "node") == "16";
    SCOPED_TRACE(csv.get(row, "node"));
    const double n = v5 ? unconstrained : shown, u = 0.125 * n;
    EXPECT_EQ(csv.get(row, "N estimate kind"), v5 ? "unconstrained" : "shown");
    EXPECT_NEAR(std::stod(csv.get(row, "N estimate [deg/sqrt(h)]")), n, 1e-12 * n);
    EXPECT_NEAR(std::stod(csv.get(row, "N upper")), n + 1.959963984540054 * u,
                1.959963984540054 * u * (v5 ? 0.00136 : 1e-12));
    ++judged;
  }
  EXPECT_EQ(judged, 2u * 2 * 6) << "reports 3 and 4 of both nodes, 6 taus each";
  std::map<int, Json> last_acceptance, last_report;
  for (const Json& j : read_jsonl(jsonl_path)) {
    if (j.at("type") == "acceptance") last_acceptance[j.at("node").get<int>()] = j;
    if (j.at("type") == "report") last_report[j.at("node").get<int>()] = j;
  }
  ASSERT_EQ(last_acceptance.size(), 2u);
  EXPECT_EQ(last_acceptance[0x10].at("limits")[0].at("estimate_kind"), "unconstrained");
  EXPECT_EQ(last_acceptance[0x2A].at("limits")[0].at("estimate_kind"), "shown");
  EXPECT_NE(last_acceptance[0x2A].at("limits")[0].at("why").get<std::string>().find("no unconstrained estimate"),
            std::string::npos);
  // The report record carries the estimate as gyrochar-analyze's JSON does, where the node sends it.
  const Json& n5 = last_report[0x10].at("ieee952").at("N");
  ASSERT_TRUE(n5.contains("unconstrained")) << n5.dump();
  EXPECT_NEAR(n5.at("unconstrained").at("value").get<double>(), unconstrained, 1e-12 * unconstrained);
  EXPECT_NEAR(n5.at("unconstrained").at("signed").get<double>(), unconstrained, 1e-12 * unconstrained);
  EXPECT_NEAR(n5.at("unconstrained").at("uncertainty").get<double>(), 0.125 * unconstrained,
              0.00136 * 0.125 * unconstrained);
  EXPECT_FALSE(last_report[0x2A].at("ieee952").at("N").contains("unconstrained"));
}

TEST(DecodeCli, RatesInDegreesPerHourAndPulsesNeverConverted) {
  const std::map<std::uint8_t, NodeSpec> nodes{{0x21, {0x21, 4, AngleUnit::rad, 0.01f}},
                                               {0x22, {0x22, 4, AngleUnit::pulse, 0.01f}}};
  LogWriter log;
  for (std::uint8_t seq = 0; seq < 5; ++seq)
    for (const auto& [address, n] : nodes) log.report(n, seq, 50.0 + seq + 0.5 * (address == 0x22), 100u * (seq + 1));
  const std::string csv_path = temp("units.csv"), jsonl_path = temp("units.jsonl");
  const Outcome r = run(log.write("units.log") + " --view final --csv " + csv_path + " --jsonl " + jsonl_path);
  ASSERT_EQ(r.code, 0) << r.err;
  const Csv csv = read_csv(csv_path);
  ASSERT_EQ(csv.rows.size(), 2u * 5 * 4);
  for (const auto& row : csv.rows) {
    const bool pulses = csv.get(row, "node") == "34";
    EXPECT_EQ(csv.get(row, "rate_unit"), pulses ? "pulse/s" : "deg/h");
    expect_row(csv, row, log, nodes, pulses ? 1.0 : rad_to_deg * 3600.0);  // rad/s -> deg/h
  }
  // IEEE-952 terms of the last report in gyro units; the pulse node's in pulse units.
  Json last_rad, last_pulse;
  for (const Json& j : read_jsonl(jsonl_path))
    if (j.at("type") == "report") (j.at("node") == 0x21 ? last_rad : last_pulse) = j;
  const std::array<double, 5> to_gyro{rad_to_deg * 3600.0, rad_to_deg * 60.0, rad_to_deg * 3600.0,
                                      rad_to_deg * std::pow(3600.0, 1.5), rad_to_deg * 3600.0 * 3600.0};
  const std::array<const char*, 5> letters{"Q", "N", "B", "K", "R"},
      gyro_units{"arcsec", "deg/sqrt(h)", "deg/h", "deg/h/sqrt(h)", "deg/h/h"},
      pulse_units{"pulse", "pulse/sqrt(s)", "pulse/s", "pulse/s/sqrt(s)", "pulse/s/s"};
  for (std::size_t k = 0; k < 5; ++k) {
    const Json& q = last_rad.at("ieee952").at(letters[k]);
    const Json& p = last_pulse.at("ieee952").at(letters[k]);
    EXPECT_EQ(q.at("unit"), gyro_units[k]);
    EXPECT_EQ(p.at("unit"), pulse_units[k]);
    EXPECT_EQ(q.at("resolved"), ieee_resolved(k));
    if (!ieee_resolved(k)) {
      EXPECT_TRUE(q.at("value").is_null());
      continue;
    }
    const double want = static_cast<double>(ieee_of(k)) * to_gyro[k];
    EXPECT_NEAR(q.at("value").get<double>(), want, 1e-14 * want) << letters[k];
    EXPECT_EQ(p.at("value").get<double>(), static_cast<double>(ieee_of(k))) << letters[k];
    EXPECT_DOUBLE_EQ(q.at("rel_uncertainty").get<double>(), 0.125);  // 12.5 % = 1250 steps of 0.01 %
  }
  EXPECT_TRUE(contains(r.out, "node 0x22")) << r.out;
  EXPECT_TRUE(contains(r.out, "rates [pulse/s] (pulses: not converted)")) << r.out;
  EXPECT_TRUE(contains(r.out, "rates [deg/h]")) << r.out;
  EXPECT_TRUE(contains(r.out, "N 0.002 pulse/sqrt(s)")) << r.out;  // as sent: no conversion
  // Version 4: the Markov term in the JSON fit object, in the rate unit, the analyzer's shape.
  const Json& fit = last_rad.at("ieee952_fit");
  EXPECT_EQ(fit.at("model_status"), "shown");
  ASSERT_EQ(fit.at("markov").size(), 1u);
  const Json& sigma = fit.at("markov").at(0).at("sigma");
  const double sigma_deg_h = static_cast<double>(markov_sigma_of) * rad_to_deg * 3600.0;
  EXPECT_NEAR(sigma.at("value").get<double>(), sigma_deg_h, 1e-14 * sigma_deg_h);
  EXPECT_NEAR(sigma.at("uncertainty").get<double>(), 0.125 * sigma_deg_h, 1e-14 * sigma_deg_h);
  EXPECT_EQ(sigma.at("unit"), "deg/h");
  EXPECT_EQ(sigma.at("resolved"), true);
  EXPECT_EQ(fit.at("markov").at(0).at("tc").at("value"), 20.0);
  EXPECT_EQ(fit.at("markov").at(0).at("tc").at("unit"), "s");
  // Its 68 % interval, 20 s exp(+-u / 20 s) (tc_interval(): stated to a factor, as the analyzer's).
  const double tc_u = fit.at("markov").at(0).at("tc").at("uncertainty");
  EXPECT_NEAR(fit.at("markov").at(0).at("tc").at("ci_low").get<double>(), 20.0 * std::exp(-tc_u / 20.0), 1e-12);
  EXPECT_NEAR(fit.at("markov").at(0).at("tc").at("ci_high").get<double>(), 20.0 * std::exp(tc_u / 20.0), 1e-12);
  EXPECT_TRUE(fit.at("sinusoids").empty());
  EXPECT_TRUE(fit.at("bandwidth").is_null());
  EXPECT_EQ(fit.at("runner_up").at("criterion_margin"), 4.5);
  EXPECT_TRUE(contains(r.out, "model:  Markov 1: sigma")) << r.out;
  // Tc sent with 25 %: sd(ln Tc) = 0.25, its 68 % interval 20 s exp(-+0.25) = 15.58 .. 25.68 s.
  EXPECT_TRUE(contains(r.out, "Tc 20 s (68 %: 15.6 .. 25.7 s)")) << r.out;
}

TEST(DecodeCli, ALostModelPageShowsMissingNeverAnotherFitsValue) {
  // Report 4 opens the second slow cycle and loses its Markov Tc page: that cycle's model is not
  // shown once its summary (report 7) has come, in the CSV, the JSON nor the view; the first
  // cycle's model stays shown until then, as it goes with the summary shown.
  const NodeSpec n{0x10, 6, AngleUnit::arcsec, 0.01f};
  LogWriter log;
  for (std::uint8_t seq = 0; seq < 9; ++seq) {
    const LogWriter::Drop drop = [&](const ReportSlot& s) {
      return seq == 4 && s.slot == Slot::fit_parameter && s.index == fit_parameter_position(FitParameter::markov_tc, 0);
    };
    log.report(n, seq, 10.0 + seq, 100u * (seq + 1), drop);
  }
  const std::string csv_path = temp("lost_model.csv"), jsonl_path = temp("lost_model.jsonl");
  const Outcome r = run(log.write("lost_model.log") + " --view final --rate-unit native --csv " + csv_path + " --jsonl " +
                        jsonl_path);
  ASSERT_EQ(r.code, 0) << r.err;
  const Csv csv = read_csv(csv_path);
  for (const auto& row : csv.rows) {
    const int seq = std::stoi(csv.get(row, "seq"));
    const std::string want = seq < 3 ? "" : seq < 7 ? "shown" : "missing";
    EXPECT_EQ(csv.get(row, "fit_model"), want) << "seq " << seq;
    EXPECT_EQ(csv.get(row, "markov1_sigma").empty(), seq < 3 || seq >= 7) << "seq " << seq;
    EXPECT_EQ(csv.get(row, "fit_markov_terms"), seq >= 3 && seq < 7 ? "1" : "") << "seq " << seq;
  }
  Json last;
  for (const Json& j : read_jsonl(jsonl_path))
    if (j.at("type") == "report") last = j;
  EXPECT_EQ(last.at("ieee952_fit").at("model_status"), "missing");
  EXPECT_TRUE(last.at("ieee952_fit").at("markov").is_null());
  EXPECT_TRUE(contains(r.out, "model: missing (this fit's model pages were lost)")) << r.out;
}

/// The part of the terminal view about node `address`.
std::string node_section(const std::string& view, std::uint8_t address) {
  char head[16];
  std::snprintf(head, sizeof head, "\nnode 0x%02X", address);
  const std::size_t begin = view.find(head);
  if (begin == std::string::npos) return "";
  return view.substr(begin, view.find("\nnode 0x", begin + 1) - begin);
}

TEST(DecodeCli, TheFitSummaryIsShownAndRecordedAndAVersionOneNodeHasNone) {
  // Four nodes: an accepted fit with white quantization, a rejected one with short taus left out,
  // a fit that could not be made, and a version-1 node (no summary at all).
  const std::map<std::uint8_t, NodeSpec> nodes{{0x40, {0x40, 5, AngleUnit::arcsec, 0.01f, 2, Ieee952Status::ok, true}},
                                               {0x41,
                                                {0x41, 5, AngleUnit::arcsec, 0.01f, 2, Ieee952Status::rejected, false}},
                                               {0x42,
                                                {0x42, 5, AngleUnit::arcsec, 0.01f, 2, Ieee952Status::too_few_points, true}},
                                               {0x43, {0x43, 5, AngleUnit::arcsec, 0.01f, 1, Ieee952Status::ok, true}}};
  LogWriter log;
  for (std::uint8_t seq = 0; seq < 6; ++seq)
    for (const auto& [address, n] : nodes) log.report(n, seq, 300.0 + seq + 0.1 * (address - 0x40), 100u * (seq + 1));
  const std::string csv_path = temp("fit.csv"), jsonl_path = temp("fit.jsonl"), prefix = temp("fit_plot");
  const Outcome r = run(log.write("fit.log") + " --view final --rate-unit native --csv " + csv_path + " --jsonl " +
                        jsonl_path + " --plot " + prefix);
  ASSERT_EQ(r.code, 0) << r.err;

  // The view.
  const std::string ok = node_section(r.out, 0x40), rejected = node_section(r.out, 0x41), none = node_section(r.out, 0x42),
                    v1 = node_section(r.out, 0x43);
  EXPECT_TRUE(contains(ok, "IEEE-952 (node's fit of both curves, chi2/dof 0.75 on 10 points):  Q 0.001 arcsec (+-12.5%)"))
      << ok;
  EXPECT_TRUE(contains(ok, "  R not fitted")) << ok;
  EXPECT_FALSE(contains(ok, "REJECTED")) << ok;
  EXPECT_FALSE(contains(ok, "quantization not white")) << ok;
  EXPECT_TRUE(contains(rejected, "chi2/dof 7.5 on 10 points")) << rejected;
  EXPECT_TRUE(contains(rejected, "N 0.002 arcsec/sqrt(s) (not resolved, +-12.5%)")) << rejected;
  EXPECT_TRUE(contains(rejected, "\n  MODEL REJECTED: the IEEE-952 terms do not describe this curve\n")) << rejected;
  // tau0 2^3 and tau0 2^2 with tau0 = 0.01 s.
  EXPECT_TRUE(contains(rejected, "\n  quantization not white: short taus left out (AVAR below 0.08 s, MVAR below 0.04 s)"))
      << rejected;
  EXPECT_TRUE(contains(rejected, "Q held at 0.2887 arcsec (pulse weight/sqrt(12))")) << rejected;
  EXPECT_TRUE(contains(none, "IEEE-952 (node's fit of both curves): no fit: too few points (10 points)")) << none;
  EXPECT_TRUE(contains(v1, "  IEEE-952 (node's fit):  Q 0.001 arcsec (+-12.5%)")) << v1;
  EXPECT_TRUE(contains(v1, "  R not resolved")) << v1;
  EXPECT_TRUE(contains(v1, "protocol 1")) << v1;
  EXPECT_FALSE(contains(v1, "chi2/dof")) << v1;

  // Every report of every node is complete: version 1 has no summary frame to miss.
  // 5 taus: 12 fast frames; slow parts of 5, 5, 5 and 4 (version 1) or 5 (version 2) frames.
  EXPECT_TRUE(contains(r.err, "node 0x43: frames 101; reports 6 complete, 0 incomplete, 0 lost; frames missing 0;"))
      << r.err;
  for (const char* node : {"node 0x40", "node 0x41", "node 0x42"})
    EXPECT_TRUE(
        contains(r.err, std::string(node) + ": frames 102; reports 6 complete, 0 incomplete, 0 lost; frames missing 0;"))
        << r.err;

  // The CSV: the summary of the node's latest fit on every row, empty for version 1. The first
  // report (part 0 of the slow cycle) has no summary yet.
  const Csv csv = read_csv(csv_path);
  ASSERT_EQ(csv.rows.size(), 4u * 6 * 5);
  std::size_t with_fit = 0;
  for (const auto& row : csv.rows) {
    const NodeSpec& n = nodes.at(static_cast<std::uint8_t>(std::stoi(csv.get(row, "node"))));
    const int seq = std::stoi(csv.get(row, "seq"));
    if (n.protocol_version == 1 || seq < 3) {
      for (const char* column : {"fit_status", "fit_chi2_per_dof", "fit_points", "fit_quantization_white",
                                 "fit_avar_excluded_below_tau_s", "fit_mvar_excluded_below_tau_s"})
        EXPECT_EQ(csv.get(row, column), "") << column;
      continue;
    }
    ++with_fit;
    EXPECT_EQ(csv.get(row, "fit_status"), name(n.fit));
    EXPECT_EQ(std::stof(csv.get(row, "fit_chi2_per_dof")), chi2_per_dof_of(n));
    EXPECT_EQ(csv.get(row, "fit_points"), "10");
    EXPECT_EQ(csv.get(row, "fit_quantization_white"), n.quantization_white ? "true" : "false");
    const double avar = n.quantization_white ? 0.0 : 8 * static_cast<double>(n.tau0_s);
    const double mvar = n.quantization_white ? 0.0 : 4 * static_cast<double>(n.tau0_s);
    EXPECT_EQ(std::stod(csv.get(row, "fit_avar_excluded_below_tau_s")), avar);
    EXPECT_EQ(std::stod(csv.get(row, "fit_mvar_excluded_below_tau_s")), mvar);
  }
  EXPECT_EQ(with_fit, 3u * 3 * 5);

  // The JSON lines: the report records carry the summary (null for version 1) and each term's
  // Fitted flag, with its value whenever fitted.
  std::map<int, Json> last;
  for (const Json& j : read_jsonl(jsonl_path))
    if (j.at("type") == "report") last[j.at("node").get<int>()] = j;
  ASSERT_EQ(last.size(), 4u);
  EXPECT_TRUE(last[0x43].at("ieee952_fit").is_null());
  EXPECT_EQ(last[0x43].at("ieee952").at("N").at("fitted"), true);  // version 1: resolved, so fitted
  const Json& fit = last[0x41].at("ieee952_fit");
  EXPECT_EQ(fit.at("curve"), "both");
  EXPECT_EQ(fit.at("status"), "rejected");
  EXPECT_EQ(fit.at("chi2_per_dof").get<double>(), 7.5);
  EXPECT_EQ(fit.at("points"), 10);
  EXPECT_EQ(fit.at("quantization_white"), false);
  EXPECT_EQ(fit.at("avar_excluded_below_tau_s").get<double>(), 8 * static_cast<double>(0.01f));  // tau0 2^3
  EXPECT_EQ(fit.at("mvar_excluded_below_tau_s").get<double>(), 4 * static_cast<double>(0.01f));
  const Json& n_term = last[0x41].at("ieee952").at("N");
  EXPECT_EQ(n_term.at("fitted"), true);
  EXPECT_EQ(n_term.at("resolved"), false);
  EXPECT_EQ(n_term.at("value").get<double>(), static_cast<double>(ieee_of(1)));
  EXPECT_EQ(last[0x40].at("ieee952_fit").at("status"), "ok");
  EXPECT_EQ(last[0x40].at("ieee952_fit").at("avar_excluded_below_tau_s").get<double>(), 0.0);
  EXPECT_TRUE(last[0x41].at("ieee952").at("R").at("value").is_null());  // not fitted

  // The plot: the rejected fit is named in the legend (drawn text in the SVG).
  const std::string svg = read_file(prefix + ".svg");
  EXPECT_GT(svg.size(), 1000u);
}

TEST(DecodeCli, LostFramesAndReportsAreShownNeverPaperedOver) {
  const NodeSpec n{0x31, 5, AngleUnit::deg, 0.01f};
  LogWriter log;
  for (std::uint8_t seq = 0; seq < 8; ++seq) {
    if (seq == 5) continue;  // report 5 lost entirely
    log.report(n, seq, 10.0 + seq, 100u * (seq + 1), [&](const ReportSlot& s) {
      return seq == 3 && s.slot == Slot::adev && s.index == 1;  // one ADEV frame lost
    });
  }
  const std::string csv_path = temp("loss.csv"), jsonl_path = temp("loss.jsonl");
  const Outcome r = run(log.write("loss.log") + " --view final --rate-unit deg/s --csv " + csv_path + " --jsonl " +
                        jsonl_path);
  ASSERT_EQ(r.code, 0) << r.err;
  const Csv csv = read_csv(csv_path);
  ASSERT_EQ(csv.rows.size(), 7u * 5);
  std::size_t missing = 0;
  for (const auto& row : csv.rows) {
    expect_row(csv, row, log, {{n.address, n}}, 1.0);  // deg/s from deg/s
    EXPECT_NE(csv.get(row, "seq"), "5");
    missing += csv.get(row, "adev_status") == "missing";
  }
  EXPECT_EQ(missing, 1u);
  EXPECT_TRUE(contains(r.err, "gyrochar-decode: node 0x31: frames")) << r.err;
  EXPECT_TRUE(contains(r.err, "reports 6 complete, 1 incomplete, 1 lost; frames missing 1;")) << r.err;
  EXPECT_TRUE(contains(r.out, "reports 6 complete, 1 incomplete, 1 lost; frames missing 1;")) << r.out;
  const std::vector<Json> records = read_jsonl(jsonl_path);
  ASSERT_FALSE(records.empty());
  const Json& health = records.back().at("nodes").at(0).at("health");
  EXPECT_EQ(health.at("reports_lost"), 1);
  EXPECT_EQ(health.at("frames_missing"), 1);
}

// The row of tau `tau` (as the view prints it) in a node's section of the view; empty if none.
std::string view_row(const std::string& section, const std::string& tau) {
  std::stringstream ss(section);
  for (std::string line; std::getline(ss, line);) {
    std::stringstream words(line);
    std::string first;
    if (words >> first && first == tau) return line;
  }
  return "";
}

std::string e4(double value) {  // the view's format of a deviation: {:.4e}
  char b[32];
  std::snprintf(b, sizeof b, "%.4e", value);
  return b;
}

TEST(DecodeCli, TheTableNeverShowsValuesOfTwoReportsInOneRow) {
  // The MDEV frame of tau 1 of the last report is lost: the table shows that report's ADEV beside
  // "missing", as the CSV says, never the report before's MDEV.
  const NodeSpec n{0x32, 4, AngleUnit::arcsec, 0.01f};
  LogWriter log;
  for (std::uint8_t seq = 0; seq < 6; ++seq)
    log.report(n, seq, 10.0 + seq, 100u * (seq + 1),
               [&](const ReportSlot& s) { return seq == 5 && s.slot == Slot::mdev && s.index == 1; });
  const std::string csv_path = temp("row.csv");
  const Outcome r = run(log.write("row.log") + " --view final --rate-unit native --csv " + csv_path);
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string section = node_section(r.out, n.address);
  // Oracle: the values the test encoded (adev_of, mdev_of); tau of index i is tau0 2^i.
  const std::string row = view_row(section, "0.02");
  ASSERT_FALSE(row.empty()) << section;
  EXPECT_TRUE(contains(row, e4(adev_of(n, 5, 1)))) << row;
  EXPECT_TRUE(contains(row, "missing")) << row;
  EXPECT_FALSE(contains(row, e4(mdev_of(n, 4, 1)))) << "the previous report's MDEV:\n" << row;
  for (const std::string tau : {"0.01", "0.04", "0.08"}) {  // the other rows: the last report, whole
    const std::string other = view_row(section, tau);
    const std::size_t i = tau == "0.01" ? 0 : tau == "0.04" ? 2 : 3;
    EXPECT_TRUE(contains(other, e4(adev_of(n, 5, i))) && contains(other, e4(mdev_of(n, 5, i)))) << other;
    EXPECT_FALSE(contains(other, "missing")) << other;
  }
  const Csv csv = read_csv(csv_path);
  for (const auto& line : csv.rows) {
    if (csv.get(line, "seq") == "5" && csv.get(line, "tau_index") == "1") {
      EXPECT_EQ(csv.get(line, "mdev_status"), "missing");
    }
  }
}

TEST(DecodeCli, MalformedLinesAndRejectedFramesAreCountedAndReportedWithExitZero) {
  const NodeSpec n{0x40, 3, AngleUnit::arcsec, 0.01f};
  LogWriter log;
  for (std::uint8_t seq = 0; seq < 4; ++seq) log.report(n, seq, 20.0 + seq, 100u * (seq + 1));
  std::string text = log.text();
  // Line 1: garbage; after the first report's lines: a bad timestamp and a bad identifier; at the
  // end a frame of the right identifier with 2 data bytes (rejected: wrong_length) and a line cut
  // in the middle of its data (no newline).
  const std::size_t first_report_lines = report_frame_count(0, n.taus);
  std::vector<std::string> lines;
  std::stringstream ss(text);
  for (std::string l; std::getline(ss, l);) lines.push_back(l);
  lines.insert(lines.begin() + static_cast<std::ptrdiff_t>(first_report_lines),
               {"(abc) can0 18FF4140#00", "(24.5) can0 18FZ4140#0000000000000000"});
  lines.insert(lines.begin(), "this is not a candump line");
  lines.push_back("(24.900000) can0 18FF4140#0102");
  std::string body;
  for (const std::string& l : lines) body += l + "\n";
  body += "(24.950000) can0 18FF4140#0102030";
  const std::string path = temp("malformed.log"), csv_path = temp("malformed.csv");
  std::ofstream(path, std::ios::binary) << body;

  const Outcome r = run(path + " --view final --rate-unit native --csv " + csv_path);
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(contains(r.err, "gyrochar-decode: " + path + ":1: malformed line: does not start with a '(timestamp)'\n"))
      << r.err;
  EXPECT_TRUE(contains(r.err, path + ":" + std::to_string(first_report_lines + 2) + ": malformed line: bad timestamp"))
      << r.err;
  EXPECT_TRUE(contains(r.err, path + ":" + std::to_string(first_report_lines + 3) +
                                  ": malformed line: identifier is not hexadecimal"))
      << r.err;
  EXPECT_TRUE(
      contains(r.err, path + ":" + std::to_string(lines.size() + 1) + ": malformed line: odd number of data hex digits"))
      << r.err;
  EXPECT_TRUE(contains(r.err, "4 malformed line(s)")) << r.err;
  EXPECT_TRUE(contains(r.err, "1 rejected frames")) << r.err;
  EXPECT_TRUE(contains(r.err, "rejected 1 (wrong_length 1)")) << r.err;
  EXPECT_TRUE(contains(r.out, "4 malformed line(s)")) << "the view shows them too:\n" << r.out;
  const Csv csv = read_csv(csv_path);
  ASSERT_EQ(csv.rows.size(), 4u * 3);  // every report decoded despite the bad lines
  for (const auto& row : csv.rows) expect_row(csv, row, log, {{n.address, n}}, 1.0);
}

// A remote request (RTR) with a node's Status identifier carries no data: counted and skipped, never
// decoded as a report frame (it would read as a Status of TauCount 0: a restart). A line longer
// than the limit is one malformed line, whatever its length. Oracle: the frames the test wrote.
TEST(DecodeCli, RemoteRequestsAndOverlongLinesAreCountedAndSkipped) {
  const NodeSpec n{0x33, 3, AngleUnit::arcsec, 0.01f};
  LogWriter log;
  for (std::uint8_t seq = 0; seq < 4; ++seq) log.report(n, seq, 20.0 + seq, 100u * (seq + 1));
  log.raw(21.5, "(21.500000) can0 14FF4033#R8");
  log.raw(22.5, "(22.500000) can0 18FF4133#" + std::string(3 << 20, '0'));  // 3 MB of "data"
  const std::string path = log.write("remote.log"), csv_path = temp("remote.csv");
  const Outcome r = run(path + " --view final --rate-unit native --csv " + csv_path);
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(contains(r.err, "malformed line: longer than 1024 bytes\n")) << r.err;
  EXPECT_TRUE(contains(r.err, "1 malformed line(s)")) << r.err;
  EXPECT_TRUE(contains(r.err, "1 remote requests (RTR: no data, not decoded)")) << r.err;
  EXPECT_TRUE(contains(r.err, "reports 4 complete, 0 incomplete, 0 lost; frames missing 0; restarts 0;")) << r.err;
  EXPECT_TRUE(contains(r.err, "rejected 0")) << r.err;
  const Csv csv = read_csv(csv_path);
  ASSERT_EQ(csv.rows.size(), 4u * 3);
  for (const auto& row : csv.rows) expect_row(csv, row, log, {{n.address, n}}, 1.0);
}

TEST(DecodeCli, TruncatedLogClosesItsLastReportWithTheMissingFramesShown) {
  const NodeSpec n{0x41, 4, AngleUnit::arcsec, 0.01f};
  LogWriter log;
  for (std::uint8_t seq = 0; seq < 3; ++seq) log.report(n, seq, 30.0 + seq, 100u * (seq + 1));
  const std::string text = log.text();
  // Cut inside the ADEV frame of tau 2 of the last report: its status, faults and the ADEV and MDEV
  // of taus 0 and 1 survive as whole lines; the cut line (an odd number of hex digits) is malformed.
  const std::size_t frames_before = 2 * report_frame_count(0, n.taus);
  std::size_t pos = 0;
  for (std::size_t k = 0; k < frames_before + 6; ++k) pos = text.find('\n', pos) + 1;  // 6 whole lines of report 2
  const std::string path = temp("truncated.log"), csv_path = temp("truncated.csv");
  std::ofstream(path, std::ios::binary) << text.substr(0, pos + 31);  // "(32.400000) can0 18FF4141#" + 5 digits
  const Outcome r = run(path + " --view none --rate-unit native --csv " + csv_path);
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(contains(r.err, "1 malformed line(s)")) << r.err;
  const Csv csv = read_csv(csv_path);
  ASSERT_EQ(csv.rows.size(), 3u * 4);  // the cut report is closed at the end of the log
  // Report 2 kept status, faults, ADEV/MDEV of tau 0 and 1: taus 2, 3 are missing.
  const std::vector<bool> want_adev{true, true, false, false};
  for (const auto& row : csv.rows) {
    if (csv.get(row, "seq") != "2") continue;
    const std::size_t i = std::stoul(csv.get(row, "tau_index"));
    EXPECT_EQ(csv.get(row, "adev_status"), want_adev[i] ? "ok" : "missing") << i;
    EXPECT_EQ(csv.get(row, "mdev_status"), want_adev[i] ? "ok" : "missing") << i;
  }
}

TEST(DecodeCli, BadInvocationsAreBadInputWithWhatAndWhy) {
  const auto expect_bad = [](const std::string& args, const std::string& first_line, int code = exit_code::bad_input) {
    const Outcome r = run(args);
    EXPECT_EQ(r.code, code) << args << "\n" << r.err;
    EXPECT_EQ(r.err.rfind(first_line, 0), 0u) << "expected '" << first_line << "' first in: " << r.err;
    EXPECT_TRUE(r.out.empty()) << "no data on stdout after an error";
  };
  expect_bad("/nonexistent/capture.log --view none",
             "gyrochar-decode: /nonexistent/capture.log: No such file or directory\n");
  expect_bad("--view none", "gyrochar-decode: options: give either a LOG or --interface");
  expect_bad("x.log --interface can0 --view none", "gyrochar-decode: options: give either a LOG or --interface");
  expect_bad("x.log --frobnicate", "gyrochar-decode: options: ");
  expect_bad("x.log --rate-unit furlong/s", "gyrochar-decode: --rate-unit: 'furlong/s' is not");
  expect_bad("x.log --node 254", "gyrochar-decode: --node: '254' is not a node address");
  expect_bad("x.log --node 0x1G", "gyrochar-decode: --node: '0x1G' is not a node address");
  expect_bad("x.log --confidence 1.5", "gyrochar-decode: --confidence: must be in (0, 1)");
  expect_bad("x.log --view sometimes", "gyrochar-decode: --view: 'sometimes' is not live, final or none");
  expect_bad("x.log --plot-every 10", "gyrochar-decode: --plot-every: needs --plot PREFIX");
  expect_bad("x.log --csv /nonexistent/dir/out.csv", "gyrochar-decode: /nonexistent/dir/out.csv: No such file or directory",
             exit_code::output_failed);
  expect_bad("x.log --plot /nonexistent/dir/plot",
             "gyrochar-decode: /nonexistent/dir/plot.svg.part: No such file or directory", exit_code::output_failed);
  const std::string empty = temp("empty.log");
  std::ofstream{empty};
  expect_bad(empty + " --view none", "gyrochar-decode: " + empty + ": empty: no candump log line\n");
  const std::string garbage = temp("garbage.log");
  std::ofstream(garbage) << "hello\nworld\n";
  const Outcome all_bad = run(garbage + " --view none");
  EXPECT_EQ(all_bad.code, exit_code::bad_input);
  EXPECT_TRUE(contains(all_bad.err, "gyrochar-decode: " + garbage + ": none of its 2 lines is a candump log line\n"))
      << all_bad.err;
  const Outcome help = run("--help");
  EXPECT_EQ(help.code, 0);
  EXPECT_TRUE(contains(help.out, "Examples:"));
  EXPECT_TRUE(contains(help.out, exit_code::help));
}

TEST(DecodeCli, MissingInterfaceIsNoHardwareNamedByItsName) {
  const Outcome r = run("--interface nosuchcan7 --view none --duration 0.1");
  EXPECT_EQ(r.code, exit_code::no_hardware) << r.err;
  EXPECT_EQ(r.err.rfind("gyrochar-decode: nosuchcan7: ", 0), 0u) << r.err;
  EXPECT_FALSE(contains(r.err, "nosuchcan7: nosuchcan7")) << r.err;
}

TEST(DecodeCli, PlotFilesAreWrittenForEveryNode) {
  LogWriter log;
  const NodeSpec a{0x50, 6, AngleUnit::arcsec, 0.01f}, b{0x51, 6, AngleUnit::rad, 0.01f};
  for (std::uint8_t seq = 0; seq < 5; ++seq) {
    log.report(a, seq, 100.0 + seq, 100u * (seq + 1));
    log.report(b, seq, 100.4 + seq, 100u * (seq + 1));
  }
  const std::string prefix = temp("plot");
  std::remove((prefix + ".svg").c_str());
  std::remove((prefix + ".png").c_str());
  const Outcome r = run(log.write("plot.log") + " --view none --plot " + prefix + " --plot-every 2");
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string svg = read_file(prefix + ".svg"), png = read_file(prefix + ".png");
  EXPECT_GT(svg.size(), 1000u);
  EXPECT_TRUE(contains(svg, "<svg"));
  EXPECT_GT(png.size(), 1000u);
  EXPECT_EQ(png.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));  // PNG signature
  EXPECT_FALSE(std::ifstream(prefix + ".png.part").good()) << "the temporary file was renamed";
}

TEST(DecodeCli, RestartsAndSilentNodesAreDetected) {
  const NodeSpec a{0x60, 3, AngleUnit::arcsec, 0.01f}, b{0x61, 3, AngleUnit::arcsec, 0.01f};
  LogWriter log;
  for (std::uint8_t seq = 0; seq < 12; ++seq) log.report(b, seq, 200.0 + seq, 100u * (seq + 1));
  for (std::uint8_t seq = 0; seq < 3; ++seq) log.report(a, seq, 200.5 + seq, 100u * (seq + 1));
  log.restart(a.address);  // silent for 6 s, then starts again from report 0
  for (std::uint8_t seq = 0; seq < 3; ++seq) log.report(a, seq, 209.5 + seq, 100u * (seq + 1));
  const std::string csv_path = temp("restart.csv"), jsonl_path = temp("restart.jsonl");
  const Outcome r = run(log.write("restart.log") + " --view none --rate-unit native --csv " + csv_path + " --jsonl " +
                        jsonl_path);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(contains(r.err, "node 0x60: frames")) << r.err;
  EXPECT_TRUE(contains(r.err, "restarts 1; offline 1;")) << r.err;
  const Csv csv = read_csv(csv_path);
  ASSERT_EQ(csv.rows.size(), 12u * 3 + 6u * 3);
  for (const auto& row : csv.rows) expect_row(csv, row, log, {{a.address, a}, {b.address, b}}, 1.0);
  std::vector<std::string> events;
  for (const Json& j : read_jsonl(jsonl_path))
    if (j.at("type") == "event" && j.at("node") == 0x60) events.push_back(j.at("event"));
  EXPECT_EQ(events, (std::vector<std::string>{"online", "offline", "online", "restart"}));
}

TEST(DecodeCli, StdinNodeFilterDurationAndTimeGoingBackwards) {
  const NodeSpec a{0x70, 3, AngleUnit::arcsec, 0.01f}, b{0x71, 3, AngleUnit::arcsec, 0.01f};
  LogWriter log;
  for (std::uint8_t seq = 0; seq < 8; ++seq) {
    log.report(a, seq, 300.0 + seq, 100u * (seq + 1));
    log.report(b, seq, 300.5 + seq, 100u * (seq + 1));
  }
  log.raw(301.2, "(299.000000) can1 123#00");  // out of order: counted, decoded at the latest time
  const std::string path = log.write("stdin.log"), csv_path = temp("stdin.csv");
  // --duration 3.45: decoding stops at the first frame at 303.45 s or later, 303.5 s (frame 6 of
  // report 3 of node 0x70, written before the first frame of report 3 of node 0x71 at the same time).
  const Outcome r = run("--view none --node 0x71 --duration 3.45 --rate-unit native --csv " + csv_path + " - < " + path);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(contains(r.err, "gyrochar-decode: stdin: ")) << r.err;
  EXPECT_TRUE(contains(r.err, "1 timestamps backwards")) << r.err;
  EXPECT_FALSE(contains(r.err, "node 0x70")) << "filtered out:\n" << r.err;
  const Csv csv = read_csv(csv_path);
  ASSERT_EQ(csv.rows.size(), 3u * 3);  // node 0x71, reports 0..2 (its report 3 starts at 303.5)
  for (const auto& row : csv.rows) {
    EXPECT_EQ(csv.get(row, "node"), "113");
    expect_row(csv, row, log, {{b.address, b}}, 1.0);
  }
}

}  // namespace
}  // namespace gyrochar
