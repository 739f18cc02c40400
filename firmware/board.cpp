#include "board.hpp"

#include <sys/epoll.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>

#include "gyrochar/crc32.hpp"
#include "hal/program/exit_codes.hpp"

namespace gyrochar::firmware {
namespace {

// Logs for journald: a priority prefix (<3> error, <4> warning, <6> info, <7> debug). printf-style
// so that logging in the loop allocates nothing.
#define BOARD_LOG(level, ...)                                   \
  do {                                                          \
    std::fprintf(stderr, "<" level ">gyrochard: " __VA_ARGS__); \
    std::fputc('\n', stderr);                                   \
  } while (0)

protocol::InputSource input_source(SourceKind s) {
  switch (s) {
    case SourceKind::quadrature: return protocol::InputSource::gpio_quadrature;
    case SourceKind::strobe: return protocol::InputSource::strobe_counter;
    case SourceKind::can_counter: return protocol::InputSource::can_counter;
  }
  return protocol::InputSource::unknown;
}

// What a checkpoint must match: everything that shapes the accumulator's state or its meaning.
// Without a window the text is what it was before windows existed, so those checkpoints resume.
std::uint32_t hash_settings(const ReportSettings& s) {
  char text[200];
  int n = std::snprintf(text, sizeof text, "tau0=%.17g pulse=%.17g S=%u octaves=%u source=%u", s.tau0_s,
                        s.pulse_weight_arcsec, s.stride_factor, s.octaves, static_cast<unsigned>(s.source));
  if (s.window_length != 0)
    n += std::snprintf(text + n, sizeof text - static_cast<std::size_t>(n), " window=%llu",
                       static_cast<unsigned long long>(s.window_length));
  return crc32(std::as_bytes(std::span(text, static_cast<std::size_t>(n))));
}

const char* restore_reason(RestoreStatus s) {
  switch (s) {
    case RestoreStatus::ok: return "ok";
    case RestoreStatus::truncated: return "truncated";
    case RestoreStatus::not_a_checkpoint: return "not a gyrochard checkpoint";
    case RestoreStatus::wrong_version: return "written by another checkpoint format version";
    case RestoreStatus::corrupted: return "CRC mismatch (corrupted)";
    case RestoreStatus::config_mismatch:
      return "written under another configuration (tau0, pulse weight, stride factor, octaves, source or window "
             "changed)";
    case RestoreStatus::other_identity: return "written for another gyro";
    case RestoreStatus::invalid_state: return "invalid state";
  }
  return "invalid";
}

// The gyro a checkpoint belongs to: the node address (bits 0-7) and, with a CAN counter source,
// the counter node, i.e. the gyro's electronics (bits 8-15, bit 16 set).
std::uint32_t gyro_identity(const Config& c) {
  const std::uint32_t counter = c.source == SourceKind::can_counter ? 0x10000u | (c.counter_node & 0xFFu) << 8 : 0;
  return counter | c.node;
}

std::string describe_identity(std::uint32_t id) {
  char text[64];
  if ((id & 0x10000u) != 0)
    std::snprintf(text, sizeof text, "node address 0x%02X, counter node 0x%02X", id & 0xFFu, (id >> 8) & 0xFFu);
  else std::snprintf(text, sizeof text, "node address 0x%02X, no CAN counter", id & 0xFFu);
  return text;
}

// Why a restore failed, with the field or the identities where they say more.
std::string restore_why(RestoreStatus s, const char* field, std::uint32_t found, std::uint32_t identity) {
  if (s == RestoreStatus::invalid_state) return std::string("invalid state: ") + field;
  if (s == RestoreStatus::other_identity)
    return std::string(restore_reason(s)) + " (" + describe_identity(found) + "; this run: " + describe_identity(identity) +
           ")";
  return restore_reason(s);
}

}  // namespace

Board::Board(const Config& config, BoardIo io, FitMode fit_mode)
    : config_(config),
      io_(io),
      can_counter_(static_cast<std::uint8_t>(config.counter_node)),
      checkpoint_file_(config.checkpoint_path),
      report_work_(config.octaves, fit_mode),
      shown_path_(printable(config.checkpoint_path)) {
  settings_.tau0_s = config.tau0_s;
  settings_.pulse_weight_arcsec = config.pulse_weight_arcsec;
  settings_.stride_factor = config.stride_factor;
  settings_.octaves = config.octaves;
  settings_.source = input_source(config.source);
  // validate() keeps the period within the protocol's 100..2000 ms: the field cannot wrap.
  settings_.report_period_ms = static_cast<std::uint16_t>(std::lround(config.report_period_s * 1000.0));
  if (config.window_s > 0) {
    settings_.window_length = static_cast<std::uint64_t>(std::llround(config.window_s / config.tau0_s));
    settings_.window_taus = window_taus(config.octaves, settings_.window_length);
  }
  settings_.config_hash = hash_settings(settings_);
  settings_.identity = gyro_identity(config);
  if (!configure(characterizer_, settings_)) throw std::invalid_argument("estimator settings out of range");
  if (settings_.window_taus != 0 && !window_.configure(settings_.stride_factor, settings_.config_hash, settings_.window_taus,
                                                       settings_.window_length, settings_.identity))
    throw std::invalid_argument("window settings out of range");
  checkpoint_buffer_.resize(characterizer_.checkpoint_size() + (settings_.window_taus ? window_.checkpoint_size() : 0));
  checkpoint_period_ns_ = static_cast<std::uint64_t>(config.checkpoint_period_s * 1e9);
  start_ns_ = io.clock.now_ns();
  next_checkpoint_ns_ = start_ns_ + checkpoint_period_ns_;
  frames_ = protocol::report_frame_count(0, config.octaves, protocol::version, settings_.window_taus);

  // The board listens to its counter electronics only (or to nothing: a GPIO source); error
  // frames always come through.
  const hal::CanFilter counter_frames{protocol::counter_input_id | config.counter_node, 0x1FFFFFFF};
  if (!io.can.set_filters(io.source ? std::span<const hal::CanFilter>{} : std::span(&counter_frames, 1)))
    throw std::runtime_error(config.can_interface + ": the CAN interface refused the receive filters");

  epoll_ = epoll_create1(EPOLL_CLOEXEC);
  for (const int fd : {io.can.fd(), io.timer.fd(), io.source ? io.source->fd() : -1, io.stop_fd}) {
    if (fd < 0) continue;
    epoll_event ev{};
    ev.events = EPOLLIN;
    ev.data.fd = fd;
    epoll_ctl(epoll_, EPOLL_CTL_ADD, fd, &ev);
  }
  // Pacing: one tick per frame, the frames of a report spread over the report period.
  io.timer.start(static_cast<std::uint64_t>(config.report_period_s * 1e9 / static_cast<double>(frames_)));
}

Board::~Board() { close(epoll_); }

std::string restore_checkpoint(std::span<const std::byte> bytes, BoardCharacterizer& cumulative, DynamicWindow& window,
                               const ReportSettings& s) {
  std::string why;
  const std::size_t size = cumulative.checkpoint_size();
  if (const RestoreStatus c = cumulative.restore(bytes); c != RestoreStatus::ok) {
    return restore_why(c, cumulative.restore_field(), cumulative.checkpoint_identity(), s.identity);
  }
  if (s.window_taus == 0) return why;
  const RestoreStatus w = window.restore(bytes.subspan(std::min(size, bytes.size())));
  if (w != RestoreStatus::ok) {
    why = "window part: " + restore_why(w, window.restore_field(), window.pyramid().checkpoint_identity(), s.identity);
  } else if (window.samples() != cumulative.increments()) {  // both see every sample
    why = "window part: invalid state: window: samples (not the cumulative count)";
  } else {
    return why;
  }
  configure(cumulative, s);  // start afresh: the cumulative part was taken already
  window.configure(s.stride_factor, s.config_hash, s.window_taus, s.window_length, s.identity);
  return why;
}

std::string Board::resume() {
  if (config_.checkpoint_path.empty()) return "no checkpoint file configured";
  const long n = checkpoint_file_.read(checkpoint_buffer_);
  if (n == -ENOENT) return "no checkpoint at " + checkpoint_file_.path() + ": starting fresh";
  std::string why;
  if (n < 0) {
    why = n == -EFBIG ? "larger than any checkpoint of this configuration" : std::strerror(static_cast<int>(-n));
  } else {
    why = restore_checkpoint(std::span(checkpoint_buffer_).first(static_cast<std::size_t>(n)), characterizer_, window_,
                             settings_);
    if (why.empty()) {
      ++faults_.sample_gaps;  // the restart is a gap
      return "resumed from " + checkpoint_file_.path() + ": " + std::to_string(characterizer_.increments()) + " samples";
    }
  }
  const int e = checkpoint_file_.set_aside();
  return "checkpoint " + checkpoint_file_.path() + " not used: " + why + "; starting fresh" +
         (e == 0 ? ", the file is kept as " + checkpoint_file_.aside_path()
                 : std::string(", and it could not be kept aside: ") + std::strerror(e));
}

int Board::checkpoint() {
  if (config_.checkpoint_path.empty()) return 0;
  std::size_t n = characterizer_.save(checkpoint_buffer_);
  if (settings_.window_taus != 0) n += window_.save(std::span(checkpoint_buffer_).subspan(n));
  const int e = checkpoint_file_.write(std::span(checkpoint_buffer_).first(n));
  if (e != 0) {
    ++checkpoint_failures_;
    BOARD_LOG("3", "checkpoint %s: %s", shown_path_.c_str(), std::strerror(e));
  }
  return e;
}

void Board::on_sample(const hal::CountSample& s) {
  faults_.lost_edges += s.lost_edges;
  if (s.gap) {
    ++faults_.sample_gaps;  // a new segment, never bridged
    characterizer_.mark_gap();
    if (settings_.window_taus != 0) window_.mark_gap();
    return;
  }
  characterizer_.add_increment(static_cast<std::int32_t>(s.count));
  if (settings_.window_taus != 0) window_.add(static_cast<std::int32_t>(s.count));
}

void Board::on_frames() {
  for (int k = 0; k < 256; ++k) {  // bounded work per wake-up: an input storm cannot starve the rest
    const auto f = io_.can.receive();
    if (!f) break;
    if (io_.source == nullptr) can_counter_.on_frame(*f, io_.clock.now_ns(), *this);
  }
}

void Board::watch_bus() {
  const hal::BusState state = io_.can.state();
  if (state == last_state_) return;
  static constexpr const char* names[] = {"error-active", "error-warning", "error-passive", "bus-off", "down"};
  if (state == hal::BusState::active)
    BOARD_LOG("6", "CAN bus %s again (was %s): reports resume", names[0], names[static_cast<int>(last_state_)]);
  else
    BOARD_LOG("4", "CAN bus %s: accumulation goes on, reports are dropped until it recovers",
              names[static_cast<int>(state)]);
  last_state_ = state;
}

void Board::on_tick() {
  if (frame_ == 0) {
    faults_.tx_dropped_frames = static_cast<std::uint32_t>(io_.can.counters().tx_dropped);
    faults_.bus_off_events = static_cast<std::uint32_t>(io_.can.counters().bus_off_events);
    build_report(characterizer_, settings_, seq_, (io_.clock.now_ns() - start_ns_) / 1000000u, faults_, report_work_,
                 content_, &window_.latest());
    frames_ = protocol::report_frame_count(seq_, config_.octaves, protocol::version, settings_.window_taus);
    if (config_.verbose)
      BOARD_LOG("7", "report %u: %llu samples", static_cast<unsigned>(seq_),
                static_cast<unsigned long long>(characterizer_.increments()));
  }
  CanFrame f;
  if (protocol::encode(report_message(content_, frame_), config_.node, f) == protocol::ProtocolError::none)
    io_.can.send(f);  // a full queue or a downed bus is counted by the backend, never waited for
  if (++frame_ >= frames_) {
    frame_ = 0;
    ++seq_;
  }
}

bool Board::run_once(int timeout_ms) {
  epoll_event events[8];
  const int n = epoll_wait(epoll_, events, 8, timeout_ms);
  if (n < 0 && errno != EINTR) {
    BOARD_LOG("3", "epoll: %s", std::strerror(errno));
    return false;
  }
  bool ticked = false;
  for (int i = 0; i < n; ++i) {
    const int fd = events[i].data.fd;
    if (fd == io_.stop_fd) return false;
    if (fd == io_.can.fd()) on_frames();
    if (fd == io_.timer.fd()) ticked = true;
  }
  // The source is polled on every pass: input closes intervals, and so does time passing.
  if (io_.source != nullptr) io_.source->poll(io_.clock.now_ns(), *this);
  if (ticked) {
    const std::uint64_t expirations = io_.timer.take_expirations();
    for (std::uint64_t k = 0; k < expirations && k < 64; ++k) on_tick();  // bounded catch-up
    watch_bus();
  }
  if (checkpoint_period_ns_ != 0 && !config_.checkpoint_path.empty() && io_.clock.now_ns() >= next_checkpoint_ns_) {
    checkpoint();
    next_checkpoint_ns_ = io_.clock.now_ns() + checkpoint_period_ns_;
  }
  return true;
}

}  // namespace gyrochar::firmware
