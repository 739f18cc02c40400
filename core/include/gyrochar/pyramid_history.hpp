#pragma once
// The pyramid's history: the past phase points the characterizer's terms read, in a fixed number
// of entries whatever the run length, over storage the caller owns.
//
// Ring level 0 keeps the last 3S points (S the stride factor); ring level l >= 1 keeps the
// multiples of 2^l with ages in (3S 2^(l-1), 3S 2^l], i.e. 3S/2 entries. A point leaving level l
// moves on to level l+1 if it is a multiple of 2^(l+1). Memory is therefore
// 3S + (levels - 1) * 3S/2 entries (history_entries()).
//
// Layout: ring 0 holds 3S entries from offset 0; ring l >= 1 holds 3S/2 entries from offset
// (l+1) 3S/2. heads[l] is the slot of phase point e >> l within ring l, i.e. (e >> l) mod
// ring_size(l). The heads belong to the characterizer's run state (they are checkpointed with it),
// so the operations that move them take them as an argument.
#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <span>

#include "gyrochar/assert.hpp"
#include "gyrochar/wide.hpp"

namespace gyrochar {

/// Entries of history needed for stride factor S and taus up to m_max. O(log m_max).
constexpr std::size_t history_entries(std::uint32_t stride_factor, std::uint64_t m_max) {
  std::size_t levels = 1;
  while ((std::uint64_t{stride_factor} << (levels - 1)) < m_max) ++levels;
  return 3u * stride_factor + (levels - 1) * (3u * stride_factor / 2);
}

/// Where the point of a given age lies: ring `ring`, `back` slots behind its head (modulo the
/// ring's size).
struct HistorySlot {
  std::uint8_t ring = 0;
  std::uint32_t back = 0;
};

/// The slot of the point of age `age` (1 <= age <= 3S 2^62) under stride factor S. O(log age).
constexpr HistorySlot history_slot(std::uint32_t stride_factor, std::uint64_t age) {
  unsigned ring = 0;
  while (3 * (std::uint64_t{stride_factor} << ring) < age) ++ring;
  // Ring 0 holds ages 1..3S: back = age. Ring l >= 1 holds ages (3S/2, 3S] * 2^l, whose
  // distance in slots, age >> l, exceeds the ring size 3S/2 once: take it off.
  const std::uint64_t back = ring == 0 ? age : (age >> ring) - 3u * stride_factor / 2;
  return {static_cast<std::uint8_t>(ring), static_cast<std::uint32_t>(back)};
}

using HistoryHeads = std::array<std::uint32_t, 64>;  // heads[l]: slot of (e >> l) in ring l

template <class Entry>
class PyramidHistory {
 public:
  /// Binds the history to storage owned by the caller, which must outlive it. No allocation.
  explicit PyramidHistory(std::span<Entry> storage) : entries_(storage) {}

  /// Stride factor S and the number of ring levels. O(1); the entries are not touched.
  void configure(std::uint32_t stride_factor, unsigned levels) {
    stride_ = stride_factor;
    levels_ = levels;
  }
  std::uint32_t stride_factor() const { return stride_; }
  unsigned levels() const { return levels_; }
  std::size_t capacity() const { return entries_.size(); }
  /// Entries in use at this configuration (what a checkpoint holds).
  std::size_t used() const { return 3u * stride_ + (levels_ - 1) * (3u * stride_ / 2); }
  Entry* data() { return entries_.data(); }
  const Entry* data() const { return entries_.data(); }
  Entry& operator[](std::size_t i) { return entries_[i]; }
  const Entry& operator[](std::size_t i) const { return entries_[i]; }

  std::uint32_t ring_size(unsigned ring) const { return ring == 0 ? 3u * stride_ : 3u * stride_ / 2; }
  std::size_t ring_offset(unsigned ring) const { return ring == 0 ? 0 : (ring + 1) * (3u * stride_ / 2); }
  /// Age at which points enter ring l: 0 for ring 0, 3S 2^(l-1) above (they leave ring l-1).
  std::uint64_t ring_lag(unsigned ring) const { return ring == 0 ? 0 : std::uint64_t{3u * stride_} << (ring - 1); }

  /// Point e from ring 0 (ages up to 3S).
  const Entry& recent(std::uint64_t e) const { return entries_[static_cast<std::size_t>(e % (3u * stride_))]; }

  /// The point `back` slots behind the head of `ring`.
  const Entry& behind(unsigned ring, std::uint32_t back, const HistoryHeads& heads) const {
    const std::uint32_t head = heads[ring];
    const std::uint32_t slot = head >= back ? head - back : head + ring_size(ring) - back;
    return entries_[ring_offset(ring) + slot];
  }

  /// Levels 0 .. countr_zero(e) run at point e; their ring heads move on by one slot. Returns how
  /// many levels run.
  unsigned advance_heads(std::uint64_t e, HistoryHeads& heads) const {
    const unsigned fired = e == 0 ? 0 : static_cast<unsigned>(std::countr_zero(e)) + 1;
    const unsigned moved = fired < levels_ ? fired : levels_;
    for (unsigned ring = 0; ring < moved; ++ring) {
      if (++heads[ring] == ring_size(ring)) heads[ring] = 0;
    }
    return fired;
  }

  /// Stores point e in ring 0 (heads advanced to it); the point it replaces (age 3S) moves on to
  /// ring 1 if it is even, and so on: the point leaving ring l has age 3S 2^l and goes to ring l+1
  /// at its head slot when it is a multiple of 2^(l+1), which is when e is.
  void insert(std::uint64_t e, Entry entry, const HistoryHeads& heads) {
    const std::uint64_t cascade_span = 3u * stride_;  // age at which a point leaves ring 0
    for (unsigned ring = 0;; ++ring) {
      Entry& cell = entries_[ring_offset(ring) + heads[ring]];
      const Entry evicted = cell;
      cell = entry;
      const unsigned next = ring + 1;
      if (next >= levels_ || (e & ((std::uint64_t{1} << next) - 1)) != 0) return;
      if (e < (cascade_span << ring)) return;  // the replaced cell was never filled
      entry = evicted;
    }
  }

  /// Points a (>= 1) .. b = a + n - 1 (x, and P in two words) enter the history as insert() would
  /// take them one by one, heads included. After point e, ring l holds the multiples q of 2^l
  /// with q <= e - ring_lag(l), the newest ring_size(l) of them, q at slot (q >> l) mod the size.
  /// So ring l takes the multiples that cross its lag within [a, b] (the newest ring_size(l)), from
  /// these points or from the lower ring that held them before; the rings are written from the top
  /// down, so each reads the rings below it before they change. O(n + rings), no allocation.
  void insert_run(std::uint64_t a, const std::int64_t* x, const std::uint64_t* p_lo, const std::uint64_t* p_hi,
                  std::size_t n, HistoryHeads& heads) {
    GYROCHAR_ASSERT(a >= 1 && n >= 1);
    const std::uint64_t b = a + n - 1;
    // Only the rings with a multiple of 2^l in [a, b] move (their lags are multiples of 2^l too).
    const auto width = static_cast<unsigned>(std::bit_width((a - 1) ^ b));
    const unsigned moved = width < levels_ ? width : levels_;
    for (unsigned l = moved; l-- > 0;) {
      const std::uint64_t lag = ring_lag(l), size = ring_size(l);
      if (b < lag) continue;
      const std::uint64_t newest = (b - lag) >> l;
      std::uint64_t first = a > lag ? ((a - 1 - lag) >> l) + 1 : 0;  // not in ring l before
      if (newest >= first + size) first = newest + 1 - size;
      Entry* ring = &entries_[ring_offset(l)];
      auto slot = static_cast<std::uint32_t>(first % size);
      std::uint64_t k = first;
      // The multiples q < a, from the rings below that held them (older q sit higher): each ring
      // holds a run of consecutive multiples, read at a fixed step of slots. Ring 0 holds every q
      // in [a - 3S, a).
      for (unsigned r = l; k <= newest && (k << l) < a;) {
        do GYROCHAR_ASSERT(r > 0);  // ring 0 holds every point of the last 3S
        while (!held(--r, k << l, a - 1));
        const std::uint64_t last = r == 0 ? a - 1 : (a - 1 - ring_lag(r)) >> r << r;  // ring r's newest
        const std::uint32_t from_size = ring_size(r);
        const auto step = static_cast<std::uint32_t>((std::uint64_t{1} << (l - r)) % from_size);
        const Entry* from = &entries_[ring_offset(r)];
        auto from_slot = static_cast<std::uint32_t>(((k << l) >> r) % from_size);
        for (; k <= newest && (k << l) <= last; ++k) {
          ring[slot] = from[from_slot];
          if (++slot == size) slot = 0;
          from_slot += step;
          if (from_slot >= from_size) from_slot -= from_size;
        }
        ++r;  // the next multiple may still sit in ring r - 1 (held() steps down from r - 1)
      }
      // The multiples q >= a, from the run itself.
      for (auto j = static_cast<std::size_t>((k << l) - a); k <= newest; ++k, j += std::size_t{1} << l) {
        ring[slot] = Entry{x[j], Int128{p_lo[j], p_hi[j]}};
        if (++slot == size) slot = 0;
      }
    }
    for (unsigned l = 0; l < moved; ++l) heads[l] = static_cast<std::uint32_t>((b >> l) % ring_size(l));
  }

  /// x and the low word of P of `count` entries of ring `ring`, from `slot` on.
  void copy_out(unsigned ring, std::uint32_t slot, std::size_t count, std::int64_t* __restrict x,
                std::uint64_t* __restrict p) const {
    GYROCHAR_ASSERT(slot < ring_size(ring) && count <= ring_size(ring));
    const Entry* from = &entries_[ring_offset(ring)];
    const std::uint32_t size = ring_size(ring);
    for (std::size_t i = 0; i < count;) {
      const std::size_t run = count - i < size - slot ? count - i : size - slot;
      for (std::size_t k = 0; k < run; ++k, ++i) {
        x[i] = from[slot + k].x;
        p[i] = from[slot + k].p.lo;
      }
      slot = 0;
    }
  }

 private:
  // Whether ring l holds point q (a multiple of 2^l) after point e.
  bool held(unsigned l, std::uint64_t q, std::uint64_t e) const {
    const std::uint64_t lag = ring_lag(l);
    return e >= lag && q <= e - lag && (q >> l) + ring_size(l) > ((e - lag) >> l);
  }

  std::span<Entry> entries_;
  std::uint32_t stride_ = 8;
  unsigned levels_ = 1;
};

}  // namespace gyrochar
