#include "fit_worker.hpp"

#include <pthread.h>
#include <sched.h>

#include <algorithm>

namespace gyrochar::firmware {

FitWorker::FitWorker(unsigned octaves, FitMode mode)
    : mode_(mode),
      workspace_(ieee952_workspace_doubles(2 * octaves)),
      // Every pair of the fit's points (both curves of every tau): a table less than half full
      // keeps the probes short.
      entries_(std::size_t{octaves} * octaves * 4 * 2 + 64),
      cache_(entries_) {
  if (mode_ == FitMode::background) thread_ = std::thread([this] { run(); });
}

FitWorker::~FitWorker() {
  if (!thread_.joinable()) return;
  {
    const std::lock_guard lock(mutex_);
    stop_ = true;
  }
  wake_.notify_one();
  thread_.join();  // a fit under way is finished first (seconds at most)
}

void FitWorker::request(std::span<const FitPoint> points, const FitSetup& setup, std::uint64_t samples) {
  {
    const std::lock_guard lock(mutex_);
    if (busy_) return;
    n_points_ = std::min(points.size(), points_.size());
    std::copy_n(points.begin(), n_points_, points_.begin());
    setup_ = setup;  // with model selection (protocol version 4 carries the model's terms)
    job_samples_ = samples;
    busy_ = true;
  }
  if (mode_ == FitMode::inline_fit) {
    fit_job();
    return;
  }
  wake_.notify_one();
}

std::uint64_t FitWorker::requested_samples() const {
  const std::lock_guard lock(mutex_);
  return job_samples_;
}

FitWorker::Result FitWorker::latest() const {
  const std::lock_guard lock(mutex_);
  return result_;
}

void FitWorker::fit_job() {
  // The job's fields are not written while busy_ is set: read them without the lock.
  const Ieee952Fit fit = fit_ieee952(std::span(points_.data(), n_points_), setup_, FitCurve::both, workspace_, &cache_);
  const std::lock_guard lock(mutex_);
  result_ = {fit, job_samples_};
  busy_ = false;
}

void FitWorker::run() {
  // Only what nothing else wants: the report loop and the count sources always come first.
  const sched_param idle{};
  pthread_setschedparam(pthread_self(), SCHED_IDLE, &idle);  // best effort: a plain thread otherwise
  for (;;) {
    {
      std::unique_lock lock(mutex_);
      wake_.wait(lock, [this] { return busy_ || stop_; });
      if (stop_) return;
    }
    fit_job();
  }
}

}  // namespace gyrochar::firmware
