#include "hal/quadrature.hpp"

namespace gyrochar::hal {

QuadratureDecoder::QuadratureDecoder(const QuadratureSettings& settings)
    : s_(settings), a_(settings.initial_a), b_(settings.initial_b) {}

std::uint64_t QuadratureDecoder::interval_of(std::uint64_t t_ns) const {
  return t_ns < s_.start_ns ? 0 : (t_ns - s_.start_ns) / s_.tau0_ns;
}

void QuadratureDecoder::emit(std::int64_t count, std::uint32_t lost, std::uint64_t end_interval, CountSink& sink,
                             std::uint64_t gap_intervals) {
  CountSample sample;
  sample.count = count;
  sample.lost_edges = lost;
  sample.end_ns = s_.start_ns + end_interval * s_.tau0_ns;
  sample.gap = gap_intervals != 0;
  sample.gap_intervals = gap_intervals;
  sink.on_sample(sample);
  ++counters_.samples;
  if (sample.gap) {
    ++counters_.gaps;
    counters_.gap_intervals += gap_intervals;
  }
}

void QuadratureDecoder::advance_to(std::uint64_t interval, CountSink& sink) {
  if (interval <= open_) return;
  if (active_) {  // the open interval saw edges: the silence before it was real zeros
    for (std::uint64_t k = silent_; k > 0; --k) emit(0, 0, open_ + 1 - k, sink);
    silent_ = 0;
    emit(count_, lost_, open_ + 1, sink);
  } else {
    ++silent_;
  }
  silent_ += interval - open_ - 1;
  open_ = interval;
  count_ = 0;
  lost_ = 0;
  active_ = false;
  if (silent_ > s_.max_silent_intervals) {  // a stall: one gap sample, however long
    emit(0, 0, open_, sink, silent_);
    silent_ = 0;
  }
}

void QuadratureDecoder::on_edge(std::uint64_t t_ns, QuadratureLine line, bool level, CountSink& sink) {
  ++counters_.edges;
  const std::uint64_t interval = interval_of(t_ns);
  if (interval < open_) ++counters_.late_edges;
  else advance_to(interval, sink);
  active_ = true;
  bool& changed = line == QuadratureLine::a ? a_ : b_;
  if (changed == level) {  // the opposite edge of this line was missed
    ++lost_;
    ++counters_.lost_edges;
    return;
  }
  changed = level;
  const bool up = line == QuadratureLine::a ? a_ != b_ : b_ == a_;
  count_ += up ? 1 : -1;
}

void QuadratureDecoder::close_until(std::uint64_t now_ns, CountSink& sink) {
  if (now_ns < s_.start_ns + s_.close_margin_ns) return;
  advance_to(interval_of(now_ns - s_.close_margin_ns), sink);
}

}  // namespace gyrochar::hal
