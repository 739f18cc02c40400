#include "hal/fake/fake_count_source.hpp"

#include <sys/eventfd.h>
#include <unistd.h>

#include <cerrno>
#include <system_error>

namespace gyrochar::hal {

FakeCountSource::FakeCountSource() : fd_(eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC)) {
  if (fd_ < 0) throw std::system_error(errno, std::generic_category(), "eventfd");
}

FakeCountSource::~FakeCountSource() { close(fd_); }

void FakeCountSource::signal() {
  std::uint64_t drained = 0;
  [[maybe_unused]] const auto r = read(fd_, &drained, sizeof drained);
  if (!samples_.empty() || !edges_.empty()) {
    const std::uint64_t one = 1;
    [[maybe_unused]] const auto w = write(fd_, &one, sizeof one);
  }
}

void FakeCountSource::script_counts(std::uint64_t start_ns, std::uint64_t tau0_ns, const std::int64_t* counts,
                                    std::size_t n) {
  for (std::size_t k = 0; k < n; ++k) {
    CountSample s;
    s.count = counts[k];
    s.end_ns = start_ns + (k + 1) * tau0_ns;
    samples_.push_back(s);
  }
  signal();
}

void FakeCountSource::push(const CountSample& sample) {
  samples_.push_back(sample);
  signal();
}

void FakeCountSource::use_quadrature(const QuadratureSettings& settings) { decoder_.emplace(settings); }

void FakeCountSource::push_edge(std::uint64_t t_ns, QuadratureLine line, bool level) {
  edges_.push_back({t_ns, line, level});
  signal();
}

void FakeCountSource::poll(std::uint64_t now_ns, CountSink& sink) {
  for (std::size_t k = 0; k < batch && !samples_.empty() && samples_.front().end_ns <= now_ns; ++k) {
    sink.on_sample(samples_.front());
    ++counters_.samples;
    counters_.lost_edges += samples_.front().lost_edges;
    if (samples_.front().gap) {
      ++counters_.gaps;
      counters_.gap_intervals += samples_.front().gap_intervals;
    }
    samples_.pop_front();
  }
  if (decoder_) {
    for (std::size_t k = 0; k < batch && !edges_.empty() && edges_.front().t_ns <= now_ns; ++k) {
      decoder_->on_edge(edges_.front().t_ns, edges_.front().line, edges_.front().level, sink);
      edges_.pop_front();
    }
    // With a backlog left (an edge storm), time must not close intervals its edges belong to.
    if (edges_.empty() || edges_.front().t_ns > now_ns) decoder_->close_until(now_ns, sink);
  }
  signal();
}

const CountSourceCounters& FakeCountSource::counters() const { return decoder_ ? decoder_->counters() : counters_; }

}  // namespace gyrochar::hal
