#pragma once
// The characterizer's block path (counts, steady state): the definitions of the members
// characterizer.hpp declares under "The block kernel". Included at the end of characterizer.hpp.
// Each signature keeps its `requires` clause on a line of its own, between `// clang-format off`
// and `// clang-format on` (clang-format 14 would join it to the parameter list).
#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "gyrochar/characterizer.hpp"
#include "gyrochar/term_kernel.hpp"

namespace gyrochar {

// clang-format off
template <class Arith>
inline void Characterizer<Arith>::push_block(const X* x, std::size_t n)
  requires(Arith::exact)
{
  // clang-format on
  // The window: the last `depth` points before the block (from ring 0), then the block.
  const std::uint32_t ring0 = 3u * stride();
  const std::size_t depth = ring0 < window_depth ? ring0 : window_depth;
  std::array<std::int64_t, window_depth + block_points> wx;
  std::array<std::uint64_t, window_depth + block_points> wp;
  std::array<std::uint64_t, block_points> p_hi;
  const auto oldest = static_cast<std::uint32_t>((run_.next_e - depth) % ring0);
  history_.copy_out(0, oldest, depth, wx.data(), wp.data());
  // P in two words: x sign-extended adds the carry out of the low word, less one when x < 0.
  std::uint64_t p_lo = run_.p.lo, p_high = run_.p.hi;
  for (std::size_t j = 0; j < n; ++j) {
    const auto v = static_cast<std::uint64_t>(x[j]);
    const std::uint64_t sum = p_lo + v;
    p_high += static_cast<std::uint64_t>(sum < p_lo) - (v >> 63);
    p_lo = sum;
    wp[depth + j] = p_lo;
    p_hi[j] = p_high;
  }
  std::memcpy(&wx[depth], x, n * sizeof(X));
  const Block b{run_.next_e, n, x, &wp[depth], p_hi.data(), &wx[depth], depth, 0};
  for (std::size_t i = 0; i < fast_count_; ++i) level0_block(taus_[i], b);
  const std::size_t done = depth == ring0 ? higher_levels(b, wx.data(), wp.data()) : fast_count_;
  // The history and the remaining levels. The taus the kernel left run at the multiples of
  // 2^level of the lowest of them: those points go one by one, as push() takes them, the runs
  // between them enter the history at once. Below level 4 they run too often for that to pay.
  const bool later = done < ntaus_;
  if (later && taus_[done].level < 4) {
    for (std::size_t j = 0; j < n; ++j) block_point(done, x[j], {wp[depth + j], p_hi[j]});
    return;
  }
  const std::uint64_t every = later ? std::uint64_t{1} << taus_[done].level : 0;
  for (std::size_t j = 0; j < n;) {
    std::size_t k = n;  // the next point at which a later tau runs
    if (later) {
      const std::uint64_t wait = (every - (run_.next_e & (every - 1))) & (every - 1);
      if (wait < n - j) k = j + static_cast<std::size_t>(wait);
    }
    if (k > j) insert_run(x + j, &wp[depth + j], p_hi.data() + j, k - j);
    if (k == n) break;
    block_point(done, x[k], {wp[depth + k], p_hi[k]});
    j = k + 1;
  }
}

// One point of a block (P: its prefix) through the history and the taus from `first` on.
// clang-format off
template <class Arith>
inline void Characterizer<Arith>::block_point(std::size_t first, X x, Int128 p)
  requires(Arith::exact)
{
  // clang-format on
  const std::uint64_t e = run_.next_e++;
  run_.p = p;
  const Entry current{x, p};
  later_levels(first, e, history_.advance_heads(e, run_.head), current);
  history_.insert(e, current, run_.head);
}

// Points run_.next_e (>= 1) .. + n - 1 enter the history at once, and run_ moves on past them.
// clang-format off
template <class Arith>
inline void Characterizer<Arith>::insert_run(const X* x, const std::uint64_t* p_lo, const std::uint64_t* p_hi,
                                              std::size_t n)
  requires(Arith::exact)
{
  // clang-format on
  history_.insert_run(run_.next_e, x, p_lo, p_hi, n, run_.head);
  run_.next_e += n;
  run_.p = {p_lo[n - 1], p_hi[n - 1]};
}

// Levels 1, 2, ... of a block that starts at a multiple of block_points, with 3S <= window_depth:
// the points of level L (the multiples of 2^L) form a series in which a tau r 2^L of that level
// is a level-0 tau of lag r, so the same kernel takes them, over a window of the series' last 3S
// points (the younger half from level L-1's window, the older half from ring L) and the block's
// points of level L. Stops at the first level not yet steady in this segment or whose terms are
// not proved to fit. Returns how many taus (a prefix of the list) the kernel took.
// clang-format off
template <class Arith>
inline std::size_t Characterizer<Arith>::higher_levels(const Block& level0, const std::int64_t* x_prev,
                                                        const std::uint64_t* p_prev)
  requires(Arith::exact)
{
  // clang-format on
  std::size_t done = fast_count_;
  const std::uint64_t e0 = level0.e0;
  const std::size_t depth = 3u * stride();
  if (e0 % block_points != 0) return done;
  std::array<std::array<std::int64_t, window_depth + block_points / 2>, 2> x_buf;  // level 1 on: half the points
  std::array<std::array<std::uint64_t, window_depth + block_points / 2>, 2> p_buf;
  std::size_t n = level0.n;
  // Levels with at least two points in the block: a single point costs less through block_point().
  for (unsigned level = 1; (std::size_t{2} << level) <= block_points && level < history_.levels(); ++level) {
    if (done == ntaus_ || taus_[done].level != level || e0 < run_.segment_start + (std::uint64_t{depth} << level))
      return done;
    std::int64_t* x_next = x_buf[level % 2].data();
    std::uint64_t* p_next = p_buf[level % 2].data();
    const std::size_t half = depth / 2;
    const std::uint32_t ring = 3u * stride() / 2;
    // Ages (3S 2^(L-1), 3S 2^L]: ring L; the younger ones and the block: every other one.
    history_.copy_out(level, static_cast<std::uint32_t>(((e0 >> level) - depth) % ring), half, x_next, p_next);
    n = (n + 1) / 2;
    // depth = 3S is even: x_prev[0] is of level L.
    every_other(reinterpret_cast<const std::uint64_t*>(x_prev), reinterpret_cast<std::uint64_t*>(x_next + half),
                depth - half + n);
    every_other(p_prev, p_next + half, depth - half + n);
    const Block b{e0, n, x_next + depth, p_next + depth, nullptr, x_next + depth, depth, level};
    for (; done < ntaus_ && taus_[done].level == level; ++done) {
      if (!terms_fit(taus_[done].result.m)) return done;
      level0_block(taus_[done], b);
    }
    x_prev = x_next;
    p_prev = p_next;
  }
  return done;
}

// The terms of tau m fit in int64 when 2 m^2 (largest increment - smallest) < 2^63 (|a| <= m
// span, |h| <= 2 m span, |t| <= m^2 span), always for m <= 2^15 since increments are int32.
template <class Arith>
inline bool Characterizer<Arith>::terms_fit(std::uint64_t m) const {
  if (m > (std::uint64_t{1} << 31)) return false;
  const std::uint64_t span = run_.increment_max >= run_.increment_min
                                 ? static_cast<std::uint64_t>(std::int64_t{run_.increment_max} - run_.increment_min)
                                 : 0;
  return span <= (~std::uint64_t{0} >> 1) / (2 * m * m);
}

// Whether every term of tau m is small enough that the 64-bit sums of n of their squares are
// exact (squares_exact()), from the segment's increment spread D: |a| <= m D, |h| <= 2 m D,
// |t| <= m^2 D (t sums m consecutive AVAR terms). The bounds go to `terms` (their sums are the
// caller's to fill). terms_fit(m) holds: m^2 D < 2^62.
template <class Arith>
inline bool Characterizer<Arith>::proved_small(std::uint64_t m, std::size_t n, BlockTerms& terms) const {
  const std::uint64_t span = run_.increment_max >= run_.increment_min
                                 ? static_cast<std::uint64_t>(std::int64_t{run_.increment_max} - run_.increment_min)
                                 : 0;
  terms.avar.magnitude_bits = m * span;
  terms.hvar.magnitude_bits = 2 * m * span;
  terms.mvar.magnitude_bits = m * m * span;
  return squares_exact(terms.hvar, n) && squares_exact(terms.mvar, n);
}

// A bound on |x[e] - x[e-m]| (m increments) in this segment, 0 when it does not fit in 62 bits.
template <class Arith>
inline std::uint64_t Characterizer<Arith>::step_bound(std::uint64_t m) const {
  const std::int64_t lo = run_.increment_min, hi = run_.increment_max;
  if (hi < lo || m > (std::uint64_t{1} << 31)) return 0;
  const auto largest = static_cast<std::uint64_t>(-lo > hi ? -lo : hi);
  return m * largest;
}

// The block's terms of one level-0 tau, and its decimated points.
// clang-format off
template <class Arith>
inline void Characterizer<Arith>::level0_block(TauState& t, const Block& b)
  requires(Arith::exact)
{
  // clang-format on
  const auto m = static_cast<std::size_t>(t.result.m >> b.level);  // the lag in the block's series (<= S)
  if (!terms_fit(t.result.m)) {                                    // level 0 only (higher_levels() checks first)
    for (std::size_t j = 0; j < b.n; ++j) {                        // the checked path, point by point
      const Entry now = b.at(*this, j, 0);
      checked_terms(t, now, b.at(*this, j, m), b.at(*this, j, 2 * m), b.at(*this, j, 3 * m));
      if (--t.countdown == 0) decimate(t, now.x);
    }
    return;
  }
  // The points at ages m, 2m, 3m: in the window, or gathered from ring 0 (S > 32).
  if (3 * m <= b.depth) {
    block_sums(t, b, m, b.wx - m, b.wx - 2 * m, b.wx - 3 * m, b.p_lo - m, b.p_lo - 2 * m, b.p_lo - 3 * m);
  } else {
    gathered_sums(t, b, m);
  }
}

// The gathered points live in this function's frame only, not in the usual path's.
// clang-format off
template <class Arith>
void Characterizer<Arith>::gathered_sums(TauState& t, const Block& b, std::size_t m)
  requires(Arith::exact)
{
  // clang-format on
  std::array<std::int64_t, block_points> x1, x2, x3;
  std::array<std::uint64_t, block_points> p1, p2, p3;
  gather(b, m, x1.data(), p1.data());
  gather(b, 2 * m, x2.data(), p2.data());
  gather(b, 3 * m, x3.data(), p3.data());
  block_sums(t, b, m, x1.data(), x2.data(), x3.data(), p1.data(), p2.data(), p3.data());
}

// The block's terms of a tau of lag m from the points at ages m, 2m, 3m, their sums, the
// decimated points and the noise sums.
// clang-format off
template <class Arith>
inline void Characterizer<Arith>::block_sums(TauState& t, const Block& b, std::size_t m, const std::int64_t* x1,
                                              const std::int64_t* x2, const std::int64_t* x3, const std::uint64_t* p1,
                                              const std::uint64_t* p2, const std::uint64_t* p3)
  requires(Arith::exact)
{
  // clang-format on
  std::array<std::int64_t, block_points> a, h, mt;
  BlockTerms terms;
  if (proved_small(t.result.m, b.n, terms)) {
    ProvedSums s;
    if (b.level == 0) {  // the MVAR terms as the running sum of the HVAR terms, from the first one's P
      const std::uint64_t t_first = term::mvar(b.p_lo[0], p1[0], p2[0], p3[0]);
      s = proved_running_terms(b.n, b.x, x1, x2, x3, t_first, a.data(), h.data());
    } else {
      s = proved_terms(b.n, b.x, x1, x2, x3, b.p_lo, p1, p2, p3, a.data(), h.data());
    }
    terms.avar.sum = s.avar;
    terms.mvar.sum = s.mvar;
    terms.hvar.sum = s.hvar;
  } else {
    terms = block_terms(b.n, b.x, x1, x2, x3, b.p_lo, p1, p2, p3, a.data(), h.data(), mt.data());
  }
  Result& r = t.result;
  t.sticky |= add_block(r.sum[0], terms.avar, a.data(), b.n) | add_block(r.sum[1], terms.mvar, mt.data(), b.n) |
              add_block(r.sum[2], terms.hvar, h.data(), b.n);
  r.n[0] += b.n;
  r.n[1] += b.n;
  r.n[2] += b.n;
  // The decimated series: its terms are the overlapping ones at the multiples of m, so the
  // block's bound covers their squares too.
  if (t.countdown > b.n) {
    t.countdown -= b.n;
    return;
  }
  // The countdown stays in 1..m, so for m = 1 every point is decimated and the block's partial
  // sums are already the non-overlapped ones.
  GYROCHAR_ASSERT(t.countdown >= 1 && t.countdown <= m);
  const auto first = static_cast<std::size_t>(t.countdown - 1);
  const std::size_t count = (b.n - 1 - first) / m + 1;
  const std::size_t j = first + (count - 1) * m;  // the newest decimated point
  BlockSquares da = terms.avar, dh = terms.hvar;
  if (m > 1) {
    da.sum = 0;
    dh.sum = 0;
    for (std::size_t k = first; k <= j; k += m) {
      da.sum += static_cast<std::uint64_t>(a[k]) * static_cast<std::uint64_t>(a[k]);
      dh.sum += static_cast<std::uint64_t>(h[k]) * static_cast<std::uint64_t>(h[k]);
    }
  }
  const auto avar_d = static_cast<std::size_t>(SumKind::avar_nonoverlapped);
  const auto hvar_d = static_cast<std::size_t>(SumKind::hvar_nonoverlapped);
  if (squares_exact(da, b.n)) {
    t.sticky |= add_high_word(r.sum[avar_d], UInt128{da.sum, 0});
  } else {
    for (std::size_t k = first; k <= j; k += m) t.sticky |= Arith::accumulate(r.sum[avar_d], a[k]);
  }
  if (squares_exact(dh, b.n)) {
    t.sticky |= add_high_word(r.sum[hvar_d], UInt128{dh.sum, 0});
  } else {
    for (std::size_t k = first; k <= j; k += m) t.sticky |= Arith::accumulate(r.sum[hvar_d], h[k]);
  }
  r.n[avar_d] += count;
  r.n[hvar_d] += count;
  t.noise.add(b.x + first, count, m, step_bound(t.result.m));
  t.decimated = {b.x[j], x1[j], x2[j]};
  t.decimated_count = 3;
  t.countdown = m - (b.n - 1 - j);
}

// x and the low word of P at age `age` of each point of the block.
// clang-format off
template <class Arith>
inline void Characterizer<Arith>::gather(const Block& b, std::uint64_t age, std::int64_t* x, std::uint64_t* p) const
  requires(Arith::exact)
{
  // clang-format on
  const std::size_t from_history = age < b.n ? static_cast<std::size_t>(age) : b.n;
  const std::uint32_t size = 3u * stride();
  std::uint32_t slot = static_cast<std::uint32_t>((b.e0 - age) % size);
  for (std::size_t j = 0; j < from_history; ++j) {
    x[j] = history_[slot].x;
    p[j] = history_[slot].p.lo;
    if (++slot == size) slot = 0;
  }
  for (std::size_t j = from_history; j < b.n; ++j) {
    x[j] = b.x[j - age];
    p[j] = b.p_lo[j - age];
  }
}

// Adds a block's squares to a 128-bit sum: the 64-bit partial sum when it is exact, else the
// terms one by one. Returns the sum's high word (for the sticky overflow bit).
template <class Arith>
inline std::uint64_t Characterizer<Arith>::add_block(UInt128& sum, const BlockSquares& s, const std::int64_t* terms,
                                                     std::size_t n) {
  if (squares_exact(s, n)) return add_high_word(sum, UInt128{s.sum, 0});
  std::uint64_t high = 0;
  for (std::size_t j = 0; j < n; ++j) high |= add_high_word(sum, square(terms[j]));
  return high;
}

}  // namespace gyrochar
