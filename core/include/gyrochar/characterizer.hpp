#pragma once
// The characterizer: everything gyrochar accumulates from a stream of phase points, in fixed
// memory, with no heap, one checkpoint format, read out by the extractors of estimates.hpp. The
// board and the offline analyzer both run it, so they compute the same numbers by construction.
//
// Per averaging factor m (tau = m tau0) it keeps, from one pass over the points:
//   - the sums of squared terms of the overlapping (or strided) Allan, modified Allan and
//     Hadamard variances (stat.hpp has the terms), in the octave pyramid described below;
//   - the decimated series x[0], x[m], x[2m], ...: the non-overlapped Allan and Hadamard sums
//     (Stable32's ADEV and HDEV) and the lag-1 autocorrelation sums of noise identification.
//
// Notation: phase index e = 0, 1, 2, ...; x_e the phase (for counts the accumulated pulses,
// x_0 = 0); P_e = sum_{i<e} x_i. AVAR = sum a^2 / (2 n tau^2), MVAR = sum t^2 / (2 m^2 n tau^2),
// HVAR = sum h^2 / (6 n tau^2), TVAR = tau^2 MVAR / 3.
//
// The pyramid. Terms of tau = r * 2^L (1 <= r <= S, S the stride factor) are formed every 2^L
// phase points ("level L"), so their stride is m/S (1 for m <= S: exactly the fully overlapped
// estimator, with Stable32's number of terms n). They need x and P at ages m, 2m, 3m. Past points
// live in a multi-resolution history (pyramid_history.hpp) of 3S + (levels - 1) * 3S/2 entries,
// independent of run length, and the work per point is O(S) amortized (level L runs every 2^L
// points; the decimation of tau m rides on its level).
//
// Gaps. A gap starts a new segment: no term and no difference of the decimated series spans it;
// sums and term counts go on, so the pooled estimate stays unbiased and n counts only the terms
// actually formed.
//
// Arithmetic policies (arith.hpp): CountArith, integer counts, exact; FloatArith, floating phase.
#include <array>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>

#include "gyrochar/arith.hpp"
#include "gyrochar/assert.hpp"
#include "gyrochar/block_kernel.hpp"
#include "gyrochar/checkpoint.hpp"
#include "gyrochar/noise_id.hpp"
#include "gyrochar/pyramid_history.hpp"
#include "gyrochar/tau_result.hpp"
#include "gyrochar/wide.hpp"

namespace gyrochar {

// ---------------------------------------------------------------------------------------------
// The characterizer over caller-owned storage

enum class ConfigureStatus : std::uint8_t {
  ok,
  bad_stride_factor,      // S must be a power of two, 2 <= S <= 2^24
  too_many_taus,          // more taus than the tau storage holds
  tau_not_representable,  // m must be r * 2^L with r <= S; taus strictly increasing, m >= 1
  history_too_small,      // storage cannot hold the history for the largest tau at this S
};

struct CharacterizerConfig {
  std::uint32_t stride_factor = 8;  // S
  std::uint32_t tag = 0;            // the caller's configuration fingerprint, kept in checkpoints
  std::uint32_t identity = 0;       // what the data belongs to (the caller's instrument), kept too
};

template <class Arith>
class Characterizer {
  template <class>
  friend struct CheckpointLayout;
  friend class CheckpointCodec<Arith>;

 public:
  using Entry = typename Arith::Entry;
  using X = typename Arith::X;
  using Sum = typename Arith::Sum;
  using Result = TauResult<Sum>;

  /// Per-tau state, kept in caller-owned storage.
  struct TauState {
    Result result;
    std::uint8_t level = 0;                 // terms formed when e is a multiple of 2^level
    std::array<std::uint8_t, 3> ring_of{};  // ring holding the point of age k*m (k = 1..3)
    std::array<std::uint32_t, 3> back{};    // its slot is head(ring) - back, modulo the ring size
    std::uint64_t sticky = 0;               // OR of the sums' high words: bit 63 = overflow
    // The decimated series x[k m]:
    std::uint64_t countdown = 0;       // runs of this level until the next multiple of m
    std::array<X, 3> decimated{};      // the last three decimated points of this segment
    std::uint8_t decimated_count = 0;  // how many of them are valid (0..3)
    typename Arith::NoiseSums noise;   // lag-1 autocorrelation sums
  };

  /// Binds the characterizer to storage owned by the caller, which must outlive it. No allocation.
  Characterizer(std::span<Entry> history, std::span<TauState> taus) : history_(history), taus_(taus) {}

  /// Configures the stride factor and the taus (strictly increasing m), and resets all state.
  /// O(taus + history). Fails (returning why, state unusable until a successful configure) when
  /// the taus or the stride do not fit the storage.
  ConfigureStatus configure(const CharacterizerConfig& config, std::span<const std::uint64_t> m_list) {
    const std::uint32_t s = config.stride_factor;
    if (s < 2 || s > (1u << 24) || !std::has_single_bit(s)) return ConfigureStatus::bad_stride_factor;
    if (m_list.size() > taus_.size()) return ConfigureStatus::too_many_taus;
    history_.configure(s, history_.levels());  // the levels follow once the taus are known
    tag_ = config.tag;
    identity_ = config.identity;
    ntaus_ = m_list.size();
    unsigned max_level = 0;
    std::uint64_t previous = 0;
    for (std::size_t i = 0; i < ntaus_; ++i) {
      const std::uint64_t m = m_list[i];
      if (m <= previous || m > (std::uint64_t{1} << 62)) return ConfigureStatus::tau_not_representable;
      previous = m;
      unsigned level = 0;
      while ((std::uint64_t{s} << level) < m) ++level;
      if (level >= 64 || (m & ((std::uint64_t{1} << level) - 1)) != 0) return ConfigureStatus::tau_not_representable;
      TauState& t = taus_[i];
      t = TauState{};
      t.result.m = m;
      t.result.stride = std::uint64_t{1} << level;
      t.level = static_cast<std::uint8_t>(level);
      for (unsigned k = 1; k <= 3; ++k) {
        const HistorySlot slot = history_slot(s, k * m);
        t.ring_of[k - 1] = slot.ring;
        t.back[k - 1] = slot.back;
      }
      if (level > max_level) max_level = level;
    }
    history_.configure(s, max_level + 1);
    fast_count_ = 0;
    while (fast_count_ < ntaus_ && taus_[fast_count_].level == 0) ++fast_count_;
    if (history_entries(s, ntaus_ ? m_list[ntaus_ - 1] : 1) > history_.capacity()) return ConfigureStatus::history_too_small;
    GYROCHAR_ASSERT(history_.used() <= history_.capacity());
    restart();
    return ConfigureStatus::ok;
  }

  /// Forgets all data (sums, counts, history, noise sums); keeps the configuration. O(taus).
  void restart() {
    for (std::size_t i = 0; i < ntaus_; ++i) {
      TauState& t = taus_[i];
      t.result.sum = {};
      t.result.n = {};
      t.result.out_of_range = 0;
      t.result.sum_overflow = false;
      t.sticky = 0;
      t.countdown = 0;
      t.decimated_count = 0;
      t.noise = typename Arith::NoiseSums{};
    }
    run_ = RunState{};
    run_.steady_from = 3u * stride();
    staged_count_ = 0;
  }

  /// Adds the next phase point (floating phase data). O(S) amortized; no allocation; never fails.
  /// Counts go through add_increment(), which keeps the input bounds exactness relies on.
  // The `requires` clause on a line of its own (clang-format 14 would join it to the parameters):
  // clang-format off
  void add_phase_point(double x)
    requires(!Arith::exact)
  {
    // clang-format on
    // Relative to the line through the first two points: x - x0 is formed exactly (as hi + lo)
    // and the line taken off by one fused multiply-add.
    const std::uint64_t k = run_.line_points++;
    if (k == 0) run_.line_x0 = x;
    const double hi = x - run_.line_x0;
    const double b = hi - x;
    const double lo = (x - (hi - b)) - (run_.line_x0 + b);
    if (k == 1) run_.line_slope = hi;
    stage(static_cast<X>(std::fma(-static_cast<double>(k), run_.line_slope, hi) + lo));
  }

  /// Adds the next increment of phase: a pulse count per tau0 (CountArith) or frequency * tau0
  /// (FloatArith, taken relative to the first one). The phase before the first increment of a
  /// segment is a phase point too, so N increments give N + 1 phase points, as Stable32 treats
  /// frequency data. O(S) amortized. CountArith: if the accumulated phase would pass 2^63 pulses, a
  /// new segment starts from 0 and phase_overflowed() turns true.
  [[gnu::always_inline]] void add_increment(typename Arith::Increment dx) {
    if constexpr (Arith::exact) {  // inside a segment: the running sum staged, fields loaded once
      const std::size_t k = staged_count_;
      const std::uint64_t e = run_.next_e + k;  // the new point's index
      std::int64_t x = 0;
      if (e != run_.segment_start && !__builtin_add_overflow(run_.x, std::int64_t{dx}, &x)) {
        run_.x = x;
        ++run_.increments;
        staged_count_ = k + 1;
        staged_[k] = x;
        if (((e + 1) & (block_points - 1)) == 0) flush();
        return;
      }
    }
    add_increment_general(dx);
  }

  /// The block API: add_increment() for each value of `block`, in order. O(S) amortized per value.
  /// Counts inside a segment go straight to the staged block (the phase as their running sum).
  template <class T>
  void add_increments(std::span<const T> block) {
    std::size_t i = 0;
    if constexpr (Arith::exact) {
      while (i < block.size()) {
        if (phase_points() == run_.segment_start) {  // a segment's first point: add_increment() stages it
          add_increment(static_cast<typename Arith::Increment>(block[i++]));
          continue;
        }
        const std::size_t k = staged_count_;
        const std::size_t room = block_points - ((run_.next_e + k) & (block_points - 1));
        const std::size_t n = block.size() - i < room ? block.size() - i : room;
        std::int64_t x = run_.x;
        bool overflow = false;
        for (std::size_t j = 0; j < n; ++j) {
          overflow |= __builtin_add_overflow(x, std::int64_t{static_cast<typename Arith::Increment>(block[i + j])}, &x);
          staged_[k + j] = x;
        }
        if (overflow) {  // the phase passes 2^63 in this run: add_increment() starts the new segment
          for (std::size_t j = 0; j < n; ++j) add_increment(static_cast<typename Arith::Increment>(block[i + j]));
        } else {
          run_.x = x;
          run_.increments += n;
          staged_count_ = k + n;
          if (n == room) flush();
        }
        i += n;
      }
    }
    for (; i < block.size(); ++i) add_increment(static_cast<typename Arith::Increment>(block[i]));
  }

  /// Starts a new segment at the next phase point: no term and no difference of a decimated series
  /// will span the break. O(taus).
  void mark_gap() {
    flush();
    run_.increment_min = RunState{}.increment_min;
    run_.increment_max = RunState{}.increment_max;
    run_.segment_start = run_.next_e;
    run_.steady_from = run_.segment_start + 3u * stride();
    run_.p_segment_start = run_.p;
    ++run_.gaps;
    for (std::size_t i = 0; i < ntaus_; ++i) {
      taus_[i].decimated_count = 0;
      taus_[i].noise.reset_segment();
    }
  }

  // -------------------------------------------------------------------------------------------
  // Checkpoints: the whole state as bytes, validated field by field on restore (checkpoint.hpp
  // has the format and the checks). The caller stores them (atomically: firmware/checkpoint.hpp).

  static constexpr std::uint32_t checkpoint_magic = CheckpointCodec<Arith>::magic;
  static constexpr std::uint16_t checkpoint_version = CheckpointCodec<Arith>::version;
  static constexpr std::uint64_t max_phase_points = CheckpointCodec<Arith>::max_phase_points;

  /// Bytes save() writes for the current configuration. O(1).
  std::size_t checkpoint_size() const { return CheckpointCodec<Arith>::size(*this); }

  /// Writes the state into `out`; returns the bytes written, 0 when `out` is too small.
  /// O(history + taus), no allocation, does not disturb accumulation.
  std::size_t save(std::span<std::byte> out) const { return CheckpointCodec<Arith>::save(*this, out); }

  /// Restores a state written by save() under the same configuration and identity (configure()
  /// first). Any byte pattern is safe: a state whose fields break the invariants of accumulation
  /// is refused as invalid_state. On success the restart is a gap: a new segment starts at the
  /// next point, sums and counts go on. On failure nothing changes but what restore_field() and
  /// checkpoint_identity() report. O(history + taus), no allocation.
  RestoreStatus restore(std::span<const std::byte> in) { return CheckpointCodec<Arith>::restore(*this, in); }

  // -------------------------------------------------------------------------------------------
  // Read-out (the extractors of estimates.hpp build on these). All O(1), no allocation.

  /// True once the accumulated pulse count passed 2^63 (CountArith); a gap was inserted there.
  bool phase_overflowed() const { return run_.phase_overflow; }
  /// Phase points added so far (over all segments).
  std::uint64_t phase_points() const { return run_.next_e + staged_count_; }
  /// Increments added so far (samples of counts or frequency; 0 for phase input).
  std::uint64_t increments() const { return run_.increments; }
  /// Gaps marked so far (restores and phase overflows included).
  std::uint64_t gaps() const { return run_.gaps; }
  std::size_t tau_count() const { return ntaus_; }
  std::uint32_t stride_factor() const { return history_.stride_factor(); }
  std::uint32_t tag() const { return tag_; }
  std::uint32_t identity() const { return identity_; }
  /// After restore() returned invalid_state: the first field that failed its check.
  const char* restore_field() const { return restore_field_ != nullptr ? restore_field_ : ""; }
  /// After restore() got past the configuration checks: the identity the checkpoint was written for.
  std::uint32_t checkpoint_identity() const { return restored_identity_; }
  /// Sums of tau i (0 <= i < tau_count()), valid at any time.
  Result result(std::size_t i) const {
    GYROCHAR_ASSERT(i < ntaus_);
    flush();
    Result r = taus_[i].result;
    r.sum_overflow = (taus_[i].sticky >> 63) != 0;
    return r;
  }
  /// The lag-1 autocorrelation sums of tau i's decimated series.
  const typename Arith::NoiseSums& noise(std::size_t i) const {
    GYROCHAR_ASSERT(i < ntaus_);
    flush();
    return taus_[i].noise;
  }

 private:
  std::uint32_t stride() const { return history_.stride_factor(); }

  // add_increment() at a segment's start or a phase overflow, and for floating increments.
  [[gnu::noinline]] void add_increment_general(typename Arith::Increment dx) {
    ++run_.increments;
    if (phase_points() == run_.segment_start) stage(run_.x);
    if constexpr (!Arith::exact) {
      if (run_.increments == 1) run_.first_increment = dx;
      run_.x += dx - run_.first_increment;
    } else {
      if (__builtin_add_overflow(run_.x, std::int64_t{dx}, &run_.x)) {
        run_.phase_overflow = true;
        mark_gap();
        run_.x = 0;
        stage(run_.x);
        run_.x = dx;
      }
    }
    stage(run_.x);
  }

  // Staging. Points wait in staged_ until a block is full or the state is read, then go through
  // the block kernel (counts, steady state) or one by one through push(). Read-outs are const and
  // process the staged points first: nothing observable changes, but two threads must not read
  // at once. A characterizer defined const never has staged points, so nothing is written then.
  void stage(X x) {
    // Blocks end on multiples of block_points, so the next one starts on one (higher_levels()).
    // Decided before the store, which the compiler must assume may change run_.
    const std::size_t k = staged_count_;
    const bool full = ((run_.next_e + k + 1) & (block_points - 1)) == 0;
    staged_[k] = x;
    staged_count_ = k + 1;
    if (full) flush();
  }
  void flush() const { const_cast<Characterizer*>(this)->process_staged(); }
  [[gnu::noinline]] void process_staged() {
    const std::size_t n = staged_count_;
    if (n == 0) return;
    GYROCHAR_ASSERT(n <= block_points);  // stage() flushes a full block at once
    staged_count_ = 0;
    std::size_t i = 0;
    if constexpr (Arith::exact) {
      // The segment's smallest and largest increment (terms_fit(), step_bound()): the staged points
      // are all of this segment (gaps flush first) and differ by increments, the first one from
      // the last point processed unless it opens the segment.
      if (run_.next_e != run_.segment_start) {
        const std::array<std::int64_t, 2> first{history_.recent(run_.next_e - 1).x, staged_[0]};
        difference_range(first.data(), 2, run_.increment_min, run_.increment_max);
      }
      difference_range(staged_.data(), n, run_.increment_min, run_.increment_max);
      while (i < n && run_.next_e < run_.steady_from) push(staged_[i++]);
      if (i < n) push_block(&staged_[i], n - i);
    } else {
      while (i < n) push(staged_[i++]);
    }
  }

  // One phase point through every level that runs at it.
  void push(X x) {
    const std::uint64_t e = run_.next_e++;
    run_.p = Arith::add_prefix(run_.p, x);
    const Entry current{x, run_.p};
    const unsigned fired = history_.advance_heads(e, run_.head);
    if (e == 0) {  // point 0 is a multiple of every m
      for (std::size_t i = 0; i < ntaus_; ++i) decimate(taus_[i], x);
    }
    std::size_t i = 0;
    if constexpr (!Arith::exact) {
      if (e >= run_.steady_from) {
        for (; i < fast_count_; ++i) {
          fast_terms(taus_[i], current);
          if (--taus_[i].countdown == 0) decimate(taus_[i], x);
        }
      }
    }
    later_levels(i, e, fired, current);
    history_.insert(e, current, run_.head);
  }

  // Terms and decimation of the taus from index `first` on whose level runs at e.
  void later_levels(std::size_t first, std::uint64_t e, unsigned fired, const Entry& current) {
    for (std::size_t i = first; i < ntaus_ && taus_[i].level < fired; ++i) {
      form_terms(taus_[i], e, current);
      if (--taus_[i].countdown == 0) decimate(taus_[i], current.x);
    }
  }

  // ---------------------------------------------------------------------------------------------
  // The block kernel (counts, steady state: the points' level-0 history lies in this segment).
  // The level-0 taus (m <= S) take the whole block at once, tau by tau, in block_terms(); the
  // history and the higher levels then take the points one by one, as push() does. Level 0 reads
  // only ring 0 as it was before the block, so the order of the two passes does not matter.
  // Working memory on the stack: about 22 KiB (x86-64, 256 points per block), 34 KiB when S > 32
  // (the gathered points).
  // The `requires` clauses on lines of their own (clang-format 14 would join them to the parameter
  // lists), and the comments aligned as written:
  // clang-format off
  struct Block {
    std::uint64_t e0;  // index of the first point
    std::size_t n;
    const X* x;
    const std::uint64_t* p_lo;  // low words of P (window: valid back to index -depth)
    const std::uint64_t* p_hi;
    const std::int64_t* wx;     // x in the window (valid back to index -depth)
    std::size_t depth;
    unsigned level;             // the points are the multiples of 2^level: tau m has lag m >> level
    // Point e0 + j - age, from the block or from ring 0 (ages up to 3S before e0).
    Entry at(const Characterizer& c, std::size_t j, std::uint64_t age) const
      requires(Arith::exact)
    {
      if (j >= age) return {x[j - age], Int128{p_lo[j - age], p_hi[j - age]}};
      return c.history_.recent(e0 + j - age);
    }
  };

  // Defined in characterizer_block.hpp, each with its contract.
  void push_block(const X* x, std::size_t n)
    requires(Arith::exact);
  void block_point(std::size_t first, X x, Int128 p)
    requires(Arith::exact);
  void insert_run(const X* x, const std::uint64_t* p_lo, const std::uint64_t* p_hi, std::size_t n)
    requires(Arith::exact);
  static constexpr std::size_t window_depth = 96;  // points before a block copied next to it
  std::size_t higher_levels(const Block& level0, const std::int64_t* x_prev, const std::uint64_t* p_prev)
    requires(Arith::exact);
  bool terms_fit(std::uint64_t m) const;
  bool proved_small(std::uint64_t m, std::size_t n, BlockTerms& terms) const;
  std::uint64_t step_bound(std::uint64_t m) const;
  void level0_block(TauState& t, const Block& b)
    requires(Arith::exact);
  [[gnu::noinline]] void gathered_sums(TauState& t, const Block& b, std::size_t m)
    requires(Arith::exact);
  void block_sums(TauState& t, const Block& b, std::size_t m, const std::int64_t* x1, const std::int64_t* x2,
                  const std::int64_t* x3, const std::uint64_t* p1, const std::uint64_t* p2, const std::uint64_t* p3)
    requires(Arith::exact);
  void gather(const Block& b, std::uint64_t age, std::int64_t* x, std::uint64_t* p) const
    requires(Arith::exact);
  // clang-format on
  static std::uint64_t add_block(UInt128& sum, const BlockSquares& s, const std::int64_t* terms, std::size_t n);

  // A point of the decimated series x[k m]: the non-overlapped second and third differences, and
  // the noise identification sums. The countdown restarts at m / 2^level runs of the level.
  static void decimate(TauState& t, X x) {
    t.countdown = t.result.m >> t.level;
    Result& r = t.result;
    X a{}, h{};
    if (t.decimated_count >= 2 && Arith::x_term2(x, t.decimated[0], t.decimated[1], a)) {
      t.sticky |= Arith::accumulate(r.sum[static_cast<std::size_t>(SumKind::avar_nonoverlapped)], a);
      ++r.n[static_cast<std::size_t>(SumKind::avar_nonoverlapped)];
    }
    if (t.decimated_count >= 3 && Arith::x_terms(x, t.decimated[0], t.decimated[1], t.decimated[2], a, h)) {
      t.sticky |= Arith::accumulate(r.sum[static_cast<std::size_t>(SumKind::hvar_nonoverlapped)], h);
      ++r.n[static_cast<std::size_t>(SumKind::hvar_nonoverlapped)];
    }
    t.decimated = {x, t.decimated[0], t.decimated[1]};
    if (t.decimated_count < 3) ++t.decimated_count;
    t.noise.add(x);
  }

  // Steady state of a ring-0 tau (m <= S, whole history inside the segment). For counts, the input
  // contract |increment| < 2^31 bounds |x[e] - x[e-k]| by k 2^31, so with m <= 2^15 the AVAR and HVAR
  // terms stay below 2^50 and the MVAR term below 2m^2 2^31 <= 2^62: no range checks are needed.
  void fast_terms(TauState& t, const Entry& now) {
    const std::uint32_t head = run_.head[0], size = 3u * stride();
    auto back = [&](std::uint32_t b) -> const Entry& { return history_[head >= b ? head - b : head + size - b]; };
    const Entry& e1 = back(t.back[0]);
    const Entry& e2 = back(t.back[1]);
    const Entry& e3 = back(t.back[2]);
    Result& r = t.result;
    const auto d1 = now.x - e1.x, d2 = e1.x - e2.x, d3 = e2.x - e3.x;
    const auto a = d1 - d2;
    const auto h = a - (d2 - d3);
    X mt{};
    Arith::p_term(now.p, e1.p, e2.p, e3.p, mt);
    t.sticky |= Arith::accumulate(r.sum[0], a) | Arith::accumulate(r.sum[1], mt) | Arith::accumulate(r.sum[2], h);
    ++r.n[0];
    ++r.n[1];
    ++r.n[2];
  }

  void form_terms(TauState& t, std::uint64_t e, const Entry& now) {
    const std::uint64_t m = t.result.m;
    const std::uint64_t span = e - run_.segment_start;  // points of this segment before e
    if (span < 2 * m) return;
    const Entry& e1 = at(t, 0);
    const Entry& e2 = at(t, 1);
    Result& r = t.result;
    X a{};
    if (span < 3 * m) {
      // Only the AVAR term fits; MVAR may still use P just before the segment start.
      if (!Arith::x_term2(now.x, e1.x, e2.x, a)) {
        ++r.out_of_range;
      } else {
        t.sticky |= Arith::accumulate(r.sum[0], a);
        ++r.n[0];
      }
      if (span + 1 == 3 * m) mvar_term(t, now.p, e1.p, e2.p, run_.p_segment_start);
      return;
    }
    checked_terms(t, now, e1, e2, at(t, 2));
  }

  // The three terms at a point whose points of ages m, 2m, 3m lie in its segment, each checked.
  void checked_terms(TauState& t, const Entry& now, const Entry& e1, const Entry& e2, const Entry& e3) {
    Result& r = t.result;
    X a{}, h{};
    if (!Arith::x_terms(now.x, e1.x, e2.x, e3.x, a, h)) {
      ++r.out_of_range;
    } else {
      t.sticky |= Arith::accumulate(r.sum[0], a);
      ++r.n[0];
      t.sticky |= Arith::accumulate(r.sum[2], h);
      ++r.n[2];
    }
    mvar_term(t, now.p, e1.p, e2.p, e3.p);
  }

  template <class P>
  static void mvar_term(TauState& ts, const P& p0, const P& p1, const P& p2, const P& p3) {
    X term{};
    if (!Arith::p_term(p0, p1, p2, p3, term)) {
      ++ts.result.out_of_range;
      return;
    }
    ts.sticky |= Arith::accumulate(ts.result.sum[1], term);
    ++ts.result.n[1];
  }

  // The point of age (k+1) m for tau t.
  const Entry& at(const TauState& t, unsigned k) const { return history_.behind(t.ring_of[k], t.back[k], run_.head); }

  PyramidHistory<Entry> history_;
  std::span<TauState> taus_;
  std::size_t ntaus_ = 0;
  std::uint32_t tag_ = 0;
  std::uint32_t identity_ = 0;
  std::uint32_t restored_identity_ = 0;
  const char* restore_field_ = nullptr;
  std::size_t fast_count_ = 0;                      // the level-0 taus (m <= S), first in the list
  static constexpr std::size_t block_points = 256;  // staged points per block (a power of two)
  std::array<X, block_points> staged_{};
  std::size_t staged_count_ = 0;

  // Everything that changes while data flows (with history_ and the tau states: the checkpoint).
  struct RunState {
    std::uint64_t next_e = 0;         // index of the next phase point
    std::uint64_t segment_start = 0;  // index of the current segment's first point
    std::uint64_t steady_from = 0;    // from here on level 0 has its whole history in the segment
    std::uint64_t increments = 0;     // add_increment() calls
    std::uint64_t gaps = 0;
    decltype(Entry{}.p) p{};  // P of the next point
    decltype(Entry{}.p) p_segment_start{};
    X x{};                                        // running phase for add_increment()
    typename Arith::Increment first_increment{};  // FloatArith: increments are taken relative to it
    std::uint64_t line_points = 0;                // FloatArith phase input: the reference line
    double line_x0 = 0, line_slope = 0;
    bool phase_overflow = false;
    // CountArith: the smallest and largest increment of this segment (they bound the terms).
    std::int32_t increment_min = INT32_MAX, increment_max = INT32_MIN;
    HistoryHeads head{};  // head[l]: slot of (e >> l) in ring l
  };
  RunState run_;
};

/// Storage for a StaticCharacterizer: the history for the worst stride factor and the tau states.
template <class Arith, unsigned Octaves, std::uint32_t MaxStride, std::size_t MaxTaus>
struct CharacterizerStorage {
  static_assert(Octaves >= 1 && Octaves <= 63, "taus up to 2^62");
  static_assert(MaxStride >= 2 && std::has_single_bit(MaxStride), "stride factor: power of two >= 2");
  static constexpr std::size_t history_capacity() {
    std::size_t most = 0;
    for (std::uint32_t s = 2; s <= MaxStride; s *= 2) {
      const std::size_t n = history_entries(s, std::uint64_t{1} << (Octaves - 1));
      if (n > most) most = n;
    }
    return most;
  }
  std::array<typename Arith::Entry, history_capacity()> history{};
  std::array<typename Characterizer<Arith>::TauState, MaxTaus> taus{};
};

/// A characterizer that owns its storage: capacity fixed at compile time for taus up to
/// 2^(Octaves-1) with any stride factor 2 <= S <= MaxStride. Not copyable (the base refers to the
/// members).
template <class Arith, unsigned Octaves, std::uint32_t MaxStride, std::size_t MaxTaus = Octaves>
class StaticCharacterizer : private CharacterizerStorage<Arith, Octaves, MaxStride, MaxTaus>, public Characterizer<Arith> {
  using Storage = CharacterizerStorage<Arith, Octaves, MaxStride, MaxTaus>;

 public:
  StaticCharacterizer() : Storage{}, Characterizer<Arith>(Storage::history, Storage::taus) {}
  StaticCharacterizer(const StaticCharacterizer&) = delete;
  StaticCharacterizer& operator=(const StaticCharacterizer&) = delete;
};

}  // namespace gyrochar

#include "gyrochar/characterizer_block.hpp"  // the block path's definitions
