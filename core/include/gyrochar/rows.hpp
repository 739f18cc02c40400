#pragma once
// Work that splits into independent rows a host may spread over its threads: the fit's exact
// Markov sums (ieee952.hpp), TheoBR's bias ratio (total.hpp). Core has no threads: it hands the
// rows to the RowRunner the host gives, or runs them in turn itself (the board, the MCU).
#include <cstddef>

namespace gyrochar {

/// row(i) for each i < count, each once, in any order, on any thread. A plain function and its
/// context, not a virtual call: core is built without RTTI, and the sanitizers' type check in a
/// host built with it would take a core object's vtable for an invalid one.
struct Rows {
  void (*run_row)(void* context, std::size_t i) = nullptr;
  void* context = nullptr;
  void row(std::size_t i) const { run_row(context, i); }
};

/// What runs rows on a host's threads. run() returns once every row is done.
class RowRunner {
 public:
  virtual void run(const Rows& rows, std::size_t count) const = 0;

 protected:
  ~RowRunner() = default;
};

/// The rows on `runner`, or in turn here when it is null.
inline void run_rows(const RowRunner* runner, const Rows& rows, std::size_t count) {
  if (runner != nullptr) {
    runner->run(rows, count);
  } else {
    for (std::size_t i = 0; i < count; ++i) rows.row(i);
  }
}

}  // namespace gyrochar
