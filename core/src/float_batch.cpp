// The batch path of floating phase (see float_batch.hpp).
#include "gyrochar/float_batch.hpp"

#include <cstring>

namespace gyrochar {
namespace {

using Prefix = FloatArith::Prefix;

// The overlapping sums while they run: AVAR 0, MVAR 1, HVAR 2 (SumKind's order).
struct Sums {
  double sum[3] = {0, 0, 0};
  std::uint64_t n[3] = {0, 0, 0};
};

Prefix prefix(const FloatRecord& r, std::size_t e) { return {r.p_hi[e], r.p_lo[e]}; }

// The terms at point e, one by one, as the characterizer's form_terms() and checked_terms() take
// them: AVAR from e >= 2m, MVAR from e >= 3m - 1 (P_0 = 0 before the first point), HVAR from 3m.
void point_terms(const FloatRecord& r, std::size_t e, std::size_t m, Sums& s) {
  if (e < 2 * m) return;
  const double* x = r.x.data();
  double a = 0, h = 0;
  if (e >= 3 * m) {
    FloatArith::x_terms(x[e], x[e - m], x[e - 2 * m], x[e - 3 * m], a, h);
    s.sum[2] += h * h;
    ++s.n[2];
  } else {
    FloatArith::x_term2(x[e], x[e - m], x[e - 2 * m], a);
  }
  s.sum[0] += a * a;
  ++s.n[0];
  if (e + 1 < 3 * m) return;
  double t = 0;
  FloatArith::p_term(prefix(r, e), prefix(r, e - m), prefix(r, e - 2 * m), e >= 3 * m ? prefix(r, e - 3 * m) : Prefix{}, t);
  s.sum[1] += t * t;
  ++s.n[1];
}

// Points e = from .. size - 1 (from >= 3m), all three terms each, four points a step in vector
// lanes (SIMD where the target has it, scalar code elsewhere): each lane's sums run apart and are
// added at the end. The terms are formed by the same operations as FloatArith's, in the same
// order (no contraction into FMA: the clones' targets have none).
using Lanes = double __attribute__((vector_size(4 * sizeof(double))));

// Four doubles from p (not aligned); the vector by reference: returning it by value would change
// the ABI between the clones.
[[gnu::always_inline]] inline void load(Lanes& v, const double* p) { std::memcpy(&v, p, sizeof v); }

// The four lanes' sums as one: (l0 + l1) + (l2 + l3).
[[gnu::always_inline]] inline double combine(const Lanes& v) { return (v[0] + v[1]) + (v[2] + v[3]); }

// Points e .. e + 3, all three terms, their squares added to the lanes' sums.
[[gnu::always_inline]] inline void steady_step(const double* x, const double* ph, const double* pl, std::size_t e,
                                               std::size_t m, Lanes& sa, Lanes& st, Lanes& sh) {
  const Lanes three{3.0, 3.0, 3.0, 3.0};
  Lanes x0, x1, x2, x3, h0, h1, h2, h3, l0, l1, l2, l3;  // x, and P's hi and lo, at ages 0, m, 2m, 3m
  load(x0, x + e), load(x1, x + e - m), load(x2, x + e - 2 * m), load(x3, x + e - 3 * m);
  load(h0, ph + e), load(h1, ph + e - m), load(h2, ph + e - 2 * m), load(h3, ph + e - 3 * m);
  load(l0, pl + e), load(l1, pl + e - m), load(l2, pl + e - 2 * m), load(l3, pl + e - 3 * m);
  const Lanes d2 = x1 - x2;
  const Lanes a = (x0 - x1) - d2;
  const Lanes h = a - (d2 - (x2 - x3));
  const Lanes t = ((h0 - h3) + (l0 - l3)) + three * ((h2 - h1) + (l2 - l1));
  sa += a * a;
  st += t * t;
  sh += h * h;
}

// The last points of a tau (fewer than four, after its lanes are combined into s), one by one.
[[gnu::always_inline]] inline void tail_terms(const double* x, const double* ph, const double* pl, std::size_t from,
                                              std::size_t size, std::size_t m, double s[3]) {
  for (std::size_t e = from; e < size; ++e) {
    double a = 0, h = 0, t = 0;
    FloatArith::x_terms(x[e], x[e - m], x[e - 2 * m], x[e - 3 * m], a, h);
    FloatArith::p_term({ph[e], pl[e]}, {ph[e - m], pl[e - m]}, {ph[e - 2 * m], pl[e - 2 * m]},
                       {ph[e - 3 * m], pl[e - 3 * m]}, t);
    s[0] += a * a;
    s[1] += t * t;
    s[2] += h * h;
  }
}

#if defined(__x86_64__) && defined(__linux__) && !defined(__clang__)
#define GYROCHAR_FLOAT_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define GYROCHAR_FLOAT_CLONES
#endif
GYROCHAR_FLOAT_CLONES void steady_terms(const double* x, const double* ph, const double* pl, std::size_t from,
                                        std::size_t size, std::size_t m, double out[3]) {
  Lanes sa{0, 0, 0, 0}, st{0, 0, 0, 0}, sh{0, 0, 0, 0};
  std::size_t e = from;
  for (; e + 4 <= size; e += 4) steady_step(x, ph, pl, e, m, sa, st, sh);
  double s[3] = {combine(sa), combine(st), combine(sh)};
  tail_terms(x, ph, pl, e, size, m, s);
  for (std::size_t k = 0; k < 3; ++k) out[k] = s[k];
}

// The decimated series x_0, x_m, x_2m, ...: the characterizer's decimate() (its terms, each sum in
// its order: the AVAR term of the third point, then both terms of each later one, when `sums`) and
// its noise sums (when `lag1`).
void decimate(std::span<const double> xs, std::size_t m, TauResult<double>& result, NoiseIdAccumulator& noise,
              bool sums = true, bool lag1 = true) {
  constexpr auto avar_d = static_cast<std::size_t>(SumKind::avar_nonoverlapped);
  constexpr auto hvar_d = static_cast<std::size_t>(SumKind::hvar_nonoverlapped);
  const std::size_t count = (xs.size() + m - 1) / m;
  if (sums && count >= 3) {
    const double* x = xs.data();
    double sa = result.sum[avar_d], sh = result.sum[hvar_d], a = 0, h = 0;
    FloatArith::x_term2(x[2 * m], x[m], x[0], a);
    sa += a * a;
    for (std::size_t k = 3, e = 3 * m; k < count; ++k, e += m) {
      FloatArith::x_terms(x[e], x[e - m], x[e - 2 * m], x[e - 3 * m], a, h);
      sa += a * a;
      sh += h * h;
    }
    result.sum[avar_d] = sa, result.sum[hvar_d] = sh;
    result.n[avar_d] += count - 2;
    result.n[hvar_d] += count - 3;
  }
  if (lag1) noise.add(xs.data(), count, m);
}

// Several taus at once (float_batch_taus()). A group's taus go through the record together, a
// chunk of points at a time: the points of the chunk at the four ages of the group's taus stay in
// the cache while each tau takes its terms there, so the record streams from memory once a group
// rather than once a tau. Each tau adds its terms to its sums in float_batch_sums()' order: the
// AVAR terms alone (2m <= e < 3m) one by one in e's order, then four lanes that keep their points
// (e = 3m + 4i + lane) from chunk to chunk, combined, and the tail one by one.
constexpr std::size_t chunk_points = 256;

// One fully overlapped tau (stride 1, 2m < size) while the chunks pass.
struct Run {
  std::size_t m = 0;
  std::size_t alone_end = 0;  // AVAR alone on [2m, alone_end): min(3m, size)
  std::size_t lanes_end = 0;  // four points a step on [3m, lanes_end), the tail one by one after
  double alone = 0;           // the squares of the AVAR terms alone so far
  Lanes sa{0, 0, 0, 0}, st{0, 0, 0, 0}, sh{0, 0, 0, 0};
};

// The AVAR terms alone of the runs in [c0, c1), eight runs a step: their terms formed into a[][],
// one row per point with a column per run (0 where a run has no term: adding 0 * 0 leaves a sum of
// squares as it is), then each row added to the eight sums, two vectors of four lanes: each sum
// takes its squares in e's order, as point_terms() does, and the eight run side by side.
constexpr std::size_t alone_lanes = 8;
GYROCHAR_FLOAT_CLONES void alone_chunk(const double* x, Run* runs, std::size_t count, std::size_t c0, std::size_t c1) {
  alignas(32) double a[chunk_points][alone_lanes];
  for (std::size_t g = 0; g < count; g += alone_lanes) {
    const std::size_t n = count - g < alone_lanes ? count - g : alone_lanes;
    std::size_t lo = c1, hi = c0, from[alone_lanes], to[alone_lanes];
    for (std::size_t j = 0; j < alone_lanes; ++j) {
      from[j] = to[j] = c0;
      if (j >= n) continue;
      const Run& r = runs[g + j];
      from[j] = c0 > 2 * r.m ? c0 : 2 * r.m;
      to[j] = c1 < r.alone_end ? c1 : r.alone_end;
      if (from[j] >= to[j]) {
        from[j] = to[j] = c0;
        continue;
      }
      lo = from[j] < lo ? from[j] : lo;
      hi = to[j] > hi ? to[j] : hi;
    }
    if (lo >= hi) continue;
    for (std::size_t j = 0; j < alone_lanes; ++j) {
      const std::size_t m = j < n ? runs[g + j].m : 0;
      const std::size_t b = from[j] > lo ? from[j] : lo, f = to[j] > b ? to[j] : b;
      for (std::size_t e = lo; e < b; ++e) a[e - lo][j] = 0;
      for (std::size_t e = b; e < f; ++e) FloatArith::x_term2(x[e], x[e - m], x[e - 2 * m], a[e - lo][j]);
      for (std::size_t e = f; e < hi; ++e) a[e - lo][j] = 0;
    }
    // The eight sums go in and out of the two vectors through an array: a lane written through
    // a conditional's vector subscript came out wrong in GCC 12's ASan build.
    alignas(32) double sums[alone_lanes] = {};
    for (std::size_t j = 0; j < n; ++j) sums[j] = runs[g + j].alone;
    Lanes s0, s1;
    load(s0, sums), load(s1, sums + 4);
    for (std::size_t i = 0; i < hi - lo; ++i) {
      Lanes v0, v1;
      load(v0, a[i]), load(v1, a[i] + 4);
      s0 += v0 * v0;
      s1 += v1 * v1;
    }
    std::memcpy(sums, &s0, sizeof s0), std::memcpy(sums + 4, &s1, sizeof s1);
    for (std::size_t j = 0; j < n; ++j) runs[g + j].alone = sums[j];
  }
}

// The four-point steps of the runs that start in [c0, c1) (each run's steps start at 3m + 4i, so
// a step may reach three points past c1).
GYROCHAR_FLOAT_CLONES void steady_chunk(const double* x, const double* ph, const double* pl, Run* runs, std::size_t count,
                                        std::size_t c0, std::size_t c1) {
  for (std::size_t j = 0; j < count; ++j) {
    Run& r = runs[j];
    const std::size_t start = 3 * r.m;
    if (c1 <= start) continue;
    const std::size_t from = c0 <= start ? start : start + (c0 - start + 3) / 4 * 4;
    std::size_t to = start + (c1 - start + 3) / 4 * 4;
    to = to < r.lanes_end ? to : r.lanes_end;
    if (from >= to) continue;
    Lanes sa = r.sa, st = r.st, sh = r.sh;
    for (std::size_t e = from; e < to; e += 4) steady_step(x, ph, pl, e, r.m, sa, st, sh);
    r.sa = sa, r.st = st, r.sh = sh;
  }
}

// The overlapping sums of runs[0 .. count) over the record, chunk by chunk, run j's into
// out[index[j]].
void run_group(const FloatRecord& record, Run* runs, const std::size_t* index, std::size_t count,
               std::span<TauResult<double>> out) {
  const std::size_t size = record.x.size();
  const double *x = record.x.data(), *ph = record.p_hi.data(), *pl = record.p_lo.data();
  std::size_t first = size;
  for (std::size_t j = 0; j < count; ++j) first = 2 * runs[j].m < first ? 2 * runs[j].m : first;
  for (std::size_t c0 = first; c0 < size; c0 += chunk_points) {
    const std::size_t c1 = size - c0 < chunk_points ? size : c0 + chunk_points;
    alone_chunk(x, runs, count, c0, c1);
    steady_chunk(x, ph, pl, runs, count, c0, c1);
  }
  for (std::size_t j = 0; j < count; ++j) {
    const Run& r = runs[j];
    const std::size_t m = r.m;
    TauResult<double>& result = out[index[j]];
    Sums s;
    s.sum[0] = r.alone;
    s.n[0] = r.alone_end - 2 * m;
    if (3 * m - 1 < size) {  // the first MVAR term (P_0 = 0), as point_terms() forms it
      double t = 0;
      FloatArith::p_term(prefix(record, 3 * m - 1), prefix(record, 2 * m - 1), prefix(record, m - 1), Prefix{}, t);
      s.sum[1] += t * t;
      ++s.n[1];
    }
    if (size > 3 * m) {
      double steady[3] = {combine(r.sa), combine(r.st), combine(r.sh)};
      tail_terms(x, ph, pl, r.lanes_end, size, m, steady);
      for (std::size_t k = 0; k < 3; ++k) {
        s.sum[k] += steady[k];
        s.n[k] += size - 3 * m;
      }
    }
    for (std::size_t k = 0; k < 3; ++k) {
      result.sum[k] = s.sum[k];
      result.n[k] = s.n[k];
    }
  }
}

// phase_batch_taus(): the MVAR term as an exact running sum of the rounded AVAR terms.

// a + b = s + err exactly (Knuth's two-sum), for a double or a vector of them. Vectors by reference:
// by value they would change the ABI of the clone without AVX (clang's -Wpsabi).
template <class V>
[[gnu::always_inline]] inline void two_sum(const V& a, const V& b, V& s, V& err) {
  s = a + b;
  const V bb = s - a;
  err = (a - (s - bb)) + (b - bb);
}

// The terms at point e of x (x0 .. x3 at ages 0, m, 2m, 3m), as FloatArith::x_terms() forms them:
// the AVAR term a and the HVAR term h = a - a1 (a1 the AVAR term of point e - m, the same bits as
// when it was a), and h's rounding error (a - a1 = h + err exactly), the step of the MVAR term.
template <class V>
[[gnu::always_inline]] inline void terms_and_step(const V& x0, const V& x1, const V& x2, const V& x3, V& a, V& h, V& err) {
  const V d2 = x1 - x2;
  a = (x0 - x1) - d2;
  const V a1 = d2 - (x2 - x3);
  two_sum(a, -a1, h, err);  // a + (-a1) is a - a1, rounded alike
}

// The running MVAR term hi + c: hi the rounded sum of the steps' high parts, c what it lost and
// their low parts.
template <class V>
[[gnu::always_inline]] inline void add_term(V& hi, V& c, const V& term_hi, const V& term_lo) {
  V s, err;
  two_sum(hi, term_hi, s, err);
  hi = s;
  c += err + term_lo;
}

// One tau while its points pass: the sums of squares (SumKind's order) and the running MVAR term.
struct PhaseRun {
  std::size_t m = 0, stride = 1;
  unsigned kinds = all_overlapping_sums;  // the overlapping sums formed (phase_batch_taus())
  bool nonoverlapped = false;             // stride m: the non-overlapped sums are the AVAR and HVAR ones
  double sum[3] = {0, 0, 0};
  std::uint64_t n[3] = {0, 0, 0};
  double t_hi = 0, t_c = 0;
};

// Points [from, to) of one tau (2m <= from), one by one, every case: the AVAR term alone below 3m,
// the squares of the terms at multiples of its stride only (the running term takes every point).
void run_points(const double* x, PhaseRun& r, std::size_t from, std::size_t to) {
  const std::size_t m = r.m, step = r.stride;
  std::size_t counted = (from + step - 1) / step * step;                     // the next point whose terms are summed
  const bool mvar = (r.kinds & sum_bit(SumKind::mvar)) != 0 && 3 * m <= to;  // no MVAR term before 3m - 1
  for (std::size_t e = from; e < to; ++e) {
    double a = 0, h = 0, err = 0;
    const bool steady = e >= 3 * m;
    if (steady) {
      terms_and_step(x[e], x[e - m], x[e - 2 * m], x[e - 3 * m], a, h, err);
    } else {
      FloatArith::x_term2(x[e], x[e - m], x[e - 2 * m], a);
    }
    if (mvar) add_term(r.t_hi, r.t_c, steady ? h : a, err);
    if (e != counted) continue;
    counted += step;
    r.sum[0] += a * a;
    ++r.n[0];
    if (steady) {
      r.sum[2] += h * h;
      ++r.n[2];
    }
    if (e + 1 < 3 * m || !mvar) continue;
    const double t = r.t_hi + r.t_c;
    r.sum[1] += t * t;
    ++r.n[1];
  }
}

// Points [from, to) of up to four fully overlapped taus, one lane a tau (lanes past `count` repeat
// the first tau and are dropped): the terms formed as run_points() forms them, each lane's sums in
// e's order. Steady (from >= 3m of each): the three terms at every point. Otherwise (Ramp) each
// lane from its own start: no term below 2m, the AVAR term alone below 3m, the MVAR term from
// 3m - 1; a lane adds 0 (0 * 0 to a sum of squares, which leaves it as it is) where it has none,
// and reads its points below an age's start at e itself (the value unused).
// Only the sums of `Kinds` (sum_bit()s) are formed: the compiler drops the terms no sum takes.
template <bool Ramp, unsigned Kinds>
[[gnu::always_inline]] inline void lanes(const double* x, PhaseRun* runs, std::size_t count, std::size_t from,
                                         std::size_t to) {
  constexpr bool avar = (Kinds & sum_bit(SumKind::avar)) != 0, mvar = (Kinds & sum_bit(SumKind::mvar)) != 0;
  constexpr bool hvar = (Kinds & sum_bit(SumKind::hvar)) != 0;
  std::size_t k1[4], k2[4], k3[4];  // the ages m, 2m, 3m of each lane
  alignas(32) double init[8][4];    // AVAR, MVAR, HVAR sums, t_hi, t_c of each lane; 2m, 3m, 3m - 1
  for (std::size_t j = 0; j < 4; ++j) {
    const PhaseRun& r = runs[j < count ? j : 0];
    k1[j] = r.m, k2[j] = 2 * r.m, k3[j] = 3 * r.m;
    init[0][j] = r.sum[0], init[1][j] = r.sum[1], init[2][j] = r.sum[2], init[3][j] = r.t_hi, init[4][j] = r.t_c;
    init[5][j] = static_cast<double>(2 * r.m), init[6][j] = static_cast<double>(3 * r.m);
    init[7][j] = static_cast<double>(3 * r.m - 1);
  }
  // The running vectors are copied from and to an array (v): a vector whose address is taken
  // (by memcpy) stays in memory, and a running sum through memory waits on the store each step.
  Lanes v[8];
  std::memcpy(v, init, sizeof v);
  Lanes sa = v[0], st = v[1], sh = v[2], t_hi = v[3], t_c = v[4];
  const Lanes two_m = v[5], three_m = v[6], first_t = v[7];
  const Lanes zero{0, 0, 0, 0};
  const auto age = [&](std::size_t e, std::size_t k) { return Ramp && e < k ? e : e - k; };
  for (std::size_t e = from; e < to; ++e) {
    const Lanes x0{x[e], x[e], x[e], x[e]};
    const Lanes x1{x[age(e, k1[0])], x[age(e, k1[1])], x[age(e, k1[2])], x[age(e, k1[3])]};
    const Lanes x2{x[age(e, k2[0])], x[age(e, k2[1])], x[age(e, k2[2])], x[age(e, k2[3])]};
    const Lanes x3{x[age(e, k3[0])], x[age(e, k3[1])], x[age(e, k3[2])], x[age(e, k3[3])]};
    Lanes a, h, err;
    terms_and_step(x0, x1, x2, x3, a, h, err);
    if constexpr (Ramp) {
      const Lanes ev = zero + static_cast<double>(e);
      const auto has_a = ev >= two_m, has_h = ev >= three_m, has_t = ev >= first_t;
      a = has_a ? a : zero;
      h = has_h ? h : zero;
      if constexpr (mvar) {
        add_term(t_hi, t_c, has_h ? h : a, has_h ? err : zero);
        const Lanes t = has_t ? t_hi + t_c : zero;
        st += t * t;
      }
    } else if constexpr (mvar) {
      add_term(t_hi, t_c, h, err);
      const Lanes t = t_hi + t_c;
      st += t * t;
    }
    if constexpr (avar) sa += a * a;
    if constexpr (hvar) sh += h * h;
  }
  v[0] = sa, v[1] = st, v[2] = sh, v[3] = t_hi, v[4] = t_c;
  std::memcpy(init, v, sizeof v);
  for (std::size_t j = 0; j < count; ++j) {
    PhaseRun& r = runs[j];
    r.sum[0] = init[0][j], r.sum[1] = init[1][j], r.sum[2] = init[2][j], r.t_hi = init[3][j], r.t_c = init[4][j];
  }
}
// lanes() for the sums runs[0].kinds asks (the same for the runs of a group).
template <bool Ramp>
[[gnu::always_inline]] inline void lanes_of_kinds(const double* x, PhaseRun* runs, std::size_t count, std::size_t from,
                                                  std::size_t to) {
  switch (runs[0].kinds & all_overlapping_sums) {
    case 1: return lanes<Ramp, 1>(x, runs, count, from, to);
    case 2: return lanes<Ramp, 2>(x, runs, count, from, to);
    case 3: return lanes<Ramp, 3>(x, runs, count, from, to);
    case 4: return lanes<Ramp, 4>(x, runs, count, from, to);
    case 5: return lanes<Ramp, 5>(x, runs, count, from, to);
    case 6: return lanes<Ramp, 6>(x, runs, count, from, to);
    case 7: return lanes<Ramp, 7>(x, runs, count, from, to);
    default: return;
  }
}
GYROCHAR_FLOAT_CLONES void steady_lanes(const double* x, PhaseRun* runs, std::size_t count, std::size_t from,
                                        std::size_t to) {
  lanes_of_kinds<false>(x, runs, count, from, to);
}
GYROCHAR_FLOAT_CLONES void ramp_lanes(const double* x, PhaseRun* runs, std::size_t count, std::size_t from, std::size_t to) {
  lanes_of_kinds<true>(x, runs, count, from, to);
}

// The taus of runs[0 .. count) (fully overlapped, 3m < size for each) over the record, side by
// side: each from its own start up to 3m of the largest, then all in the steady state.
void run_group(std::span<const double> x, PhaseRun* runs, std::size_t count) {
  const std::size_t size = x.size();
  std::size_t least = size, most = 0;
  for (std::size_t j = 0; j < count; ++j) {
    least = runs[j].m < least ? runs[j].m : least;
    most = runs[j].m > most ? runs[j].m : most;
  }
  const std::size_t steady = 3 * most < size ? 3 * most : size;
  ramp_lanes(x.data(), runs, count, 2 * least, steady);
  if (steady < size) steady_lanes(x.data(), runs, count, steady, size);
  for (std::size_t j = 0; j < count; ++j) {
    PhaseRun& r = runs[j];
    r.n[0] = size - 2 * r.m;
    r.n[1] = size - 3 * r.m + 1;
    r.n[2] = size - 3 * r.m;
  }
}

void store(const PhaseRun& r, TauResult<double>& out) {
  for (std::size_t k = 0; k < 3; ++k) {
    const bool formed = (r.kinds & (1u << k)) != 0;
    out.sum[k] = formed ? r.sum[k] : 0.0;
    out.n[k] = formed ? r.n[k] : 0;
  }
  if (!r.nonoverlapped) return;
  for (const auto& [overlapped, alone] :
       {std::pair{SumKind::avar, SumKind::avar_nonoverlapped}, std::pair{SumKind::hvar, SumKind::hvar_nonoverlapped}}) {
    out.sum[static_cast<std::size_t>(alone)] = r.sum[static_cast<std::size_t>(overlapped)];
    out.n[static_cast<std::size_t>(alone)] = r.n[static_cast<std::size_t>(overlapped)];
  }
}

}  // namespace

TauResult<double> float_batch_sums(const FloatRecord& record, std::uint64_t m, std::uint64_t stride,
                                   NoiseIdAccumulator& noise) {
  TauResult<double> result;
  result.m = m;
  result.stride = stride;
  const std::size_t size = record.x.size();
  if (m == 0) return result;
  if (m >= size) {  // no term; the decimated series is x_0 alone (when there is one)
    if (size > 0) noise.add(record.x[0]);
    return result;
  }
  const auto lag = static_cast<std::size_t>(m);
  decimate(record.x, lag, result, noise);
  Sums s;
  if (stride == 1 && size > 3 * lag) {
    for (std::size_t e = 2 * lag; e < 3 * lag; ++e) point_terms(record, e, lag, s);
    double steady[3];
    steady_terms(record.x.data(), record.p_hi.data(), record.p_lo.data(), 3 * lag, size, lag, steady);
    for (std::size_t k = 0; k < 3; ++k) {
      s.sum[k] += steady[k];
      s.n[k] += size - 3 * lag;
    }
  } else {
    const auto step = static_cast<std::size_t>(stride);
    const std::size_t first = (2 * lag + step - 1) / step * step;
    for (std::size_t e = first; e < size; e += step) point_terms(record, e, lag, s);
  }
  for (std::size_t k = 0; k < 3; ++k) {
    result.sum[k] = s.sum[k];
    result.n[k] = s.n[k];
  }
  return result;
}

void float_batch_taus(const FloatRecord& record, std::span<const std::uint64_t> m, std::span<const std::uint64_t> stride,
                      std::span<TauResult<double>> out, std::span<NoiseIdAccumulator> noise) {
  const std::size_t size = record.x.size();
  Run runs[float_batch_group];
  std::size_t index[float_batch_group];  // runs[j] is tau index[j]
  std::size_t count = 0;
  for (std::size_t i = 0; i < m.size() && i < stride.size() && i < out.size() && i < noise.size(); ++i) {
    if (stride[i] != 1 || m[i] == 0 || m[i] >= size || size - m[i] <= m[i]) {  // strided, or no overlapping term
      out[i] = float_batch_sums(record, m[i], stride[i], noise[i]);
      continue;
    }
    const auto lag = static_cast<std::size_t>(m[i]);
    out[i] = TauResult<double>{};
    out[i].m = m[i];
    out[i].stride = 1;
    decimate(record.x, lag, out[i], noise[i]);
    Run& r = runs[count];
    r = Run{};
    r.m = lag;
    r.alone_end = 3 * lag < size ? 3 * lag : size;
    r.lanes_end = size > 3 * lag ? 3 * lag + (size - 3 * lag) / 4 * 4 : 3 * lag;
    index[count++] = i;
    if (count == float_batch_group) {
      run_group(record, runs, index, count, out);
      count = 0;
    }
  }
  if (count > 0) run_group(record, runs, index, count, out);
}

void phase_batch_taus(std::span<const double> x, std::span<const std::uint64_t> m, std::span<const std::uint64_t> stride,
                      std::span<TauResult<double>> out, std::span<NoiseIdAccumulator> noise, unsigned kinds) {
  constexpr unsigned decimated = sum_bit(SumKind::avar_nonoverlapped) | sum_bit(SumKind::hvar_nonoverlapped);
  const bool lag1 = (kinds & noise_sums) != 0, alone = (kinds & decimated) != 0;
  const std::size_t size = x.size();
  PhaseRun runs[phase_batch_lanes];
  std::size_t index[phase_batch_lanes];  // runs[j] is tau index[j]
  std::size_t count = 0;
  const auto flush = [&] {
    run_group(x, runs, count);
    for (std::size_t j = 0; j < count; ++j) store(runs[j], out[index[j]]);
    count = 0;
  };
  for (std::size_t i = 0; i < m.size() && i < stride.size() && i < out.size() && i < noise.size(); ++i) {
    out[i] = TauResult<double>{};
    out[i].m = m[i];
    out[i].stride = stride[i];
    if (m[i] == 0) continue;
    if (m[i] >= size) {  // no term; the decimated series is x_0 alone (when there is one)
      if (size > 0 && lag1) noise[i].add(x[0]);
      continue;
    }
    const auto lag = static_cast<std::size_t>(m[i]);
    PhaseRun r;
    r.m = lag;
    r.kinds = kinds & all_overlapping_sums;
    r.stride = stride[i] > 1 ? static_cast<std::size_t>(stride[i]) : 1;
    // Terms every m points (m = 1 fully overlapped, or a stride of m) are the decimated series'
    // own, in its order: its sums are the AVAR and HVAR ones (the same bits), taken from them.
    constexpr unsigned both = sum_bit(SumKind::avar) | sum_bit(SumKind::hvar);
    r.nonoverlapped = alone && r.stride == lag && size > 2 * lag && (kinds & both) == both;
    decimate(x, lag, out[i], noise[i], alone && !r.nonoverlapped, lag1);
    if (size <= 2 * lag) continue;  // no overlapping term
    if (r.stride != 1 || size <= 3 * lag) {
      run_points(x.data(), r, 2 * lag, size);
      store(r, out[i]);
      continue;
    }
    runs[count] = r;
    index[count++] = i;
    if (count == phase_batch_lanes) flush();
  }
  if (count > 0) flush();
  for (std::size_t i = 0; i < m.size() && i < stride.size() && i < out.size() && i < noise.size(); ++i)
    for (const SumKind k : {SumKind::avar_nonoverlapped, SumKind::hvar_nonoverlapped})
      if ((kinds & sum_bit(k)) == 0) out[i].sum[static_cast<std::size_t>(k)] = 0, out[i].n[static_cast<std::size_t>(k)] = 0;
}

}  // namespace gyrochar
