#pragma once
// 4x quadrature decoding of A/B edge events, binned by edge timestamp into tau0 intervals. Pure
// logic (no OS): the libgpiod backend and the host tests feed it the same way.
//
// Sense: A leading B (00 -> 10 -> 11 -> 01 -> 00, written AB) counts up. An event that does not
// change its line's level means the opposite edge of that line was missed: one lost edge, no count
// (the missed edge and this one cancel), and the interval is flagged. An edge whose timestamp falls
// in an interval already delivered (it reached us after the interval was closed) is late: it
// counts in the open interval, so the phase stays right, and is counted. Intervals without edges
// are held back: when edges resume they are delivered as zeros, but a silence longer than
// `max_silent_intervals` is a stall (a dithered gyro is never silent that long) and is delivered
// as one gap sample, which also keeps the work per call bounded after a clock jump. Samples
// therefore arrive in order, at most max_silent_intervals late.
#include <cstdint>

#include "hal/count_source.hpp"

namespace gyrochar::hal {

struct QuadratureSettings {
  std::uint64_t start_ns = 0;  // start of interval 0
  std::uint64_t tau0_ns = 1000000;
  std::uint64_t close_margin_ns = 0;  // an interval is closed this long after its end
  std::uint64_t max_silent_intervals = 1000;
  bool initial_a = false, initial_b = false;  // line levels at start
};

enum class QuadratureLine : std::uint8_t { a, b };

class QuadratureDecoder {
 public:
  explicit QuadratureDecoder(const QuadratureSettings& settings);
  /// One edge (the line's new level), in timestamp order.
  void on_edge(std::uint64_t t_ns, QuadratureLine line, bool level, CountSink& sink);
  /// Delivers every interval that ends at least close_margin_ns before `now_ns`.
  void close_until(std::uint64_t now_ns, CountSink& sink);
  const CountSourceCounters& counters() const { return counters_; }

 private:
  std::uint64_t interval_of(std::uint64_t t_ns) const;
  void advance_to(std::uint64_t interval, CountSink& sink);  // closes [open_, interval)
  void emit(std::int64_t count, std::uint32_t lost, std::uint64_t end_interval, CountSink& sink,
            std::uint64_t gap_intervals = 0);  // gap_intervals > 0: a gap sample
  QuadratureSettings s_;
  bool a_, b_;
  std::uint64_t open_ = 0;    // index of the open interval
  std::int64_t count_ = 0;    // its count so far
  std::uint32_t lost_ = 0;    // its lost edges so far
  bool active_ = false;       // it saw an edge
  std::uint64_t silent_ = 0;  // closed intervals without edges, not yet delivered
  CountSourceCounters counters_;
};

}  // namespace gyrochar::hal
