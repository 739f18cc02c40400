#pragma once
// The board's IEEE-952 fit, made beside the report loop. A fit on a young run costs a few hundred
// million instructions (the covariance of every pair of its points, before the covariance cache's
// sums turn linear): more than a report period on a small board, and a stall the count sources
// cannot afford (the GPIO line's event buffer holds 16 edges). So gyrochard hands the points to a
// thread of the lowest priority (SCHED_IDLE) and goes on; each report that carries the Ieee952
// frames sends the latest finished fit. Inline mode fits at once, in the caller's thread: the host
// tests and the demo (on its virtual clock) use it, so that their runs repeat exactly.
// Everything is allocated in the constructor; request() and latest() allocate nothing.
#include <array>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <span>
#include <thread>
#include <vector>

#include "gyrochar/ieee952.hpp"
#include "gyrochar/noise_model.hpp"

namespace gyrochar::firmware {

enum class FitMode : std::uint8_t { inline_fit, background };

class FitWorker {
 public:
  static constexpr std::size_t max_points = 80;  // both curves of 40 octave taus

  FitWorker(unsigned octaves, FitMode mode);
  ~FitWorker();
  FitWorker(const FitWorker&) = delete;
  FitWorker& operator=(const FitWorker&) = delete;

  /// Fits `points` (at most 2 per octave) made from `samples` samples: at once in inline mode; in
  /// background mode handed to the worker, unless it is still busy with the previous ones (then
  /// nothing happens and requested_samples() stays).
  void request(std::span<const FitPoint> points, const FitSetup& setup, std::uint64_t samples);
  /// The samples of the last points taken (0: none yet).
  std::uint64_t requested_samples() const;
  /// The latest finished fit and the samples it was made from (0: no fit finished yet; the fit is
  /// then the default one, status too_few_points, no points).
  struct Result {
    Ieee952Fit fit;
    std::uint64_t samples = 0;
  };
  Result latest() const;

 private:
  void fit_job();  // job_ -> result_, in the calling thread
  void run();      // the worker thread

  FitMode mode_;
  std::vector<double> workspace_;
  std::vector<PairSumCache::Entry> entries_;
  PairSumCache cache_;
  // The job: written by request() only while no fit is under way.
  std::array<FitPoint, max_points> points_{};
  std::size_t n_points_ = 0;
  FitSetup setup_{};
  std::uint64_t job_samples_ = 0;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  bool busy_ = false, stop_ = false;
  Result result_;
  std::thread thread_;  // last: started once everything above is built
};

}  // namespace gyrochar::firmware
