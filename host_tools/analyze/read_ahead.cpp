// The data file's blocks read ahead on a thread of their own (read_ahead.hpp).
#include "read_ahead.hpp"

namespace gyrochar {

ReadAhead::ReadAhead(DataFile& file, std::size_t block, std::size_t depth) : file_(file), ring_(depth < 2 ? 2 : depth) {
  for (Block& b : ring_) b.values.resize(block < 1 ? 1 : block);
  thread_ = std::jthread([this](std::stop_token stop) { read(stop); });
}

ReadAhead::~ReadAhead() = default;  // thread_'s: asks it to stop (its wait for room ends), then joins it

void ReadAhead::read(std::stop_token stop) {
  for (;;) {
    std::size_t slot = 0;
    {
      std::unique_lock lock(mutex_);
      changed_.wait(lock, stop, [&] { return filled_ < ring_.size(); });
      if (stop.stop_requested()) return;  // left early: no more blocks
      slot = (head_ + filled_) % ring_.size();
    }
    Block& b = ring_[slot];  // not the held block, nor one filled: only this thread touches it
    try {
      b.n = file_.read(b.values);
      b.lines.resize(b.n);
      for (std::size_t i = 0; i < b.n; ++i) b.lines[i] = file_.line_of(i);
      b.bytes = file_.bytes_read();
    } catch (...) {
      const std::lock_guard lock(mutex_);
      error_ = std::current_exception();
      ended_ = true;
      changed_.notify_all();
      return;
    }
    const std::lock_guard lock(mutex_);
    if (b.n == 0) ended_ = true;
    else ++filled_;
    changed_.notify_all();
    if (b.n == 0) return;
  }
}

std::span<double> ReadAhead::next() {
  std::unique_lock lock(mutex_);
  if (held_) {  // the caller is done with the block it had: its slot is free again
    held_ = false;
    head_ = (head_ + 1) % ring_.size();
    --filled_;
    changed_.notify_all();
  }
  changed_.wait(lock, [&] { return filled_ > 0 || ended_; });
  if (filled_ == 0) {
    if (error_) std::rethrow_exception(error_);
    return {};
  }
  held_ = true;
  return {ring_[head_].values.data(), ring_[head_].n};
}

}  // namespace gyrochar
