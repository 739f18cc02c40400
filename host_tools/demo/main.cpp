// gyrochar-demo: the live system as a host simulation on a virtual clock. Simulated ring laser
// gyros feed the board's estimator (firmware/report.hpp) on several nodes; their reports cross an
// in-process CAN bus (hal/fake) with optional frame loss; the host decoder follows every node,
// shows a refreshing table, and writes a CSV. Hours of gyro time pass in seconds.
#include <CLI/CLI.hpp>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

#include "decoder.hpp"
#include "live_view.hpp"
#include "gyro_sim.hpp"
#include "hal/fake/fake_can_bus.hpp"
#include "report.hpp"

namespace {

using namespace gyrochar;

struct Node {
  Node(std::uint8_t a, const GyroParameters& g, std::unique_ptr<hal::FakeCanNode> c)
      : address(a), gyro(g), can(std::move(c)) {}
  std::uint8_t address;
  GyroSimulator gyro;
  firmware::Estimator estimator;
  std::unique_ptr<hal::FakeCanNode> can;
  std::uint8_t seq = 0;
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"gyrochar-demo: simulated gyros -> board estimator -> virtual CAN bus -> decoder, on a virtual clock.",
               "gyrochar-demo"};
  app.footer("Examples:\n  gyrochar-demo\n  gyrochar-demo --hours 24 --nodes 3 --loss 0.001 --csv decoded.csv\n"
             "Exit codes: 0 success, 2 bad options.");
  double hours = 6, tau0 = 0.01, loss = 0, view_every_min = 30;
  unsigned nodes = 2, octaves = 20;
  std::string csv_path = "gyrochar-demo.csv";
  app.add_option("--hours", hours, "gyro hours to simulate")->capture_default_str();
  app.add_option("--nodes", nodes, "gyro nodes on the bus (1..8)")->capture_default_str();
  app.add_option("--tau0", tau0, "sample interval in seconds")->capture_default_str();
  app.add_option("--octaves", octaves, "octave taus per node")->capture_default_str();
  app.add_option("--loss", loss, "probability that a frame is lost on the bus")->capture_default_str();
  app.add_option("--view-every", view_every_min, "refresh the view every N gyro minutes")->capture_default_str();
  app.add_option("--csv", csv_path, "decoded reports as CSV (one row per node, report and tau)")->capture_default_str();
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "gyrochar-demo: options: %s (see --help)\n", e.what());
    return 2;
  }
  if (!(hours > 0) || !(tau0 > 0) || nodes < 1 || nodes > 8 || !(loss >= 0 && loss < 1) || octaves < 1 || octaves > 40) {
    std::fprintf(stderr, "gyrochar-demo: options: hours, tau0 > 0; nodes 1..8; loss in [0, 1); octaves 1..40\n");
    return 2;
  }
  FILE* csv = std::fopen(csv_path.c_str(), "w");
  if (csv == nullptr) {
    std::fprintf(stderr, "gyrochar-demo: %s: cannot write\n", csv_path.c_str());
    return 2;
  }
  write_csv_header(csv);

  hal::FakeCanBus bus(7);
  bus.set_loss(loss);
  std::vector<std::unique_ptr<Node>> gyros;
  for (unsigned i = 0; i < nodes; ++i) {
    GyroParameters g;
    g.tau0_s = tau0;
    g.q_rad = 2 * units::arcsec;
    g.n_rad_sqrt_s = (0.002 + 0.001 * i) * units::deg_per_sqrt_h;
    g.k_rad_s_sqrt_s = 0.03 * units::deg_per_h_sqrt_h;
    g.seed = 100 + i;
    auto n = std::make_unique<Node>(static_cast<std::uint8_t>(0x10 + i), g, bus.attach());
    firmware::EstimatorSettings s;
    s.tau0_s = tau0;
    s.octaves = octaves;
    s.source = protocol::InputSource::simulated;
    if (!n->estimator.configure(s)) {
      std::fprintf(stderr, "gyrochar-demo: cannot configure the estimator\n");
      return 2;
    }
    gyros.push_back(std::move(n));
  }
  auto host = bus.attach(1 << 16);
  double t = 0;
  Decoder decoder([&](DecoderEvent e, const NodeView& v, std::uint8_t seq) {
    if (e == DecoderEvent::report_closed) write_csv_rows(csv, v, seq, t);
  });

  const bool tty = isatty(STDOUT_FILENO);
  const auto samples_per_report = static_cast<std::uint64_t>(std::llround(1.0 / tau0));  // 1 s reports
  const auto reports = static_cast<std::uint64_t>(hours * 3600.0);
  const auto view_every = static_cast<std::uint64_t>(view_every_min * 60.0);
  firmware::ReportContent content;
  for (std::uint64_t r = 0; r < reports; ++r) {
    for (auto& n : gyros) {
      for (std::uint64_t k = 0; k < samples_per_report; ++k)
        n->estimator.add_count(static_cast<std::int32_t>(n->gyro.next_count()));
      n->estimator.report(n->seq, (r + 1) * 1000, {}, content);
      const std::size_t frames = protocol::report_frame_count(n->seq, octaves);
      for (std::size_t k = 0; k < frames; ++k) {  // paced over the report period
        CanFrame f;
        protocol::encode(firmware::report_message(content, k), n->address, f);
        n->can->send(f);
        while (auto in = host->receive()) decoder.feed(*in, t + static_cast<double>(k) / static_cast<double>(frames));
      }
      ++n->seq;
    }
    t += 1.0;
    if (view_every && (r + 1) % view_every == 0) print_view(stdout, decoder, t, tty);
  }
  decoder.flush();
  print_view(stdout, decoder, t, tty);
  std::fclose(csv);
  std::fprintf(stderr, "gyrochar-demo: %.1f gyro hours, %u nodes, %llu frames on the bus; decoded reports in %s\n",
               hours, nodes, static_cast<unsigned long long>(bus.frames_on_bus()), csv_path.c_str());
  return 0;
}
