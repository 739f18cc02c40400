// gyrochard: the board program. The composition root: the only place that picks backends. It reads
// the configuration, opens the Linux backends (SocketCAN, the configured count source, timerfd),
// resumes from the checkpoint, and runs the board's event loop until SIGTERM or SIGINT, when it
// writes a last checkpoint. The whole configuration (and the checkpoint's directory) is checked
// before any hardware is opened, so an invalid configuration exits 2 even without the hardware;
// then missing hardware exits 3 naming the device (hal/program/exit_codes.hpp). A run in which a checkpoint
// could not be written exits 4 (an output failed) at its end. Text from the configuration is
// logged with control bytes escaped (printable()).
#include <sys/signalfd.h>
#include <unistd.h>

#include <cmath>
#include <csignal>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>

#include "board.hpp"
#include "config.hpp"
#include "hal/program/exit_codes.hpp"
#include "hal/linux/gpio_quadrature.hpp"
#include "hal/linux/gpio_strobe.hpp"
#include "hal/linux/socketcan.hpp"
#include "hal/linux/timer.hpp"

namespace {

using namespace gyrochar;

constexpr const char* program = "gyrochard";

int config_error(const firmware::ConfigError& e) {
  print_error(program, printable(e.where.empty() ? e.key : e.where + ": " + e.key), printable(e.why));
  return exit_code::bad_input;
}

// The HAL's messages name the device first ("can0: No such device").
int no_hardware(const std::exception& e) {
  print_error(program, printable(e.what()));
  return exit_code::no_hardware;
}

// The configured count source; nullptr for CounterInput frames (they arrive on the CAN bus).
std::unique_ptr<hal::CountSource> open_source(const firmware::Config& c, std::uint64_t now_ns) {
  const auto tau0_ns = static_cast<std::uint64_t>(std::llround(c.tau0_s * 1e9));
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
  if (parsed.exit_now) return finish(program, exit_code::ok);
  if (parsed.error) return config_error(*parsed.error);
  const firmware::Config& config = *parsed.config;
  if (const auto problem = firmware::check_files(config)) return config_error(*problem);

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
  std::unique_ptr<firmware::Board> board;
  try {
    source = open_source(config, clock.now_ns());
    can = std::make_unique<hal::SocketCan>(config.can_interface);
    timer = std::make_unique<hal::TimerFd>();
    board = std::make_unique<firmware::Board>(config, firmware::BoardIo{*can, source.get(), clock, *timer, stop_fd},
                                              firmware::FitMode::background);
  } catch (const std::invalid_argument& e) {  // settings validate() passed: a bug
    print_error(program, "internal error", e.what());
    return exit_code::internal;
  } catch (const std::exception& e) {
    return no_hardware(e);
  }
  std::fprintf(stderr, "<6>gyrochard: %s\n", printable(board->resume()).c_str());
  std::fprintf(stderr, "<6>gyrochard: running: node %u on %s, tau0 %g s, %u octaves, stride factor %u\n",
               static_cast<unsigned>(config.node), printable(config.can_interface).c_str(), config.tau0_s, config.octaves,
               config.stride_factor);

  while (board->run_once(1000)) {
  }
  const int e = board->checkpoint();
  std::fprintf(stderr, "<6>gyrochard: stopping on signal after %llu samples%s\n",
               static_cast<unsigned long long>(board->characterizer().increments()),
               config.checkpoint_path.empty() ? ""
               : e == 0                       ? ", checkpoint written"
                                              : ", checkpoint NOT written");
  close(stop_fd);
  if (board->checkpoint_failures() == 0) return finish(program, exit_code::ok);
  print_error(program, "checkpoint " + printable(config.checkpoint_path),
              std::to_string(board->checkpoint_failures()) + " checkpoint(s) could not be written during the run");
  return finish(program, exit_code::output_failed);
}
