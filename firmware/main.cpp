// gyrochard: the board program. The composition root: the only place that picks backends. It reads
// the configuration, opens the Linux backends (SocketCAN, the configured count source, timerfd),
// resumes from the checkpoint, and runs the board's event loop until SIGTERM or SIGINT, when it
// writes a last checkpoint. Exit codes: 0 clean stop, 2 invalid configuration, 3 hardware missing.
#include <sys/signalfd.h>
#include <unistd.h>

#include <csignal>
#include <cstdio>
#include <memory>
#include <stdexcept>

#include "board.hpp"
#include "config.hpp"
#include "hal/linux/gpio_quadrature.hpp"
#include "hal/linux/gpio_strobe.hpp"
#include "hal/linux/socketcan.hpp"
#include "hal/linux/timer.hpp"

namespace {

using namespace gyrochar;

constexpr int exit_config = 2;
constexpr int exit_hardware = 3;

int fail(int code, const std::string& key, const std::string& why) {
  std::fprintf(stderr, "gyrochard: %s: %s\n", key.c_str(), why.c_str());
  return code;
}

// The configured count source; nullptr for CounterInput frames (they arrive on the CAN bus).
std::unique_ptr<hal::CountSource> open_source(const firmware::Config& c, std::uint64_t now_ns) {
  const auto tau0_ns = static_cast<std::uint64_t>(c.tau0_s * 1e9 + 0.5);
  switch (c.source) {
    case firmware::SourceKind::quadrature: {
      hal::GpioQuadratureSettings s;
      s.chip = c.gpio_chip;
      s.line_a = c.line_a;
      s.line_b = c.line_b;
      s.tau0_ns = tau0_ns;
      return std::make_unique<hal::GpioQuadratureSource>(s, now_ns);
    }
    case firmware::SourceKind::strobe: {
      hal::GpioStrobeSettings s;
      s.chip = c.gpio_chip;
      s.line = c.strobe_line;
      s.counter_path = c.counter_path;
      s.tau0_ns = tau0_ns;
      return std::make_unique<hal::GpioStrobeSource>(s);
    }
    case firmware::SourceKind::can_counter: return nullptr;
  }
  return nullptr;
}

}  // namespace

int main(int argc, char** argv) {
  const firmware::ParseResult parsed = firmware::parse_config(argc, argv);
  if (parsed.exit_now) return 0;
  if (parsed.error) return fail(exit_config, parsed.error->key, parsed.error->why);
  const firmware::Config& config = *parsed.config;

  // Signals become a readable descriptor for the loop.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGTERM);
  sigaddset(&signals, SIGINT);
  sigprocmask(SIG_BLOCK, &signals, nullptr);
  const int stop_fd = signalfd(-1, &signals, SFD_NONBLOCK | SFD_CLOEXEC);

  hal::MonotonicClock clock;
  std::unique_ptr<hal::SocketCan> can;
  std::unique_ptr<hal::CountSource> source;
  std::unique_ptr<hal::TimerFd> timer;
  try {
    source = open_source(config, clock.now_ns());
  } catch (const std::exception& e) {
    return fail(exit_hardware, "source", e.what());
  }
  try {
    can = std::make_unique<hal::SocketCan>(config.can_interface);
  } catch (const std::exception& e) {
    return fail(exit_hardware, "can-interface", e.what());
  }
  try {
    timer = std::make_unique<hal::TimerFd>();
  } catch (const std::exception& e) {
    return fail(exit_hardware, "timer", e.what());
  }
  std::unique_ptr<firmware::Board> board;
  try {
    board = std::make_unique<firmware::Board>(config, firmware::BoardIo{*can, source.get(), clock, *timer, stop_fd},
                                                   firmware::FitMode::background);
  } catch (const std::exception& e) {
    return fail(exit_config, "configuration", e.what());
  }
  std::fprintf(stderr, "<6>gyrochard: %s\n", board->resume().c_str());
  std::fprintf(stderr, "<6>gyrochard: running: node %u on %s, tau0 %g s, %u octaves, stride factor %u\n",
               static_cast<unsigned>(config.node), config.can_interface.c_str(), config.tau0_s, config.octaves,
               config.stride_factor);

  while (board->run_once(1000)) {
  }
  const int e = board->checkpoint();
  std::fprintf(stderr, "<6>gyrochard: stopping on signal after %llu samples%s\n",
               static_cast<unsigned long long>(board->characterizer().increments()),
               config.checkpoint_path.empty() ? "" : e == 0 ? ", checkpoint written" : ", checkpoint NOT written");
  close(stop_fd);
  return 0;
}
