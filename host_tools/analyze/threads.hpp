#pragma once
// Independent pieces of the analyzer's work on several threads: the total family's taus
// (total_analysis.cpp), the fit's pair sums and rows (report_fit.cpp), TheoBR's bias ratio. Each
// piece writes its own result, so the results are the same bits on any number of threads.
#include <algorithm>
#include <atomic>
#include <cstddef>
#include <future>
#include <thread>
#include <vector>

#include "gyrochar/rows.hpp"

namespace gyrochar {

/// The threads `asked` stands for (--threads): one per core when 0.
inline unsigned thread_count(unsigned asked) {
  return asked > 0 ? asked : std::max(1u, std::thread::hardware_concurrency());
}

/// body(worker, i) for every i < count, each once: on this thread (worker 0, which takes i = 0) and
/// threads - 1 more (workers 1 ..), each taking the next i not yet taken. An exception in a body
/// reaches the caller once every thread has stopped.
template <class Body>
void on_threads(unsigned threads, std::size_t count, const Body& body) {
  std::atomic<std::size_t> next{0};
  const auto work = [&](unsigned worker, std::size_t i) {
    for (; i < count; i = next++) body(worker, i);
  };
  const std::size_t first = next++;
  std::vector<std::future<void>> helpers;
  for (unsigned k = 1; k < threads && k < count; ++k) helpers.push_back(std::async(std::launch::async, work, k, next++));
  try {
    work(0, first);
  } catch (...) {
    next = count;
    for (std::future<void>& h : helpers) h.wait();
    throw;
  }
  for (std::future<void>& h : helpers) h.get();
}

/// Core's rows (rows.hpp) on `threads` threads.
class ThreadRows final : public RowRunner {
 public:
  explicit ThreadRows(unsigned threads) : threads_(threads) {}
  void run(const Rows& rows, std::size_t count) const override {
    on_threads(threads_, count, [&](unsigned, std::size_t i) { rows.row(i); });
  }

 private:
  unsigned threads_;
};

}  // namespace gyrochar
