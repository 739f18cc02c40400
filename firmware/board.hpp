#pragma once
// The board: counts from a count source (or CounterInput frames on the bus) into the estimator,
// reports paced over each report period onto the CAN bus, checkpoints to a file. With a window
// configured, a second characterizer restarted every window gives the dynamic Allan deviation. It runs on any
// HAL backends: the Linux ones in gyrochard (main.cpp), the fakes in the host tests. Everything
// is allocated in the constructor; run_once() and checkpoint() allocate nothing.
#include <cstdint>
#include <string>
#include <vector>

#include "checkpoint.hpp"
#include "config.hpp"
#include "hal/can_bus.hpp"
#include "hal/can_counter.hpp"
#include "hal/clock.hpp"
#include "hal/count_source.hpp"
#include "report.hpp"

namespace gyrochar::firmware {

/// Restores a board checkpoint (the cumulative characterizer's bytes, then with a window the
/// window's) into characterizers configured for `settings`. Every field is checked (Characterizer::
/// restore(), DynamicWindow::restore(), and the window's sample count against the cumulative one);
/// any byte pattern is safe. Returns "" when both resumed, else why not (naming the field or the
/// identities), with both as configured, fresh. O(history + taus); allocates only the message.
std::string restore_checkpoint(std::span<const std::byte> bytes, BoardCharacterizer& cumulative, DynamicWindow& window,
                               const ReportSettings& settings);

struct BoardIo {
  hal::CanBus& can;
  hal::CountSource* source = nullptr;  // nullptr: counts come as CounterInput frames on `can`
  const hal::Clock& clock;
  hal::PeriodicTimer& timer;
  int stop_fd = -1;  // readable: stop (gyrochard's signalfd)
};

class Board final : public hal::CountSink {
 public:
  /// Throws std::invalid_argument for settings the estimator cannot hold (validate() refuses them
  /// first), std::runtime_error when the CAN interface refuses the receive filters. gyrochard fits in the
  /// background (fit_worker.hpp); the host simulation and the tests inline, to repeat exactly.
  Board(const Config& config, BoardIo io, FitMode fit_mode = FitMode::inline_fit);
  ~Board();
  Board(const Board&) = delete;
  Board& operator=(const Board&) = delete;

  /// Resumes from the checkpoint file when there is one for this configuration; returns what
  /// happened, for the log (a bad file is kept aside and the run starts fresh).
  std::string resume();
  /// One pass of the event loop: waits up to timeout_ms for input, a pacing tick or stop.
  /// Returns false once stop_fd is readable.
  bool run_once(int timeout_ms);
  /// Writes a checkpoint now (run_once also does, every checkpoint period). Returns 0 or errno.
  int checkpoint();
  /// Checkpoints that could not be written so far (each logged): gyrochard's exit status says so.
  std::uint64_t checkpoint_failures() const { return checkpoint_failures_; }

  void on_sample(const hal::CountSample& sample) override;
  const Characterizer<CountArith>& characterizer() const { return characterizer_; }
  /// The dynamic Allan deviation's window (window.hpp); taus() == 0 when the configuration has none.
  const DynamicWindow& window() const { return window_; }
  const FaultCounters& faults() const { return faults_; }
  /// True between two reports: every frame of the last report sent, the next not yet built (a run
  /// that ends here leaves no report cut off at its end).
  bool between_reports() const { return frame_ == 0; }

 private:
  void on_tick();
  void on_frames();
  void watch_bus();
  Config config_;
  BoardIo io_;
  ReportSettings settings_;
  BoardCharacterizer characterizer_;
  DynamicWindow window_;
  ReportContent content_;
  FaultCounters faults_;
  hal::CanCounterDecoder can_counter_;
  CheckpointFile checkpoint_file_;
  std::vector<std::byte> checkpoint_buffer_;
  ReportWorkspace report_work_;
  std::uint64_t start_ns_ = 0, next_checkpoint_ns_ = 0, checkpoint_period_ns_ = 0;
  std::uint64_t checkpoint_failures_ = 0;
  std::string shown_path_;  // the checkpoint path for the log, control bytes escaped
  std::uint8_t seq_ = 0;
  std::size_t frame_ = 0, frames_ = 1;
  hal::BusState last_state_ = hal::BusState::active;
  int epoll_ = -1;
};

}  // namespace gyrochar::firmware
