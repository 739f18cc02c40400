// gyrochar-demo: the live system as a host simulation on a virtual clock. Simulated ring laser
// gyros feed the board program's own code (firmware/board.hpp: the event loop, the estimator, the
// report pacing) through the HAL fakes: a scripted count source, a virtual clock and timer, and an
// in-process CAN bus with optional frame loss. The host decoder (the pipeline of gyrochar-decode)
// follows every node, shows its table as the run goes, and leaves a CSV and an ADEV/MDEV plot.
// Hours of gyro time pass in seconds. The demo knows each gyro's true IEEE-952 parameters
// (sim_truth.hpp, the simulator's own options): the view shows them beside every node's fitted
// terms, and the plot draws the true model beside the fitted one. Each board also keeps the
// dynamic Allan deviation over --window minutes, which the plot draws as a heat map per node.
#include <algorithm>
#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <csignal>
#include <thread>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <memory>
#include <optional>
#include <vector>

#include "board.hpp"
#include "candump.hpp"
#include "limits.hpp"
#include "live_web.hpp"
#include "output_paths.hpp"
#include "plot.hpp"
#include "session.hpp"
#include "view.hpp"
#include "gyro_sim.hpp"
#include "sim_truth.hpp"
#include "hal/program/command_line.hpp"
#include "hal/program/exit_codes.hpp"
#include "hal/fake/fake_can_bus.hpp"
#include "hal/fake/fake_clock.hpp"
#include "hal/fake/fake_count_source.hpp"

namespace {

using namespace gyrochar;

constexpr const char* program = "gyrochar-demo";

volatile std::sig_atomic_t stop_requested = 0;
extern "C" void request_stop(int) { stop_requested = 1; }

[[noreturn]] void bad(const std::string& what, const std::string& why) {
  exit_with(exit_code::bad_input, program, what, why);
}

// One simulated gyro board on the bus.
struct Node {
  Node(const firmware::Config& c, const GyroParameters& g, hal::FakeCanBus& bus, const hal::FakeClock& clock)
      : gyro(g), can(bus.attach()), timer(clock), board(c, firmware::BoardIo{*can, &source, clock, timer}) {}
  GyroSimulator gyro;
  std::unique_ptr<hal::FakeCanNode> can;
  hal::FakeTimer timer;
  hal::FakeCountSource source;
  firmware::Board board;
};

// The command line's values.
struct DemoOptions {
  double hours = 6, tau0 = 0.01, loss = 0, view_every_min = 30, window_min = 30;
  unsigned nodes = 2, octaves = 20;
  std::string csv_path = "gyrochar-demo.csv", plot_prefix = "gyrochar-demo", candump_path, http_text, limits_path;
  double speed = 0, refresh_s = 1;
};

void add_options(CLI::App& app, DemoOptions& d) {
  app.footer(
      "Examples:\n  gyrochar-demo\n  gyrochar-demo --hours 24 --nodes 3 --loss 0.001 --csv decoded.csv --plot adev\n"
      "  gyrochar-demo --hours 2 --window 10   # a heat map of 12 windows per node\n"
      "  gyrochar-demo --nodes 8 --http 8080 --speed 600   # then open http://127.0.0.1:8080/\n\n"
      "With --http the live page is served during the run and, after it, until Ctrl-C (SIGINT or\n"
      "SIGTERM, which also end the run early, its outputs written). An address that cannot be listened\n"
      "on (port in use) is an output that cannot be opened (4).\n\n"
      "Two outputs (--csv, --candump, --plot's files) that are the same file, through links too, are\n"
      "refused (bad input) before anything is written.\n" +
      std::string(exit_code::help));
  app.add_option("--hours", d.hours, "gyro hours to simulate")->capture_default_str();
  app.add_option("--nodes", d.nodes, "gyro boards on the bus (1..8)")->capture_default_str();
  app.add_option("--tau0", d.tau0, "sample interval in seconds")->capture_default_str();
  app.add_option("--octaves", d.octaves, "octave taus per node (1..40)")->capture_default_str();
  app.add_option("--loss", d.loss, "probability that a frame is lost on the bus")->capture_default_str();
  app.add_option("--window", d.window_min, "gyro minutes per window of the dynamic Allan deviation (0: none)")
      ->capture_default_str();
  app.add_option("--view-every", d.view_every_min, "show the table every N gyro minutes (0: only at the end)")
      ->capture_default_str();
  app.add_option("--csv", d.csv_path, "decoded reports as CSV (one row per node, report and tau; empty: none)")
      ->capture_default_str();
  app.add_option("--plot", d.plot_prefix, "ADEV/MDEV plot written to PREFIX.svg and PREFIX.png (empty: none)")
      ->capture_default_str();
  app.add_option("--candump", d.candump_path, "also record the bus as a candump log (canplayer replays it)");
  app.add_option("--http", d.http_text, "serve the live web page on [ADDR:]PORT (address 127.0.0.1 unless given)")
      ->option_text("[ADDR:]PORT");
  app.add_option("--speed", d.speed, "gyro seconds per wall-clock second (0: as fast as it can)")->capture_default_str();
  app.add_option("--refresh", d.refresh_s, "wall-clock seconds between updates of the live web page")->capture_default_str();
  app.add_option("--limits", d.limits_path,
                 "acceptance limits (gyrochar-analyze --help): each node's verdicts on the live page (--http) and in "
                 "the CSV's verdict columns, as gyrochar-decode --limits gives them");
}

// Every option checked, in this order, before anything is opened: the live page's address and the
// limits file read.
void check_options(const DemoOptions& d, std::optional<web::ListenAddress>& http, std::vector<Limit>& limits) {
  if (std::string why; !d.http_text.empty() && !(http = web::parse_listen_address(d.http_text, why))) bad("--http", why);
  if (!(d.speed >= 0) || !std::isfinite(d.speed)) bad("--speed", fmt::format("must be a number >= 0, not {}", d.speed));
  if (!(d.refresh_s > 0) || !std::isfinite(d.refresh_s))
    bad("--refresh", fmt::format("must be a number of seconds > 0, not {}", d.refresh_s));
  if (!d.limits_path.empty()) {
    if (!http && d.csv_path.empty())
      bad("--limits", "the demo shows verdicts on its live page (--http) and in its CSV (--csv): give one of them");
    try {
      limits = read_limits_file(d.limits_path);
    } catch (const LimitsError& e) {
      bad("--limits", d.limits_path + ": " + e.what());
    }
  }
  // Each rule its own message: the option, what it must be, and what was given.
  if (!(d.hours > 0) || !std::isfinite(d.hours))
    bad("--hours", fmt::format("must be a positive number of hours, not {}", d.hours));
  if (!(d.tau0 > 0) || !std::isfinite(d.tau0))
    bad("--tau0", fmt::format("must be a positive number of seconds, not {}", d.tau0));
  if (d.hours * 3600 / d.tau0 > 1e12) bad("--hours", "more than 10^12 samples per node");
  if (d.nodes < 1 || d.nodes > 8) bad("--nodes", fmt::format("must be 1..8, not {}", d.nodes));
  if (d.octaves < 1 || d.octaves > 40) bad("--octaves", fmt::format("must be 1..40, not {}", d.octaves));
  if (!(d.loss >= 0 && d.loss < 1)) bad("--loss", fmt::format("must be a probability in [0, 1), not {}", d.loss));
  if (!(d.view_every_min >= 0) || !std::isfinite(d.view_every_min))
    bad("--view-every", fmt::format("must be a number of minutes >= 0, not {}", d.view_every_min));
  if (!(d.window_min == 0 || (d.window_min >= 4.0 / 60 && std::isfinite(d.window_min))))
    bad("--window", fmt::format("must be 0 (none) or at least 4 s of gyro time, not {} min", d.window_min));
  if (!d.plot_prefix.empty()) {
    if (const std::string why = decoding::plot_devices_missing(); !why.empty()) bad("--plot", why);
  }
  std::vector<NamedPath> outputs = plot_outputs("--plot", d.plot_prefix);
  outputs.insert(outputs.begin(), {{"--csv", d.csv_path}, {"--candump", d.candump_path}});
  if (const auto conflict = output_conflict({}, outputs)) bad(conflict->what, conflict->why);
}

// Gyro board i on the bus, its true terms noted in `truth`.
std::unique_ptr<Node> make_node(const DemoOptions& d, unsigned i, hal::FakeCanBus& bus, const hal::FakeClock& clock,
                                decoding::TrueTermsByNode& truth) {
  firmware::Config c;
  c.node = static_cast<std::uint8_t>(0x10 + i);
  c.source = firmware::SourceKind::quadrature;  // what a real board would use; the fake stands in
  c.tau0_s = d.tau0;
  c.octaves = d.octaves;
  c.report_period_s = 1.0;
  c.window_s = d.window_min * 60;
  // 1 arcsec pulses at the earth rate with 2 arcsec of white angle noise (so the quantization is
  // white), ARW 0.002, 0.003, ... deg/sqrt(h), bias instability 0.01 deg/h, RRW 0.03 deg/h/sqrt(h);
  // the second gyro also a Gauss-Markov rate of 0.2 deg/h, Tc 300 s (a hump near 570 s), which
  // its board's model selection finds and the view and plot show (protocol version 4).
  SimOptions o;
  o.duration_s = d.hours * 3600;
  o.tau0_s = d.tau0;
  o.pulse_arcsec = 1.0;
  o.white_angle_arcsec = 2.0;
  o.arw_deg_per_sqrt_h = 0.002 + 0.001 * i;
  o.bias_deg_per_h = 0.01;
  o.rrw_deg_per_h_sqrt_h = 0.03;
  o.seed = 100 + i;
  if (i == 1) o.markov = {{0.2, 300.0}};
  if (const auto problem = check_parameters(o)) bad(problem->what, problem->why);
  const Ieee952Truth t = ieee952_truth(o);
  decoding::TrueTerms& known = truth[c.node];
  known.qnbkr = {t.q_rad, t.n_rad_sqrt_s, t.b_rad_s, t.k_rad_s_sqrt_s, t.r_rad_s2};
  for (const MarkovRate& m : t.markov) known.markov.push_back({m.sigma_rad_s, m.tc_s});
  for (const SinusoidRate& w : t.sinusoids) known.sinusoids.push_back({w.amplitude_rad_s, w.frequency_hz});
  try {
    return std::make_unique<Node>(c, gyro_parameters(o), bus, clock);
  } catch (const std::exception& e) {
    bad(fmt::format("node {}", i), e.what());
  }
}

// What the run loop drives: the clock, the boards, the host's end of the bus and the decoder.
struct Rig {
  hal::FakeClock& clock;
  std::vector<std::unique_ptr<Node>>& gyros;
  hal::FakeCanNode& host;
  decoding::Session& session;
  const decoding::SessionOptions& so;
  const decoding::TrueTermsByNode& truth;
  decoding::LiveWeb* web;
  FILE* candump;
};

// The table on stdout (the screen cleared first on a terminal).
void show(const Rig& rig, bool tty) {
  if (tty) std::fputs("\033[H\033[J", stdout);
  std::fputs(decoding::format_view(rig.session.decoder(), rig.session.input(), rig.so.shown, rig.so.rate_unit,
                                   rig.session.intervals(), &rig.truth)
                 .c_str(),
             stdout);
  std::fflush(stdout);
}

// The virtual clock moves in steps of a quarter second: each step scripts the counts of that
// step into every node's source, runs each board's loop once (samples, paced report frames),
// and hands what crossed the bus to the decoder. Until the end of the run or a stop signal.
void run_clock(const DemoOptions& d, Rig& rig) {
  hal::FakeClock& clock = rig.clock;
  const bool tty = isatty(STDOUT_FILENO) == 1;
  const auto tau0_ns = static_cast<std::uint64_t>(std::llround(d.tau0 * 1e9));
  const std::uint64_t step_ns = 250000000;
  const std::uint64_t start_ns = clock.now_ns();
  const auto end_ns = start_ns + static_cast<std::uint64_t>(d.hours * 3600e9);
  const auto view_every_ns = static_cast<std::uint64_t>(d.view_every_min * 60e9);
  std::uint64_t scripted_ns = start_ns, next_view_ns = start_ns + view_every_ns;
  std::vector<std::int64_t> counts;
  const auto wall_start = std::chrono::steady_clock::now();
  // One step of the virtual clock: the counts of its samples into every node's source, each
  // board's loop once, and what crossed the bus to the decoder.
  const auto advance = [&](std::uint64_t ns) {
    clock.advance(ns);
    const std::uint64_t n = (clock.now_ns() - scripted_ns) / tau0_ns;
    for (auto& node : rig.gyros) {
      counts.resize(n);
      for (auto& c : counts) c = node->gyro.next_count();
      node->source.script_counts(scripted_ns, tau0_ns, counts.data(), counts.size());
      node->timer.update();
      node->board.run_once(0);
    }
    scripted_ns += n * tau0_ns;
    const double t_s = static_cast<double>(clock.now_ns() - start_ns) * 1e-9;
    while (auto frame = rig.host.receive()) {
      rig.session.feed(*frame, t_s);
      if (rig.candump != nullptr) std::fprintf(rig.candump, "%s\n", format_candump_line(t_s, "vcan0", *frame).c_str());
    }
  };
  while (clock.now_ns() < end_ns && !stop_requested) {
    if (d.speed > 0)  // hold the virtual clock to `speed` gyro seconds per wall-clock second
      std::this_thread::sleep_until(
          wall_start + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                           std::chrono::duration<double>(static_cast<double>(clock.now_ns() - start_ns) * 1e-9 / d.speed)));
    advance(step_ns);
    if (rig.web) rig.web->update(rig.session);
    if (view_every_ns != 0 && clock.now_ns() >= next_view_ns) {
      show(rig, tty);
      next_view_ns += view_every_ns;
    }
  }
  // The report each board is sending at the end goes out whole (at most two report periods more of
  // the gyros, in steps of a millisecond): the last view, plot and CSV rows show a whole report,
  // not one the end of the run cut off.
  const std::uint64_t finish_by_ns = clock.now_ns() + 2000000000;
  const auto between_reports = [&] {
    return std::all_of(rig.gyros.begin(), rig.gyros.end(), [](const auto& node) { return node->board.between_reports(); });
  };
  while (!stop_requested && !between_reports() && clock.now_ns() < finish_by_ns) advance(1000000);
  rig.session.finish();
  if (rig.web) rig.web->update(rig.session, true);
  show(rig, tty);
}

// The plot of every node's curves; false when it could not be written (said on stderr).
bool write_demo_plot(const std::string& prefix, const Rig& rig) {
  std::vector<decoding::NodePlot> panels;
  for (const auto& [address, node] : rig.session.decoder().nodes()) {
    const auto known = rig.truth.find(address);
    panels.push_back(decoding::plot_data(node, rig.so.rate_unit, rig.session.intervals(),
                                         known == rig.truth.end() ? nullptr : &known->second));
  }
  std::string why;
  if (decoding::write_plot(prefix, panels, rig.so.confidence, why)) return true;
  print_error(program, "plot", why);
  return false;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "gyrochar-demo: simulated gyros -> the board program (on HAL fakes) -> virtual CAN bus -> decoder,\n"
      "on a virtual clock.",
      "gyrochar-demo"};
  DemoOptions d;
  add_options(app, d);
  if (const auto code = parse_command_line(app, argc, argv, program)) return finish(program, *code);
  std::optional<web::ListenAddress> http;
  std::vector<Limit> limits;
  check_options(d, http, limits);
  // The live page is an output: an address that cannot be listened on is refused (4) before any
  // file is opened for writing.
  decoding::TrueTermsByNode truth;  // what the decoder cannot know: each simulated gyro's parameters
  std::unique_ptr<decoding::LiveWeb> web;
  if (http) {
    try {
      web = std::make_unique<decoding::LiveWeb>(*http, program, d.refresh_s, decoding::SessionOptions{}.confidence, &truth);
    } catch (const web::ListenError& e) {
      exit_with(exit_code::output_failed, program, "--http", e.what());
    }
    web->judge(&limits);
    print_error(program, "live page", web->url());
  }
  FILE* csv = d.csv_path.empty() ? nullptr : std::fopen(d.csv_path.c_str(), "w");
  if (!d.csv_path.empty() && csv == nullptr) exit_with(exit_code::output_failed, program, d.csv_path, std::strerror(errno));
  FILE* candump = nullptr;
  if (!d.candump_path.empty() && (candump = std::fopen(d.candump_path.c_str(), "w")) == nullptr)
    exit_with(exit_code::output_failed, program, d.candump_path, std::strerror(errno));

  hal::FakeClock clock;
  hal::FakeCanBus bus(7);
  bus.set_loss(d.loss);
  auto host = bus.attach(1 << 16);
  std::vector<std::unique_ptr<Node>> gyros;
  for (unsigned i = 0; i < d.nodes; ++i) gyros.push_back(make_node(d, i, bus, clock, truth));
  decoding::SessionOptions so;
  so.csv = csv;
  so.limits = &limits;  // the CSV's verdict columns, as gyrochar-decode's (empty: none)
  if (web) so.on_report = web->hook();
  struct sigaction action {};
  action.sa_handler = request_stop;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
  decoding::Session session(so);
  session.input().source = "in-process CAN bus";
  Rig rig{clock, gyros, *host, session, so, truth, web.get(), candump};
  run_clock(d, rig);

  int code = exit_code::ok;
  if (!close_output(candump, program, d.candump_path)) code = exit_code::output_failed;
  if (!close_output(csv, program, d.csv_path)) code = exit_code::output_failed;
  if (!d.plot_prefix.empty() && !write_demo_plot(d.plot_prefix, rig)) code = exit_code::output_failed;
  // The decoder's end-of-run summary, under this program's name.
  std::fputs(decoding::format_summary(session.decoder(), session.input(), so.shown, program).c_str(), stderr);
  std::fprintf(stderr, "gyrochar-demo: %.1f gyro hours, %u nodes, %llu frames on the bus%s%s%s%s\n", d.hours, d.nodes,
               static_cast<unsigned long long>(bus.frames_on_bus()), d.csv_path.empty() ? "" : "; CSV ", d.csv_path.c_str(),
               d.plot_prefix.empty() ? "" : ", plot ", d.plot_prefix.empty() ? "" : (d.plot_prefix + ".svg/.png").c_str());
  if (web) {  // the final page stays served until Ctrl-C
    print_error(program, "live page", web->url() + " serves the finished run until Ctrl-C");
    while (!stop_requested) std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  return finish(program, code);
}
