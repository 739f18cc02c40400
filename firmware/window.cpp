#include "window.hpp"

#include <cmath>
#include <cstdint>
#include <cstring>

#include "gyrochar/crc32.hpp"

namespace gyrochar::firmware {

unsigned window_taus(unsigned octaves, std::uint64_t length) {
  unsigned taus = 0;
  while (taus < octaves && taus < max_window_taus && (std::uint64_t{4} << taus) <= length) ++taus;
  return taus;
}

bool DynamicWindow::configure(std::uint32_t stride_factor, std::uint32_t tag, unsigned taus, std::uint64_t length,
                              std::uint32_t identity) {
  length_ = 0;
  windows_ = 0;
  latest_ = WindowCurve{};
  if (taus < 1 || taus > max_window_taus || stride_factor > max_stride_factor || (std::uint64_t{4} << (taus - 1)) > length)
    return false;
  std::array<std::uint64_t, max_window_taus> m_list{};
  for (unsigned k = 0; k < taus; ++k) m_list[k] = std::uint64_t{1} << k;
  if (pyramid_.configure({stride_factor, tag, identity}, std::span(m_list.data(), taus)) != ConfigureStatus::ok)
    return false;
  length_ = length;
  return true;
}

void DynamicWindow::add(std::int32_t count) {
  pyramid_.add_increment(count);
  if (pyramid_.increments() == length_) complete_window();
}

void DynamicWindow::mark_gap() { pyramid_.mark_gap(); }

void DynamicWindow::complete_window() {
  WindowCurve& c = latest_;
  c.complete = true;
  c.window = static_cast<std::uint32_t>(windows_++);
  c.gaps = static_cast<std::uint32_t>(pyramid_.gaps());
  for (std::size_t i = 0; i < pyramid_.tau_count(); ++i) {
    const auto r = pyramid_.result(i);
    c.avar[i] = variance(r, SumKind::avar, 1.0);
    c.mvar[i] = variance(r, SumKind::mvar, 1.0);
    c.valid[i] = r.n[static_cast<std::size_t>(SumKind::avar)] > 0 && r.n[static_cast<std::size_t>(SumKind::mvar)] > 0 &&
                 r.out_of_range == 0 && !r.sum_overflow;
  }
  pyramid_.restart();
}

std::size_t DynamicWindow::checkpoint_size() const {
  return pyramid_.checkpoint_size() + sizeof windows_ + sizeof latest_ + sizeof(std::uint32_t);
}

std::size_t DynamicWindow::save(std::span<std::byte> out) const {
  if (out.size() < checkpoint_size()) return 0;
  std::size_t n = pyramid_.save(out);
  const std::size_t begin = n;
  std::memcpy(out.data() + n, &windows_, sizeof windows_);
  n += sizeof windows_;
  std::memcpy(out.data() + n, &latest_, sizeof latest_);
  n += sizeof latest_;
  const std::uint32_t crc = crc32(out.subspan(begin, n - begin));
  std::memcpy(out.data() + n, &crc, sizeof crc);
  return n + sizeof crc;
}

namespace {

std::uint8_t byte_of(const bool& flag) {
  std::uint8_t b = 0;
  std::memcpy(&b, &flag, 1);
  return b;
}

// The windows completed and the latest curve, as complete_window() leaves them: the curve of window
// windows - 1 (none before the first: all zero), flags 0 or 1, variances finite and not negative,
// zero beyond the window's taus. The flags are read as bytes first: any byte pattern is safe.
// Returns the field that fails, or nullptr.
const char* invalid_curve(std::uint64_t windows, const WindowCurve& c, unsigned taus) {
  const std::uint8_t complete = byte_of(c.complete);
  if (complete > 1 || (complete == 1) != (windows > 0)) return "window: latest.complete";
  if (complete == 0 ? c.window != 0 || c.gaps != 0 : windows - 1 > UINT32_MAX || c.window != windows - 1)
    return "window: latest.window (windows completed)";
  for (std::size_t i = 0; i < max_window_taus; ++i) {
    const bool used = complete == 1 && i < taus;
    const std::uint8_t valid = byte_of(c.valid[i]);
    if (valid > (used ? 1 : 0)) return "window: latest.valid";
    if (!(std::isfinite(c.avar[i]) && c.avar[i] >= 0 && std::isfinite(c.mvar[i]) && c.mvar[i] >= 0) ||
        (!used && (c.avar[i] != 0 || c.mvar[i] != 0)))
      return "window: latest.avar/mvar";
  }
  return nullptr;
}

}  // namespace

RestoreStatus DynamicWindow::restore(std::span<const std::byte> in) {
  const std::size_t pyramid_bytes = pyramid_.checkpoint_size();
  restore_field_ = nullptr;
  if (length_ == 0) return RestoreStatus::config_mismatch;  // not configured: no window to restore
  if (in.size() < checkpoint_size()) return RestoreStatus::truncated;
  const std::span<const std::byte> own = in.subspan(pyramid_bytes, sizeof windows_ + sizeof latest_);
  std::uint32_t crc = 0;
  std::memcpy(&crc, in.data() + pyramid_bytes + own.size(), sizeof crc);
  if (crc != crc32(own)) return RestoreStatus::corrupted;
  std::uint64_t windows = 0;
  WindowCurve latest;
  std::memcpy(&windows, own.data(), sizeof windows);
  std::memcpy(&latest, own.data() + sizeof windows, sizeof latest);
  restore_field_ = invalid_curve(windows, latest, taus());
  if (restore_field_ == nullptr && windows > UINT64_MAX / length_) restore_field_ = "window: windows completed";
  if (restore_field_ != nullptr) return RestoreStatus::invalid_state;
  if (const RestoreStatus s = pyramid_.restore(in.first(pyramid_bytes)); s != RestoreStatus::ok) return s;
  if (pyramid_.increments() >= length_) {  // a window completes at length samples and starts afresh
    restore_field_ = "window: samples in the window";
    pyramid_.restart();
    return RestoreStatus::invalid_state;
  }
  windows_ = windows;
  latest_ = latest;
  return RestoreStatus::ok;
}

}  // namespace gyrochar::firmware
