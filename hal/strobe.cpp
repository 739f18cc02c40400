#include "hal/strobe.hpp"

namespace gyrochar::hal {

void StrobeDecoder::on_strobe(std::uint64_t t_ns, std::uint64_t counter_value, CountSink& sink) {
  ++counters_.edges;
  if (!have_reference_) {
    have_reference_ = true;
    last_t_ns_ = t_ns;
    last_value_ = counter_value;
    return;
  }
  const std::uint64_t dt = t_ns - last_t_ns_;
  if (2 * dt < s_.tau0_ns) {  // a glitch on the strobe line
    ++counters_.lost_edges;
    return;
  }
  std::int64_t count = static_cast<std::int64_t>(counter_value - last_value_);
  if (s_.counter_bits < 64) {
    const std::uint64_t modulus = std::uint64_t{1} << s_.counter_bits;
    const std::uint64_t diff = (counter_value - last_value_) & (modulus - 1);
    count = diff >= modulus / 2 ? static_cast<std::int64_t>(diff) - static_cast<std::int64_t>(modulus)
                                : static_cast<std::int64_t>(diff);
  }
  CountSample sample;
  sample.end_ns = t_ns;
  if (2 * dt > 3 * s_.tau0_ns) {  // missed strobes: the count spans several intervals
    sample.gap = true;
    sample.gap_intervals = (dt + s_.tau0_ns / 2) / s_.tau0_ns;
    ++counters_.gaps;
    counters_.gap_intervals += sample.gap_intervals;
  } else {
    sample.count = count;
  }
  sink.on_sample(sample);
  ++counters_.samples;
  last_t_ns_ = t_ns;
  last_value_ = counter_value;
}

}  // namespace gyrochar::hal
