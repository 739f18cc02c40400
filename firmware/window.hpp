#pragma once
// The board's dynamic Allan deviation (DAVAR): beside the cumulative characterizer, a second one
// (the same core pyramid) that starts afresh every `length` samples. Window k holds samples
// k length .. (k+1) length - 1, exactly as if they had been cut out of the run into a file of their
// own (length + 1 phase points); when it completes, its ADEV and MDEV curve is kept until the next
// one completes, and the reports send it (protocol version 3, the Window message). A gap inside a
// window breaks it into segments as it does the cumulative run: no term spans it.
//
// Fixed memory, owned by the object (WindowPyramid: 30 octave taus, stride factor up to 64); add()
// and mark_gap() allocate nothing. docs/core.md has the memory, docs/dynamic.md what the curve shows
// and what it costs.
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "gyrochar/characterizer.hpp"
#include "capacities.hpp"

namespace gyrochar::firmware {

using WindowPyramid = StaticCharacterizer<CountArith, max_window_taus, max_stride_factor>;

/// The window taus for a node of `octaves` octave taus (m = 1, 2, 4, ...) and windows of `length`
/// samples: the taus with 4 m <= length (an MDEV estimate of at least length/4 terms, an ADEV one
/// of at least length/2), at most max_window_taus. 0 when length < 4. O(1).
unsigned window_taus(unsigned octaves, std::uint64_t length);

/// The curve of one completed window, in pulses per tau0: variance() of the core with tau0 = 1.
struct WindowCurve {
  bool complete = false;                               // false: no window has completed yet
  std::uint32_t window = 0;                            // k: the window covered samples k length .. (k+1) length - 1
  std::uint32_t gaps = 0;                              // gaps inside it (a restart from a checkpoint is one)
  std::array<double, max_window_taus> avar{}, mvar{};  // (pulses / tau0)^2
  std::array<bool, max_window_taus> valid{};           // a term formed, none out of range: avar and mvar hold
};

class DynamicWindow {
 public:
  /// Windows of `length` samples over octave taus 1 .. 2^(taus-1), with stride factor S and the
  /// checkpoint tag and identity of the cumulative characterizer. False (state unusable) for taus beyond
  /// max_window_taus, length < 4 m_max, or a stride factor the pyramid cannot hold. Resets everything.
  bool configure(std::uint32_t stride_factor, std::uint32_t tag, unsigned taus, std::uint64_t length,
                 std::uint32_t identity = 0);

  /// One sample of counts (pulses per tau0). O(S) amortized as the cumulative characterizer; at the
  /// end of a window O(taus) more, to keep its curve and restart the pyramid.
  void add(std::int32_t count);
  /// A break in the sample stream: the window goes on in a new segment. O(taus).
  void mark_gap();

  /// The latest completed window.
  const WindowCurve& latest() const { return latest_; }
  /// Samples per window, and window taus (0: not configured).
  std::uint64_t length() const { return length_; }
  unsigned taus() const { return static_cast<unsigned>(pyramid_.tau_count()); }
  /// Samples so far in the current window.
  std::uint64_t samples_in_window() const { return pyramid_.increments(); }

  /// Checkpoints: the current window's pyramid (Characterizer::save(), with its own header and
  /// CRC), then the windows completed and the latest curve, with a CRC-32. O(history + taus); no
  /// allocation. save() returns the bytes written, 0 when `out` is too small. restore() needs the
  /// same configuration and checks every field (the pyramid's as Characterizer::restore() does; the
  /// windows completed and the latest curve against each other and the window length); a restored
  /// window goes on after a gap; on failure nothing else changes (a pyramid found holding a whole
  /// window's samples is restarted).
  std::size_t checkpoint_size() const;
  std::size_t save(std::span<std::byte> out) const;
  RestoreStatus restore(std::span<const std::byte> in);
  /// After restore() returned invalid_state: the field that failed.
  const char* restore_field() const { return restore_field_ != nullptr ? restore_field_ : pyramid_.restore_field(); }
  /// Samples since the start: the windows completed and the current one's (the cumulative
  /// characterizer's count: the board checks a restored window against it).
  std::uint64_t samples() const { return windows_ * length_ + pyramid_.increments(); }
  const WindowPyramid& pyramid() const { return pyramid_; }

 private:
  void complete_window();

  WindowPyramid pyramid_;
  std::uint64_t length_ = 0;
  std::uint64_t windows_ = 0;  // windows completed since the start
  WindowCurve latest_;
  const char* restore_field_ = nullptr;
};

}  // namespace gyrochar::firmware
