#pragma once
// A scripted count source for host tests: either count samples (delivered once the clock passes
// their end) or quadrature edges (decoded by the real QuadratureDecoder). Script before polling;
// polling never allocates. The eventfd is readable while scripted input waits.
#include <cstdint>
#include <deque>
#include <optional>

#include "hal/count_source.hpp"
#include "hal/quadrature.hpp"

namespace gyrochar::hal {

class FakeCountSource final : public CountSource {
 public:
  FakeCountSource();
  ~FakeCountSource() override;
  FakeCountSource(const FakeCountSource&) = delete;
  FakeCountSource& operator=(const FakeCountSource&) = delete;

  /// Scripted counts: `counts[k]` for the interval ending at start_ns + (k+1) tau0_ns.
  void script_counts(std::uint64_t start_ns, std::uint64_t tau0_ns, const std::int64_t* counts, std::size_t n);
  void push(const CountSample& sample);
  /// Scripted edges instead, decoded with these settings.
  void use_quadrature(const QuadratureSettings& settings);
  void push_edge(std::uint64_t t_ns, QuadratureLine line, bool level);

  int fd() const override { return fd_; }
  void poll(std::uint64_t now_ns, CountSink& sink) override;
  const CountSourceCounters& counters() const override;

  static constexpr std::size_t batch = 256;  // input items per poll

 private:
  struct Edge {
    std::uint64_t t_ns;
    QuadratureLine line;
    bool level;
  };
  void signal();
  std::deque<CountSample> samples_;
  std::deque<Edge> edges_;
  std::optional<QuadratureDecoder> decoder_;
  CountSourceCounters counters_;
  int fd_ = -1;
};

}  // namespace gyrochar::hal
