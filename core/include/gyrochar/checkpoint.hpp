#pragma once
// The characterizer's checkpoint codec: the whole state as bytes (native byte order: restore on
// the same kind of board), with a format version, the caller's tag and identity, and a CRC-32 at
// the end, and the validation that makes restoring any byte pattern safe. The caller stores the
// bytes (atomically: firmware/checkpoint.hpp). Characterizer::save() and restore() are the API;
// this header is their implementation, apart from what the characterizer computes.
//
// Layout: Header, the m list (uint64 per tau), the run state, the history's used entries, the tau
// states, the CRC-32 of everything before it.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>

#include "gyrochar/crc32.hpp"

namespace gyrochar {

enum class RestoreStatus : std::uint8_t {
  ok,
  truncated,         // fewer bytes than the checkpoint needs
  not_a_checkpoint,  // wrong magic number
  wrong_version,     // written by another checkpoint format version
  corrupted,         // CRC mismatch
  config_mismatch,   // another arithmetic, stride factor, tau list or caller tag than now
  other_identity,    // written for another identity (another instrument): checkpoint_identity() has it
  invalid_state,     // the CRC holds but a field breaks the state's invariants: restore_field() names it
};

template <class Arith>
class Characterizer;

/// Tests craft checkpoints field by field through a specialization of this (the library has none).
template <class Arith>
struct CheckpointLayout;

template <class Arith>
class CheckpointCodec {
  template <class>
  friend struct CheckpointLayout;
  using C = Characterizer<Arith>;

 public:
  static constexpr std::uint32_t magic = 0x43525947;  // "GYRC"
  static constexpr std::uint16_t version = 5;         // 5: the identity in the header
  /// Phase points (and gaps) a checkpoint may count: 2^62 (146 000 years at 1 MHz); indices and
  /// counts stay far from wrapping around.
  static constexpr std::uint64_t max_phase_points = std::uint64_t{1} << 62;

  /// Bytes save() writes for c's configuration. O(1).
  static std::size_t size(const C& c) {
    return sizeof(Header) + c.ntaus_ * sizeof(std::uint64_t) + sizeof(typename C::RunState) +
           c.history_.used() * sizeof(typename C::Entry) + c.ntaus_ * sizeof(typename C::TauState) + sizeof(std::uint32_t);
  }

  /// Characterizer::save().
  static std::size_t save(const C& c, std::span<std::byte> out) {
    if (out.size() < size(c)) return 0;
    c.flush();
    std::byte* p = out.data();
    const Header h = header(c);
    p = put(p, &h, sizeof h);
    for (std::size_t i = 0; i < c.ntaus_; ++i) p = put(p, &c.taus_[i].result.m, sizeof(std::uint64_t));
    p = put(p, &c.run_, sizeof c.run_);
    p = put(p, c.history_.data(), c.history_.used() * sizeof(typename C::Entry));
    p = put(p, c.taus_.data(), c.ntaus_ * sizeof(typename C::TauState));
    const std::uint32_t crc = crc32({out.data(), static_cast<std::size_t>(p - out.data())});
    p = put(p, &crc, sizeof crc);
    return static_cast<std::size_t>(p - out.data());
  }

  /// Characterizer::restore().
  static RestoreStatus restore(C& c, std::span<const std::byte> in) {
    Header h{};
    if (in.size() < sizeof h.magic) return RestoreStatus::truncated;
    std::memcpy(&h.magic, in.data(), sizeof h.magic);
    if (h.magic != magic) return RestoreStatus::not_a_checkpoint;
    if (in.size() < sizeof h) return RestoreStatus::truncated;
    std::memcpy(&h, in.data(), sizeof h);
    if (h.version != version) return RestoreStatus::wrong_version;
    const Header mine = header(c);
    if (h.exact != mine.exact || h.entry_bytes != mine.entry_bytes || h.tau_bytes != mine.tau_bytes ||
        h.stride != mine.stride || h.ntaus != mine.ntaus || h.tag != mine.tag)
      return RestoreStatus::config_mismatch;
    const std::size_t bytes = size(c);
    if (in.size() < bytes) return RestoreStatus::truncated;
    std::uint32_t crc = 0;
    std::memcpy(&crc, in.data() + bytes - sizeof crc, sizeof crc);
    if (crc != crc32(in.first(bytes - sizeof crc))) return RestoreStatus::corrupted;
    c.restored_identity_ = h.identity;
    if (h.identity != c.identity_) return RestoreStatus::other_identity;
    const std::byte* p = in.data() + sizeof h;
    for (std::size_t i = 0; i < c.ntaus_; ++i) {
      std::uint64_t m = 0;
      p = get(p, &m, sizeof m);
      if (m != c.taus_[i].result.m) return RestoreStatus::config_mismatch;
    }
    // The CRC guards against accidents, not against a state that was never valid (a file on a
    // board's flash can be written by anything): every field is checked before any is taken.
    const std::size_t run_bytes = sizeof(typename C::RunState);
    const std::size_t history_bytes = c.history_.used() * sizeof(typename C::Entry);
    c.restore_field_ = invalid_field(c, p, p + run_bytes, p + run_bytes + history_bytes);
    if (c.restore_field_ != nullptr) return RestoreStatus::invalid_state;
    c.staged_count_ = 0;  // the restored state replaces the points not yet processed
    p = get(p, &c.run_, run_bytes);
    p = get(p, c.history_.data(), history_bytes);
    get(p, c.taus_.data(), c.ntaus_ * sizeof(typename C::TauState));
    c.mark_gap();
    return RestoreStatus::ok;
  }

 private:
  struct Header {
    std::uint32_t magic = CheckpointCodec::magic;
    std::uint16_t version = CheckpointCodec::version;
    std::uint8_t exact = Arith::exact;
    std::uint8_t reserved = 0;
    std::uint32_t entry_bytes = sizeof(typename Arith::Entry);
    std::uint32_t tau_bytes = sizeof(typename C::TauState);
    std::uint32_t stride = 0;
    std::uint32_t tag = 0;
    std::uint32_t identity = 0;
    std::uint32_t reserved2 = 0;
    std::uint64_t ntaus = 0;
  };
  static Header header(const C& c) {
    Header h;
    h.stride = c.stride();
    h.tag = c.tag_;
    h.identity = c.identity_;
    h.ntaus = c.ntaus_;
    return h;
  }
  static std::byte* put(std::byte* p, const void* from, std::size_t n) {
    std::memcpy(p, from, n);
    return p + n;
  }
  static const std::byte* get(const std::byte* p, void* to, std::size_t n) {
    std::memcpy(to, p, n);
    return p + n;
  }

  // The invariants restore() checks on a checkpoint's run state, history and tau states, before
  // taking anything. Returns the first field that fails, nullptr when all hold. Every field that
  // positions, counts or bounds must be what accumulation since configure() can produce. Two kinds
  // may hold anything: what restore()'s gap resets (p_segment_start, increment_min/max, the
  // decimated points), and the history's values but the last point's (no term reads a point
  // across that gap). Flags are read as bytes first: any byte pattern is safe. O(history + taus).
  static const char* invalid_field(const C& c, const std::byte* run_bytes, const std::byte* history_bytes,
                                   const std::byte* tau_bytes) {
    typename C::RunState r;
    std::memcpy(&r, run_bytes, sizeof r);
    if (byte_of(&r.phase_overflow) > (Arith::exact ? 1 : 0)) return "phase_overflow";
    const std::uint64_t e = r.next_e;
    const std::uint32_t s = c.stride();
    if (e > max_phase_points) return "next_e (phase points)";
    if (r.segment_start > e) return "segment_start";
    if (r.gaps > max_phase_points) return "gaps";  // as many calls as points can have: the count never wraps
    if (r.steady_from != r.segment_start + 3u * s) return "steady_from";
    // Points come from increments, one each plus one at each segment's start (gaps + 1 segments
    // at most, each opened by an increment), or (floating phase input) from add_phase_point().
    if (Arith::exact || r.line_points == 0) {
      if (r.increments > e || e - r.increments > r.increments || (e > r.increments && e - r.increments - 1 > r.gaps))
        return "increments (samples)";
    } else if (r.increments != 0 || r.line_points != e) {
      return "line_points";
    }
    // The last point's entry in ring 0 holds the running phase and P (a NaN never compares equal).
    typename C::Entry last{};
    const auto last_slot = static_cast<std::size_t>((e - 1) % (3u * s));
    if (e > 0) std::memcpy(&last, history_bytes + last_slot * sizeof last, sizeof last);
    if (r.p.hi != last.p.hi || r.p.lo != last.p.lo) return "p (prefix sum)";
    if (r.x != (Arith::exact || r.line_points == 0 ? last.x : typename C::X{})) return "x (running phase)";
    if constexpr (Arith::exact) {
      if (r.line_points != 0 || r.line_x0 != 0 || r.line_slope != 0 || r.first_increment != 0)
        return "line (floating input only)";
    } else {
      if (!std::isfinite(r.first_increment) || !std::isfinite(r.line_x0) || !std::isfinite(r.line_slope))
        return "line (reference line or first increment)";
    }
    for (std::size_t l = 0; l < r.head.size(); ++l) {
      const std::uint64_t want = l < c.history_.levels() && e > 0
                                     ? ((e - 1) >> l) % c.history_.ring_size(static_cast<unsigned>(l))
                                     : 0;
      if (r.head[l] != want) return "head (history position)";
    }
    for (std::size_t i = 0; i < c.ntaus_; ++i) {
      typename C::TauState t;
      std::memcpy(&t, tau_bytes + i * sizeof(typename C::TauState), sizeof t);
      if (const char* field = invalid_tau(t, c.taus_[i], e)) return field;
    }
    return nullptr;
  }

  // A tau state against the configured one, after e phase points.
  static const char* invalid_tau(const typename C::TauState& t, const typename C::TauState& configured, std::uint64_t e) {
    const auto& r = t.result;
    if (r.m != configured.result.m || r.stride != configured.result.stride || t.level != configured.level ||
        t.ring_of != configured.ring_of || t.back != configured.back)
      return "tau (averaging factor, stride or history position)";
    // Point 0 and every multiple of m are decimated; the countdown counts the level's runs to the next.
    const std::uint64_t countdown = e == 0 ? 0 : (r.m >> t.level) - (((e - 1) % r.m) >> t.level);
    if (t.countdown != countdown) return "countdown (decimation)";
    if (t.decimated_count > 3) return "decimated_count";
    if (byte_of(&r.sum_overflow) != 0) return "sum_overflow";  // kept in sticky, false in the state
    // Terms form at most at every stride-th point (overlapping) or every m-th (decimated).
    const std::uint64_t formed = e / r.stride, decimated = e / r.m;
    for (std::size_t k = 0; k < r.n.size(); ++k) {
      if (r.n[k] > (k < 3 ? formed : decimated)) return "n (term count)";
      if constexpr (Arith::exact) {
        if (r.n[k] == 0 && (r.sum[k].lo | r.sum[k].hi) != 0) return "sum (of squares, without terms)";
        if ((r.sum[k].hi & ~t.sticky) != 0) return "sticky (the sums' high words)";
      } else {
        if (!std::isfinite(r.sum[k]) || r.sum[k] < 0 || (r.n[k] == 0 && r.sum[k] != 0)) return "sum (of squares)";
      }
    }
    if (!Arith::exact && t.sticky != 0) return "sticky (the sums' high words)";
    if (r.out_of_range > 2 * formed) return "out_of_range";
    if (!t.noise.plausible(e == 0 ? 0 : (e - 1) / r.m + 1)) return "noise (lag-1 sums)";
    return nullptr;
  }

  static std::uint8_t byte_of(const bool* flag) {
    std::uint8_t b = 0;
    std::memcpy(&b, flag, 1);
    return b;
  }
};

}  // namespace gyrochar
