#include "hal/can_counter.hpp"

#include "gyrochar/wire/protocol.hpp"

namespace gyrochar::hal {

bool CanCounterDecoder::on_frame(const CanFrame& frame, std::uint64_t now_ns, CountSink& sink) {
  if (frame.error) return false;
  const protocol::Decoded d = protocol::decode(frame);
  if (d.error != protocol::ProtocolError::none || d.node != node_) return false;
  const auto* in = std::get_if<protocol::CounterInputMsg>(&d.message);
  if (in == nullptr) return false;
  ++counters_.edges;
  if (in->count_error) ++counters_.lost_edges;
  if (have_reference_) {
    const auto missed = static_cast<std::uint8_t>(in->seq - last_seq_ - 1);
    CountSample sample;
    sample.end_ns = now_ns;
    if (missed != 0 || in->count_error || in->sensor_not_ready) {
      sample.gap = true;
      sample.gap_intervals = missed + 1u;
      sample.lost_edges = in->count_error ? 1 : 0;
      ++counters_.gaps;
      counters_.gap_intervals += sample.gap_intervals;
    } else {
      sample.count = static_cast<std::int32_t>(in->count - last_count_);
    }
    sink.on_sample(sample);
    ++counters_.samples;
  }
  have_reference_ = true;
  last_count_ = in->count;
  last_seq_ = in->seq;
  return true;
}

}  // namespace gyrochar::hal
