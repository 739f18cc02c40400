// gyrochar-decode: follows the gyrochar nodes on a CAN bus (live SocketCAN interface, candump log
// or stdin), shows their statistics and link health, records them as CSV / JSON lines and plots
// ADEV and MDEV with the IEEE-952 model. Columns and exit codes: host_tools/decode/README.md.
#include <fcntl.h>
#include <fmt/format.h>
#include <poll.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "hal/linux/can_interface.hpp"
#include "hal/program/command_line.hpp"
#include "hal/program/exit_codes.hpp"
#include "hal/linux/socketcan.hpp"
#include "html_report.hpp"
#include "limits.hpp"
#include "live_web.hpp"
#include "node_report.hpp"
#include "output_paths.hpp"
#include "plot.hpp"
#include "session.hpp"
#include "view.hpp"

namespace {

using namespace gyrochar;
using namespace gyrochar::decoding;

constexpr const char* program = "gyrochar-decode";
constexpr std::uint64_t malformed_reported = 10;  // malformed lines reported one by one, then counted

[[noreturn]] void fail(int code, const std::string& what, const std::string& why) { exit_with(code, program, what, why); }

volatile std::sig_atomic_t stop_requested = 0;
extern "C" void request_stop(int) { stop_requested = 1; }

void install_stop_handler() {
  struct sigaction action {};
  action.sa_handler = request_stop;  // no SA_RESTART: a blocked read()/poll() returns EINTR
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

double wall_s() { return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count(); }
double steady_s() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

enum class View { live, final, none };

struct Options {
  std::string log;        // candump log path or "-"
  std::string interface;  // live SocketCAN interface
  std::string csv, jsonl, plot, kalibr;
  double plot_every_s = 0.0;
  std::string view;
  std::string rate_unit = "deg/h";
  double confidence = 0.683;
  double duration_s = 0.0;
  std::vector<std::string> nodes;
  double refresh_s = 1.0;
  std::string limits_path, report, summary;  // --limits, --report, --summary
  std::vector<Limit> limits;
  std::string command;  // for the report's provenance
  std::string http;     // [ADDR:]PORT of the live web page; empty: none
};

std::FILE* open_output(const std::string& path) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) fail(exit_code::output_failed, path, std::strerror(errno));
  return f;
}

NodeFilter parse_nodes(const std::vector<std::string>& texts) {
  NodeFilter shown;
  if (texts.empty()) return shown.set();
  for (const std::string& t : texts) {
    std::size_t used = 0;
    unsigned long address = 0;
    try {
      address = std::stoul(t, &used, 0);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != t.size() || used == 0 || address > protocol::max_node_address)
      fail(exit_code::bad_input, "--node", "'" + t + "' is not a node address 0..253 (0x00..0xFD)");
    shown.set(address);
  }
  return shown;
}

// Everything the main loop does besides decoding: the live view, the periodic plot, the end.
class Presenter {
 public:
  Presenter(const Options& o, View view, DisplayRate rate_unit, Session& session, LiveWeb* web)
      : options_(o), view_(view), rate_unit_(rate_unit), session_(session), web_(web), tty_(isatty(STDOUT_FILENO) == 1) {}

  void malformed(const std::string& where, std::uint64_t line, const std::string& why) {
    const std::uint64_t count = session_.input().malformed_lines;
    if (count <= malformed_reported) print_error(program, fmt::format("{}:{}", where, line), "malformed line: " + why);
    if (count == malformed_reported) print_error(program, where, "further malformed lines are only counted");
  }

  /// Called often: refreshes the view and the plot when due.
  void housekeeping() {
    const double now = steady_s();
    if (view_ == View::live && now - last_view_s_ >= options_.refresh_s) {
      show();
      last_view_s_ = now;
    }
    if (web_ != nullptr) web_->update(session_);
    const InputCounters& in = session_.input();
    if ((!options_.plot.empty() || !options_.report.empty()) && options_.plot_every_s > 0 && in.started &&
        in.now_s - last_plot_s_ >= options_.plot_every_s) {
      if (!options_.plot.empty()) plot();
      if (!options_.report.empty()) report();
      last_plot_s_ = in.now_s;
    }
  }

  /// True once --duration has passed: decoder time since `start_s` (a live interface's clock runs
  /// without frames too).
  bool done(double start_s) const {
    return options_.duration_s > 0 && session_.input().now_s - start_s >= options_.duration_s;
  }

  int finish() {
    session_.finish();
    if (web_ != nullptr) web_->update(session_, true);
    int code = exit_code::ok;
    if (!options_.plot.empty() && !plot()) code = exit_code::output_failed;
    if (const int k = options_.kalibr.empty() ? exit_code::ok : kalibr(); code == exit_code::ok) code = k;
    if (!options_.report.empty() && !report() && code == exit_code::ok) code = exit_code::output_failed;
    if (view_ != View::none) show();
    if (const int v = options_.limits.empty() ? exit_code::ok : verdicts(); code == exit_code::ok) code = v;
    std::fputs(format_summary(session_.decoder(), session_.input(), session_.options().shown).c_str(), stderr);
    return code;
  }

 private:
  void show() {
    const std::string text = format_view(session_.decoder(), session_.input(), session_.options().shown, rate_unit_,
                                         session_.intervals());
    if (view_ == View::live && tty_) std::fputs("\033[H\033[J", stdout);  // home, clear screen
    std::fputs(text.c_str(), stdout);
    std::fflush(stdout);
  }

  // The Kalibr imu.yaml of the one node shown: exit code.
  int kalibr() {
    const NodeView* node = nullptr;
    std::string seen;
    int count = 0;
    for (const auto& [address, v] : session_.decoder().nodes()) {
      if (!session_.options().shown[address]) continue;
      seen += fmt::format("{}0x{:02X}", seen.empty() ? "" : ", ", address);
      node = &v;
      ++count;
    }
    if (count != 1) {
      print_error(program, "--kalibr", seen.empty() ? "no node seen" : "nodes " + seen + " seen: choose one with --node");
      return exit_code::bad_input;
    }
    std::string why;
    const auto yaml = kalibr_yaml(*node, why);
    if (!yaml) {
      print_error(program, "--kalibr", why);
      return exit_code::bad_input;
    }
    std::FILE* f = std::fopen(options_.kalibr.c_str(), "w");
    if (f == nullptr) {
      print_error(program, options_.kalibr, std::strerror(errno));
      return exit_code::output_failed;
    }
    std::fputs(yaml->c_str(), f);
    return close_output(f, program, options_.kalibr) ? exit_code::ok : exit_code::output_failed;
  }

  bool report() {
    std::string why;
    const std::string page = decode_html(session_.decoder(), session_.input(), session_.options().shown, rate_unit_,
                                         session_.intervals(), options_.limits, options_.command);
    if (html::write_file_atomically(options_.report, page, why)) return true;
    print_error(program, "--report", why);
    return false;
  }

  // The verdicts at the end: after the view (stdout) and in the summary file (the session wrote
  // the JSON lines records).
  int verdicts() {
    const Decoder& d = session_.decoder();
    const NodeFilter& shown = session_.options().shown;
    if (view_ != View::none) std::fputs(format_verdicts(d, shown, options_.limits).c_str(), stdout);
    std::vector<GyroSummary> rows;
    for (const auto& [address, node] : d.nodes()) {
      if (!shown[address]) continue;
      rows.push_back(node_summary(node, session_.input().source, options_.limits));
    }
    std::string why;
    if (!options_.summary.empty() && !append_summary(options_.summary, options_.limits, rows, why)) {
      print_error(program, options_.summary, why);
      return exit_code::output_failed;
    }
    return exit_code::ok;
  }

  bool plot() {
    std::vector<NodePlot> panels;
    for (const auto& [address, node] : session_.decoder().nodes())
      if (session_.options().shown[address]) panels.push_back(plot_data(node, rate_unit_, session_.intervals()));
    if (panels.empty()) {
      print_error(program, options_.plot, "no node to plot");
      return true;
    }
    std::string why;
    if (write_plot(options_.plot, panels, options_.confidence, why)) return true;
    print_error(program, "plot", why);
    return false;
  }

  const Options& options_;
  View view_;
  DisplayRate rate_unit_;
  Session& session_;
  LiveWeb* web_;  // the live web page (--http), or null
  bool tty_;
  double last_view_s_ = -1e300;
  double last_plot_s_ = 0.0;
};

int decode_log(const Options& o, Session& session, Presenter& presenter) {
  const bool from_stdin = o.log == "-";
  const std::string where = from_stdin ? "stdin" : o.log;
  const int fd = from_stdin ? STDIN_FILENO : ::open(o.log.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) fail(exit_code::bad_input, o.log, std::strerror(errno));
  session.input().source = where;
  LineReader reader(fd);
  std::string_view line;
  std::string why;
  std::uint64_t line_number = 0;
  for (;;) {
    const LineReader::Result r = reader.next(line);
    if (r == LineReader::Result::line) {
      ++line_number;
      if (line.empty()) continue;
      if (!session.feed_line(line, why)) presenter.malformed(where, line_number, why);
      if ((line_number & 0xFFF) == 0) presenter.housekeeping();
      if (presenter.done(session.input().first_s) || stop_requested) break;
    } else if (r == LineReader::Result::again) {
      if (stop_requested) break;
      pollfd p{fd, POLLIN, 0};
      ::poll(&p, 1, 200);  // wait for more input, wake up for the view
      presenter.housekeeping();
    } else if (r == LineReader::Result::end) {
      break;
    } else {
      fail(exit_code::bad_input, where, std::strerror(errno));
    }
  }
  if (!from_stdin) ::close(fd);
  const InputCounters& in = session.input();
  if (in.lines == 0) fail(exit_code::bad_input, where, "empty: no candump log line");
  if (in.malformed_lines == in.lines)
    fail(exit_code::bad_input, where, fmt::format("none of its {} lines is a candump log line", in.lines));
  return presenter.finish();
}

std::string bus_text(const std::string& interface, const hal::CanBus& bus) {
  static constexpr const char* states[] = {"error active", "error warning", "error passive", "bus-off", "down"};
  const hal::CanCounters& c = bus.counters();
  return fmt::format("{}: {}; received {}, dropped in the socket queue {}, error frames {}, bus-off events {}", interface,
                     states[static_cast<int>(bus.state())], c.received, c.rx_dropped, c.error_frames, c.bus_off_events);
}

int decode_live(const Options& o, Session& session, Presenter& presenter) {
  std::unique_ptr<hal::SocketCan> bus;
  try {
    bus = std::make_unique<hal::SocketCan>(o.interface);
  } catch (const std::exception& e) {
    exit_with(exit_code::no_hardware, program, e.what());  // "can0: why": the interface first
  }
  session.input().source = o.interface;
  const double start_s = wall_s();
  session.tick(start_s);
  while (!stop_requested && !presenter.done(start_s)) {
    pollfd p{bus->fd(), POLLIN, 0};
    ::poll(&p, 1, 100);
    for (int k = 0; k < 10000; ++k) {  // bounded: the view stays alive under a flood
      const auto frame = bus->receive();
      if (!frame) break;
      session.feed(*frame, wall_s());
    }
    session.tick(wall_s());
    session.input().bus = bus_text(o.interface, *bus);
    presenter.housekeeping();
  }
  return presenter.finish();
}

// The help's footer: the input, what is shown and recorded, examples, the outputs, the exit codes.
std::string help_footer() {
  return "Input: exactly one of LOG (a `candump -l` log; '-' reads stdin, e.g. `candump -L can0 | gyrochar-decode -`)\n"
         "and --interface. A log is decoded at its own timestamps; a live interface at the system clock.\n"
         "Rates are shown in --rate-unit, IEEE-952 terms as Q arcsec, N deg/sqrt(h), B deg/h, K deg/h/sqrt(h),\n"
         "R deg/h/h; a node that reports pulses is shown in pulse units, never converted.\n"
         "The node's IEEE-952 fit (protocol version 2) comes with its summary: status (ok, too_few_points,\n"
         "rejected = the model does not describe the curve, singular), chi2/dof, points used, whether the\n"
         "quantization is white, and the taus below which short-tau points were left out. A term in the\n"
         "model but not resolved is shown with its value and uncertainty and \"not resolved\"; a rejected\n"
         "fit is said so and draws no model line. Version-1 nodes send no summary.\n"
         "CSV: one row per node, report and tau; after session, the fit summary: fit_status,\n"
         "fit_chi2_per_dof, fit_points, fit_quantization_white (true/false), fit_avar_excluded_below_tau_s,\n"
         "fit_mvar_excluded_below_tau_s (s; 0 = none left out); empty without a summary. JSON lines: the\n"
         "report records carry it as \"ieee952_fit\" (null without), each term \"fitted\" and \"resolved\".\n"
         "A version-4 node's fit also carries its selected model: Markov terms (sigma, Tc), the sensor's\n"
         "filter (Tf), sinusoids, the runner-up; shown only with the summary of the same slow cycle\n"
         "(fit_model = shown, else pending or missing): the CSV's fit_model, fit_markov_terms, markov1_sigma,\n"
         "... columns, \"markov\", \"sinusoids\", \"bandwidth\" in \"ieee952_fit\", a 'model:' line in the\n"
         "table, and the Markov terms and the whole model in the plot.\n"
         "A node with a window (protocol version 3, gyrochard --window) adds its dynamic Allan deviation: window\n"
         "rows (column type = window) in the CSV and JSON lines, and a heat map beside its plot.\n"
         "All columns: host_tools/decode/README.md.\n\n"
         "Examples:\n"
         "  gyrochar-decode --interface can0\n"
         "  gyrochar-decode --interface can0 --csv run.csv --jsonl run.jsonl --plot run --plot-every 60\n"
         "  gyrochar-decode capture.log --view none --csv capture.csv --plot capture\n"
         "  gyrochar-decode capture.log --node 0x10 --rate-unit deg/s --view final\n"
         "  gyrochar-decode --interface can0 --node 0x10 --duration 86400 --kalibr imu.yaml\n"
         "  candump -L can0 | gyrochar-decode - --duration 3600 --plot hour\n\n"
         "The table shows one report per row: a value whose frame that report lost reads 'missing', as in\n"
         "the CSV (one still awaited 'pending'), never the report before's.\n"
         "Malformed lines (lines longer than " +
         std::to_string(max_candump_line_bytes) +
         " bytes among them), remote request (RTR) frames and\n"
         "rejected frames are counted and reported, not fatal. A log that is missing, unreadable, empty or\n"
         "without any candump line is bad input, and so is an output (--csv, --jsonl, --kalibr, --plot's\n"
         "files, --report, --summary) that is the same file as LOG or as another output, through links too:\n"
         "refused before anything is written.\n"
         "--limits FILE (the format of gyrochar-analyze --help): each shown node's verdicts (pass, fail,\n"
         "undecided, with the run length at which an undecided one is expected to decide): in the CSV, columns\n"
         "after the others on every tau row (verdict: the node's over all limits; per limit its limit, verdict,\n"
         "estimate and the decision bounds lower and upper, filled where it applies: a term on every tau row,\n"
         "a deviation on the row of its tau; a term also its estimate kind: judged by the node's unconstrained\n"
         "estimate where it sends one, protocol version 5, else by the shown value); in the JSON lines a\n"
         "record of type \"acceptance\" per node at each closed report where a verdict changed (\"final\":\n"
         "false; the first report always) and at the end (\"final\": true); at the end after the view, in the\n"
         "report, and with --summary FILE.csv as one row per node. Without --limits the CSV has no verdict\n"
         "column. The exit code does not depend on them.\n"
         "--report FILE.html: a self-contained page (inline SVG and CSS, no script, no external reference):\n"
         "provenance, each node's plot, taus with intervals, fit and verdicts.\n" +
         std::string(exit_code::help);
}

void add_options(CLI::App& app, Options& o) {
  app.add_option("log", o.log, "candump log file, or '-' for stdin")->option_text("LOG");
  app.add_option("-i,--interface", o.interface, "live SocketCAN interface, e.g. can0, vcan0")->option_text("IF");
  app.add_option("--csv", o.csv, "write one row per node, closed report and tau to this CSV file")->option_text("FILE");
  app.add_option("--jsonl", o.jsonl, "write the same rows, per-report status and events as JSON lines")->option_text("FILE");
  app.add_option("--plot", o.plot, "write PREFIX.svg and PREFIX.png at the end")->option_text("PREFIX");
  app.add_option("--kalibr", o.kalibr, "write the node's N and K as a Kalibr imu.yaml at the end (one node: --node)")
      ->option_text("FILE");
  app.add_option("--limits", o.limits_path,
                 "acceptance limits: a verdict per node and limit, in the CSV, the JSON lines (when one changes), "
                 "the view, the report (gyrochar-analyze --help)")
      ->option_text("FILE");
  app.add_option("--report", o.report, "write a self-contained HTML report at the end (and every --plot-every)")
      ->option_text("FILE.html");
  app.add_option("--summary", o.summary, "with --limits: append one row per node to this production summary CSV")
      ->option_text("FILE.csv");
  app.add_option("--plot-every", o.plot_every_s, "also rewrite the plot and the report every S seconds (decoder time)")
      ->option_text("S");
  app.add_option("--view", o.view,
                 "live: refreshing table; final: the table once at the end; none. "
                 "Default: live when stdout is a terminal, else none")
      ->option_text("MODE");
  app.add_option("--refresh", o.refresh_s, "seconds between refreshes of the live view")->capture_default_str();
  app.add_option("--rate-unit", o.rate_unit, "deg/h, deg/s, rad/s or native (the node's angle unit per s)")
      ->capture_default_str();
  app.add_option("--confidence", o.confidence, "level of the confidence intervals, in (0, 1)")->capture_default_str();
  app.add_option("--duration", o.duration_s, "stop after S seconds of decoder time (log time for a log)")->option_text("S");
  app.add_option("--node", o.nodes, "show and record only this node address (repeatable; 16 or 0x10)")
      ->option_text("ADDRESS");
  app.add_option("--http", o.http,
                 "serve the live web page on [ADDR:]PORT (address 127.0.0.1 unless given; 0.0.0.0 for every "
                 "interface), updated every --refresh seconds")
      ->option_text("[ADDR:]PORT");
}

// The checks below run in the order main calls them: the first bad option is the one reported.

std::optional<web::ListenAddress> check_http(const Options& o) {
  std::optional<web::ListenAddress> http;
  if (std::string why; !o.http.empty() && !(http = web::parse_listen_address(o.http, why)))
    fail(exit_code::bad_input, "--http", why);
  return http;
}

void check_input(const Options& o) {
  if (o.log.empty() == o.interface.empty())
    fail(exit_code::bad_input, "options", "give either a LOG or --interface (see --help)");
  if (!o.interface.empty())  // a name no interface can have is bad input; a missing one is hardware
    if (const std::string problem = interface_name_problem(o.interface); !problem.empty())
      fail(exit_code::bad_input, "--interface", "'" + o.interface + "': " + problem);
}

DisplayRate check_rate_unit(const Options& o) {
  const DisplayRate rate_unit = gyrochar::rate_unit(o.rate_unit);
  if (!rate_unit && o.rate_unit != "native")
    fail(exit_code::bad_input, "--rate-unit", "'" + o.rate_unit + "' is not deg/h, deg/s, rad/s or native");
  return rate_unit;
}

void check_numbers(const Options& o) {
  if (!(o.confidence > 0 && o.confidence < 1)) fail(exit_code::bad_input, "--confidence", "must be in (0, 1)");
  if (!(o.duration_s >= 0)) fail(exit_code::bad_input, "--duration", "must be >= 0");
  if (!(o.plot_every_s >= 0)) fail(exit_code::bad_input, "--plot-every", "must be >= 0");
  if (o.plot_every_s > 0 && o.plot.empty() && o.report.empty())
    fail(exit_code::bad_input, "--plot-every", "needs --plot PREFIX or --report FILE.html");
}

// --limits read into o.limits; --summary checked against them.
void read_limits(Options& o) {
  if (!o.limits_path.empty()) {
    try {
      o.limits = read_limits_file(o.limits_path);
    } catch (const LimitsError& e) {
      fail(exit_code::bad_input, "--limits", o.limits_path + ": " + e.what());
    }
  }
  if (!o.summary.empty()) {
    std::string why;
    if (o.limits.empty()) fail(exit_code::bad_input, "--summary", "needs --limits (the rows hold the verdicts)");
    if (!summary_compatible(o.summary, o.limits, why)) fail(exit_code::bad_input, "--summary", o.summary + ": " + why);
  }
}

// --refresh and --view.
View choose_view(const Options& o) {
  if (!(o.refresh_s > 0)) fail(exit_code::bad_input, "--refresh", "must be > 0");
  View view = isatty(STDOUT_FILENO) ? View::live : View::none;
  if (o.view == "live") view = View::live;
  else if (o.view == "final") view = View::final;
  else if (o.view == "none") view = View::none;
  else if (!o.view.empty()) fail(exit_code::bad_input, "--view", "'" + o.view + "' is not live, final or none");
  return view;
}

// No output is an input or another output; the plot can be written (checked now, not after hours of
// decoding).
void check_outputs(const Options& o) {
  std::vector<NamedPath> outputs = plot_outputs("--plot", o.plot);
  outputs.insert(outputs.begin(), {{"--csv", o.csv}, {"--jsonl", o.jsonl}, {"--kalibr", o.kalibr}});
  outputs.insert(outputs.end(), {{"--report", o.report},
                                 {"--report", o.report.empty() ? "" : o.report + ".part"},
                                 {"--summary", o.summary}});
  if (const auto conflict = output_conflict({{"LOG", o.log}, {"--limits", o.limits_path}}, outputs))
    fail(exit_code::bad_input, conflict->what, conflict->why);
  if (!o.plot.empty()) {
    if (const std::string missing = plot_devices_missing(); !missing.empty()) fail(exit_code::bad_input, "--plot", missing);
    std::fclose(open_output(o.plot + ".svg.part"));  // fail now, not after hours of decoding
    std::remove((o.plot + ".svg.part").c_str());
  }
}

// The page is an output: an address that cannot be listened on is refused (4) before any file is
// opened for writing. Null without --http.
std::unique_ptr<LiveWeb> open_live_page(const std::optional<web::ListenAddress>& http, const Options& o) {
  std::unique_ptr<LiveWeb> web;
  if (http) {
    try {
      web = std::make_unique<LiveWeb>(*http, program, o.refresh_s, o.confidence);
    } catch (const web::ListenError& e) {
      fail(exit_code::output_failed, "--http", e.what());
    }
    web->judge(&o.limits);
    print_error(program, "live page", web->url());
  }
  return web;
}

// Opens the CSV and JSON lines, decodes the log or the interface to its end, closes them: exit code.
int decode(const Options& o, View view, const DisplayRate& rate_unit, LiveWeb* web) {
  SessionOptions s;
  s.rate_unit = rate_unit;
  s.confidence = o.confidence;
  s.shown = parse_nodes(o.nodes);
  s.csv = o.csv.empty() ? nullptr : open_output(o.csv);
  s.jsonl = o.jsonl.empty() ? nullptr : open_output(o.jsonl);
  s.limits = &o.limits;
  if (web != nullptr) s.on_report = web->hook();
  install_stop_handler();
  int code = exit_code::ok;
  {
    Session session(s);
    Presenter presenter(o, view, rate_unit, session, web);
    code = o.interface.empty() ? decode_log(o, session, presenter) : decode_live(o, session, presenter);
  }
  for (const auto& [file, path] : {std::pair{s.csv, o.csv}, std::pair{s.jsonl, o.jsonl}})
    if (!close_output(file, program, path)) code = exit_code::output_failed;
  return code;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "gyrochar-decode: follows the gyrochar nodes on a CAN bus; shows, records and plots their "
      "ADEV, MDEV, IEEE-952 terms and link health.",
      "gyrochar-decode"};
  app.footer(help_footer());
  Options o;
  add_options(app, o);
  if (const auto code = parse_command_line(app, argc, argv, program)) return finish(program, *code);
  for (int i = 0; i < argc; ++i) o.command += (i ? " " : "") + std::string(argv[i]);
  const std::optional<web::ListenAddress> http = check_http(o);
  check_input(o);
  const DisplayRate rate_unit = check_rate_unit(o);
  check_numbers(o);
  read_limits(o);
  const View view = choose_view(o);
  check_outputs(o);
  const std::unique_ptr<LiveWeb> web = open_live_page(http, o);
  return finish(program, decode(o, view, rate_unit, web.get()));
}
