#pragma once
// Fully overlapped Allan variance of integer pulse counts, straight from the definition (the oracle
// the simulator tests measure with, independent of the analysis engine): phase x_k = sum of the
// first k counts (x_0 = 0), and for each averaging factor m every term x[j+2m] - 2x[j+m] + x[j],
// j = 0 .. N - 2m. Terms are exact 64-bit integers, their squares summed exactly in 128 bits.
// Streaming: a ring of the last 2 m_max + 1 phase points (rounded up to a power of two), O(taus)
// work per count, no allocation after construction.
#include <cstdint>
#include <stdexcept>
#include <utility>
#include <vector>

namespace gyrochar::oracle {

class OverlappingAvar {
 public:
  explicit OverlappingAvar(std::vector<std::uint64_t> m_list) : m_(std::move(m_list)), sum_(m_.size(), 0), n_(m_.size(), 0) {
    std::uint64_t m_max = 1;
    for (std::uint64_t m : m_) m_max = m > m_max ? m : m_max;
    std::uint64_t size = 1;
    while (size < 2 * m_max + 1) size *= 2;
    ring_.assign(size, 0);
    mask_ = size - 1;
  }

  void add(std::int64_t count) {
    x_ += count;
    ++k_;
    ring_[k_ & mask_] = x_;
    for (std::size_t i = 0; i < m_.size(); ++i) {
      const std::uint64_t m = m_[i];
      if (k_ < 2 * m) continue;
      const std::int64_t d = x_ - 2 * ring_[(k_ - m) & mask_] + ring_[(k_ - 2 * m) & mask_];
      sum_[i] += static_cast<unsigned __int128>(static_cast<__int128>(d) * d);
      ++n_[i];
    }
  }

  std::size_t size() const { return m_.size(); }
  std::uint64_t m(std::size_t i) const { return m_[i]; }
  std::uint64_t terms(std::size_t i) const { return n_[i]; }
  /// AVAR at m_list[i] in (pulse / s)^2: sum d^2 / (2 n tau^2), tau = m tau0.
  double avar(std::size_t i, double tau0_s) const {
    if (n_[i] == 0) throw std::logic_error("no term yet");
    const double tau = static_cast<double>(m_[i]) * tau0_s;
    return static_cast<double>(sum_[i]) / (2.0 * static_cast<double>(n_[i]) * tau * tau);
  }

 private:
  std::vector<std::uint64_t> m_;
  std::vector<unsigned __int128> sum_;
  std::vector<std::uint64_t> n_;
  std::vector<std::int64_t> ring_;
  std::uint64_t mask_ = 0, k_ = 0;
  std::int64_t x_ = 0;
};

}  // namespace gyrochar::oracle
