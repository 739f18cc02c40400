// gyrochard: the board program. The composition root: it picks the backends from the configuration
// (the only place that does), then runs one epoll loop over the count input, the CAN bus, the
// report pacing timer and the termination signals. No heap allocation after start-up: the
// estimator, the report and every buffer are fixed-size members created before the loop.
//
// Input in this build: CounterInput frames from the gyro electronics on the CAN bus
// (--source can-counter). The GPIO sources (quadrature, strobe) are not in this build and are
// refused at start-up with a clear message.
#include <sys/epoll.h>
#include <sys/signalfd.h>
#include <sys/timerfd.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <memory>
#include <stdexcept>
#include <string>

#include "config.hpp"
#include "hal/linux/socketcan.hpp"
#include "report.hpp"

namespace {

using namespace gyrochar;

constexpr int exit_config = 2;
constexpr int exit_hardware = 3;

void log(const char* level, const std::string& message) {
  std::fprintf(stderr, "<%s>gyrochard: %s\n", level, message.c_str());  // journald priority prefix
}

std::uint64_t monotonic_ms() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::uint64_t>(ts.tv_sec) * 1000u + static_cast<std::uint64_t>(ts.tv_nsec) / 1000000u;
}

class Board {
 public:
  Board(const firmware::Config& c, hal::CanBus& can) : config_(c), can_(can) {
    firmware::EstimatorSettings s;
    s.tau0_s = c.tau0_s;
    s.pulse_weight_arcsec = c.pulse_weight_arcsec;
    s.stride_factor = c.stride_factor;
    s.octaves = c.octaves;
    s.source = protocol::InputSource::can_counter;
    s.report_period_ms = static_cast<std::uint16_t>(c.report_period_s * 1000.0);
    s.config_hash = static_cast<std::uint32_t>(std::hash<std::string>{}(
        std::to_string(c.tau0_s) + "/" + std::to_string(c.pulse_weight_arcsec) + "/" +
        std::to_string(c.stride_factor) + "/" + std::to_string(c.octaves)));
    if (!estimator_.configure(s)) throw std::invalid_argument("estimator settings out of range");
    start_ms_ = monotonic_ms();
  }

  // A frame from the bus: counter input from the configured electronics, anything else ignored.
  void on_frame(const CanFrame& f) {
    if (f.error) return;  // bus state is tracked by the backend
    const protocol::Decoded d = protocol::decode(f);
    if (d.error != protocol::ProtocolError::none || d.node != config_.counter_node) return;
    const auto* in = std::get_if<protocol::CounterInputMsg>(&d.message);
    if (in == nullptr) return;
    if (in->count_error) ++faults_.lost_edges;
    if (have_count_) {
      const auto expected = static_cast<std::uint8_t>(last_seq_ + 1);
      if (in->seq != expected || in->count_error || in->sensor_not_ready) {
        ++faults_.sample_gaps;  // lost frames or a bad interval: a new segment, never bridged
        estimator_.mark_gap();
      } else {
        estimator_.add_count(static_cast<std::int32_t>(in->count - last_count_));
      }
    }
    have_count_ = true;
    last_count_ = in->count;
    last_seq_ = in->seq;
  }

  // One pacing tick: the next frame of the current report (a new report at frame 0).
  void on_tick() {
    if (frame_ == 0) {
      faults_.tx_dropped_frames = static_cast<std::uint32_t>(can_.counters().tx_dropped);
      faults_.bus_off_events = static_cast<std::uint32_t>(can_.counters().bus_off_events);
      estimator_.report(seq_, monotonic_ms() - start_ms_, faults_, content_);
      frames_ = protocol::report_frame_count(seq_, config_.octaves);
      if (config_.verbose)
        log("7", "report " + std::to_string(seq_) + ", " + std::to_string(estimator_.samples()) + " samples");
    }
    CanFrame f;
    if (protocol::encode(firmware::report_message(content_, frame_), config_.node, f) == protocol::ProtocolError::none)
      can_.send(f);  // a full queue or a downed bus is counted by the backend, never waited for
    if (++frame_ >= frames_) {
      frame_ = 0;
      ++seq_;
    }
  }

  std::size_t frames_per_report() const { return protocol::report_frame_count(0, config_.octaves); }

 private:
  firmware::Config config_;
  hal::CanBus& can_;
  firmware::Estimator estimator_;
  firmware::ReportContent content_;
  firmware::FaultCounters faults_;
  std::uint64_t start_ms_ = 0;
  std::uint8_t seq_ = 0;
  std::size_t frame_ = 0, frames_ = 1;
  bool have_count_ = false;
  std::uint32_t last_count_ = 0;
  std::uint8_t last_seq_ = 0;
};

}  // namespace

int main(int argc, char** argv) {
  const firmware::ParseResult parsed = firmware::parse_config(argc, argv);
  if (parsed.exit_now) return 0;
  if (parsed.error) {
    std::fprintf(stderr, "gyrochard: %s: %s\n", parsed.error->key.c_str(), parsed.error->why.c_str());
    return exit_config;
  }
  const firmware::Config& config = *parsed.config;
  if (config.source != firmware::SourceKind::can_counter) {
    std::fprintf(stderr, "gyrochard: source: only can-counter input is in this build\n");
    return exit_config;
  }
  std::unique_ptr<hal::SocketCan> can;
  try {
    can = std::make_unique<hal::SocketCan>(config.can_interface);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "gyrochard: can-interface: %s\n", e.what());
    return exit_hardware;
  }
  std::unique_ptr<Board> board;
  try {
    board = std::make_unique<Board>(config, *can);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "gyrochard: configuration: %s\n", e.what());
    return exit_config;
  }

  // Pacing timer: one tick per frame, frames spread over the report period.
  const int timer = timerfd_create(CLOCK_MONOTONIC, TFD_NONBLOCK | TFD_CLOEXEC);
  const auto tick_ns = static_cast<long long>(config.report_period_s * 1e9 / static_cast<double>(board->frames_per_report()));
  itimerspec period{};
  period.it_interval.tv_sec = tick_ns / 1000000000LL;
  period.it_interval.tv_nsec = tick_ns % 1000000000LL;
  period.it_value = period.it_interval;
  timerfd_settime(timer, 0, &period, nullptr);
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGTERM);
  sigaddset(&signals, SIGINT);
  sigprocmask(SIG_BLOCK, &signals, nullptr);
  const int sigfd = signalfd(-1, &signals, SFD_NONBLOCK | SFD_CLOEXEC);
  const int epoll = epoll_create1(EPOLL_CLOEXEC);
  for (const int fd : {can->fd(), timer, sigfd}) {
    epoll_event ev{};
    ev.events = EPOLLIN;
    ev.data.fd = fd;
    epoll_ctl(epoll, EPOLL_CTL_ADD, fd, &ev);
  }
  log("6", "running: node " + std::to_string(config.node) + " on " + config.can_interface + ", counter input from node " +
               std::to_string(config.counter_node) + ", tau0 " + std::to_string(config.tau0_s) + " s");
  bool running = true;
  epoll_event events[8];
  while (running) {
    const int n = epoll_wait(epoll, events, 8, 1000);
    if (n < 0 && errno != EINTR) {
      log("3", std::string("epoll: ") + std::strerror(errno));
      break;
    }
    for (int i = 0; i < n; ++i) {
      const int fd = events[i].data.fd;
      if (fd == sigfd) {
        running = false;
      } else if (fd == timer) {
        std::uint64_t expirations = 0;
        if (read(timer, &expirations, sizeof expirations) == sizeof expirations)
          for (std::uint64_t k = 0; k < expirations && k < 64; ++k) board->on_tick();  // bounded catch-up
      } else {
        for (int k = 0; k < 256; ++k) {  // bounded work per wake-up: an input storm cannot starve the rest
          const auto f = can->receive();
          if (!f) break;
          board->on_frame(*f);
        }
      }
    }
  }
  log("6", "stopping on signal");
  close(epoll);
  close(sigfd);
  close(timer);
  return 0;
}
