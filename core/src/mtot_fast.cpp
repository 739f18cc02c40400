// Exact MTOTVAR from lag sums; the derivation in docs/total.md ("MTOTVAR exactly, from lag sums"),
// the interface in total_fast.hpp.
//
// Notation (docs/total.md): a window of len = 3m residuals starting at n; Sp the prefix sums of the
// residual, zero before the record; U_n[t] = Sp[n + t] - Sp[n]. Every modified-Allan term of the
// detrended, reflected window is z_k(n) = sum_j a_j Sp[n + p_j(k)]: four "moving" positions
// p = s k + o (s = +-1, the reflected copies) with integer coefficients constant over each m-run of
// k, and four fixed positions 0, h, len - h, len (the constant of the reflection and the slope's
// half sums) whose coefficients phi depend on k.
#include <algorithm>
#include <cstdint>

#include "gyrochar/total_fast.hpp"

namespace gyrochar {
namespace {

using Index = std::size_t;
using Pos = std::int64_t;  // positions relative to a window, may be negative
using Wide = long double;

struct Terms {
  int a[4] = {}, s[4] = {};
  Pos o[4] = {};
  int at_len = 0;      // the coefficient of U[len] from the reflections
  int moving = 0;      // the sum of a
  double phi[4] = {};  // at the fixed positions 0, h, len - h, len
  Pos pos(int i, Pos k) const { return s[i] * k + o[i]; }
};

struct Geometry {
  Pos m, len, h, run;
  Pos fixed[4];
  explicit Geometry(Pos m_) : m(m_), len(3 * m_), h(3 * m_ / 2), run(3 * m_ - 3 * m_ / 2), fixed{0, h, len - h, len} {}

  static Wide sum_t2(Pos tau) {  // sum_{t<tau} t^2
    const Wide T = static_cast<Wide>(tau);
    return (T - 1) * T * (2 * T - 1) / 6;
  }

  // z_k = E[k+3m] - 3 E[k+2m] + 3 E[k+m] - E[k] with E the prefix sums of the 9m-point extension:
  // E[q] = U[len] - U[len - q] (first copy), U[len] + U[q - len] (the window), 3 U[len] - U[3 len - q]
  // (last copy); then the slope's line, removed: z_k -= slope * (z_k of the ramp t), slope =
  // (U[len] - U[len - h] - U[h]) / (h run).
  Terms terms(Pos k) const {
    static constexpr int w[4] = {-1, 3, -3, 1};
    Terms t;
    const Pos j = k / m;
    int at_len = 0, moving = 0;  // the coefficient of U[len] and the moving coefficients' sum
    for (int i = 0; i < 4; ++i) {
      const Pos c = j + i;
      if (c <= 2) t.a[i] = -w[i], t.s[i] = -1, t.o[i] = len - i * m, at_len += w[i];
      else if (c <= 5) t.a[i] = w[i], t.s[i] = 1, t.o[i] = i * m - len, at_len += w[i];
      else t.a[i] = -w[i], t.s[i] = -1, t.o[i] = 3 * len - i * m, at_len += 3 * w[i];
      moving += t.a[i];
    }
    t.at_len = at_len, t.moving = moving;
    return at(t, k);
  }
  // Term k of the m-run whose coefficients and offsets are t's: its fixed positions' coefficients.
  Terms at(Terms t, Pos k) const {
    const double b = beta(t, k);
    t.phi[0] = -(t.moving + t.at_len) + b;  // U[t] = Sp[n + t] - Sp[n]: the coefficients sum to 0
    t.phi[1] = -b, t.phi[2] = -b, t.phi[3] = t.at_len + b;
    return t;
  }
  // The slope's coefficient beta of term k, whose m-run has the coefficients and offsets of t:
  // minus z_k of the ramp t (a constant changes no z), computed in integers, exact (below 2^53 for
  // len < 2^25), over h run.
  double beta(const Terms& t, Pos k) const {
    Pos ramp = t.at_len * sum_t_int(len);
    for (int i = 0; i < 4; ++i) ramp += t.a[i] * sum_t_int(t.pos(i, k));
    return -static_cast<double>(ramp) / (static_cast<double>(h) * static_cast<double>(run));
  }
  static Pos sum_t_int(Pos tau) { return tau * (tau - 1) / 2; }  // sum_{t<tau} t
  // The same term's value on a window whose U is the function u.
  template <class F>
  Wide apply(const Terms& t, Pos k, F u) const {
    Wide z = 0;
    for (int i = 0; i < 4; ++i) z += t.a[i] * u(t.pos(i, k));
    for (int f = 1; f < 4; ++f) z += t.phi[f] * u(fixed[f]);
    return z + t.phi[0] * u(0);
  }
};

// The 6m terms, each pair of mirror terms once with weight 2: the extension
// is even about its reflection points and the modified Allan filter symmetric, so z_k = z_{len-k}
// on [0, len] and z_k = z_{3 len - k} on (len, 2 len), for every window (the kernels are equal,
// not their split into moving and fixed positions).
// for_each_run_piece calls f(k0, k1, weight, t) for the k in [k0, k1), pieces that lie in one m-run
// each, t the run's coefficients and offsets (Geometry::at gives term k's fixed coefficients from it).
template <class F>
void for_each_run_piece(const Geometry& g, F f) {
  auto split = [&](Pos lo, Pos hi, double weight) {
    for (Pos k = lo; k < hi;) {
      const Pos end = std::min(hi, (k / g.m + 1) * g.m);
      f(k, end, weight, g.terms(k));
      k = end;
    }
  };
  const Pos len = g.len;
  split(0, (len + 1) / 2, 2.0);  // 2 k < len
  if (len % 2 == 0) split(len / 2, len / 2 + 1, 1.0);
  split(len + 1, (3 * len + 1) / 2, 2.0);  // len < k, 2 k < 3 len
  if (len % 2 == 0) split(3 * len / 2, 3 * len / 2 + 1, 1.0);
}

// The sum over every k of the autocorrelation of z_k's kernel on the window (as a function of the
// residual), A(d) for d in [0, len]: from the autocorrelation B of its first difference (eight
// spikes a k), summed twice (A vanishes from d = len on). Per m-run and pair of spikes: two that
// move the same way, or two fixed ones, are at one distance for the whole run (their products
// summed, one update); the others sweep B once each (one stream at a time, not 28 scattered updates
// a term). `beta` holds the run's slope coefficients (m doubles).
void kernel_autocorrelation(const Geometry& g, std::span<double> A, std::span<double> B, std::span<double> beta) {
  for (Pos d = 0; d <= g.len; ++d) B[static_cast<Index>(d)] = 0.0;
  auto add = [&B](Pos d, double v) { B[static_cast<Index>(d < 0 ? -d : d)] += d == 0 ? 2.0 * v : v; };
  for_each_run_piece(g, [&](Pos k0, Pos k1, double weight, const Terms& t) {
    const double count = static_cast<double>(k1 - k0);
    for (Pos k = k0; k < k1; ++k) beta[static_cast<Index>(k - k0)] = g.beta(t, k);
    // phi_e(k) as Geometry::at: base_e + beta(k) at the ends (0, len), -beta(k) at h and len - h
    const double base[4] = {static_cast<double>(-(t.moving + t.at_len)), 0.0, 0.0, static_cast<double>(t.at_len)};
    auto phi = [&](int e, Pos k) {
      const double b = beta[static_cast<Index>(k - k0)];
      return e == 0 || e == 3 ? base[e] + b : -b;
    };
    for (int u = 0; u < 4; ++u) {
      const double au = t.a[u];
      B[0] += weight * au * au * count;
      for (int x = u + 1; x < 4; ++x) {
        const double c = weight * au * t.a[x];
        if (t.s[u] == t.s[x]) add(t.o[u] - t.o[x], c * count);
        else
          for (Pos k = k0; k < k1; ++k) add(t.pos(u, k) - t.pos(x, k), c);
      }
      for (int e = 0; e < 4; ++e) {
        const double c = weight * au;
        for (Pos k = k0; k < k1; ++k) add(t.pos(u, k) - g.fixed[e], c * phi(e, k));
      }
    }
    double products[4][4] = {};
    for (Pos k = k0; k < k1; ++k) {
      double p[4];
      for (int e = 0; e < 4; ++e) p[e] = phi(e, k);
      for (int e = 0; e < 4; ++e)
        for (int f = e; f < 4; ++f) products[e][f] += p[e] * p[f];
    }
    for (int e = 0; e < 4; ++e) {
      B[0] += weight * products[e][e];
      for (int f = e + 1; f < 4; ++f) add(g.fixed[e] - g.fixed[f], weight * products[e][f]);
    }
  });
  // B(d) = 2 A(d) - A(d - 1) - A(d + 1)
  Wide above = 0, here = 0;  // A(d + 1), A(d) from d = len
  for (Pos d = g.len; d >= 1; --d) {
    const Wide below = 2 * here - above - B[static_cast<Index>(d)];
    above = here, here = below;
    A[static_cast<Index>(d - 1)] = static_cast<double>(below);
  }
  A[static_cast<Index>(g.len)] = 0.0;
}

// The products of two moving positions that move the same way, over the windows past both ends:
// sum over (n, k) of Sp[n + s k + o] Sp[n + s k + o + delta] is sum_i W(i) Sp[i] Sp[i + delta], W(i)
// the number of (n, k) with n + s k + o = i, a trapezoid in i (the convolution of the boxes of n and
// of s k), whose second difference is four spikes of +-1. All the pairs and m-runs with one
// distance delta (0, m or 2m: the offsets within one reflected copy differ by multiples of m) share
// one weight, the sum of their trapezoids times their coefficients: an integer, piecewise linear
// between the spikes, built from them in one sweep. So three passes over the ends instead of one
// per pair, run and end; both ends in each (the windows' geometry is the same), W exact (integers
// below 2^53 in doubles).
struct Spike {
  Pos delta, at, step;  // the weight of distance delta: its second difference at `at`
};

Wide same_way_terms(const Geometry& g, std::span<const double> head, std::span<const double> tail) {
  const Pos len = g.len, n0 = -(len - 1), n1 = 0;
  Spike spikes[6 * 10 * 4];
  int count = 0;
  for (Pos j = 0; j < 6; ++j) {
    const Pos k0 = j * g.m, k1 = k0 + g.m;
    const Terms t = g.terms(k0);
    for (int u = 0; u < 4; ++u)
      for (int v = u; v < 4; ++v) {
        if (t.s[u] != t.s[v]) continue;
        const Pos c = (u == v ? 1 : 2) * t.a[u] * t.a[v];
        // The first factor the lower position: i = n + s k + o, the other at i + delta, delta >= 0.
        const Pos o = t.o[u] <= t.o[v] ? t.o[u] : t.o[v], delta = t.o[u] <= t.o[v] ? t.o[v] - t.o[u] : t.o[u] - t.o[v];
        // The box of s k: [k0, k1), or [1 - k1, 1 - k0) for s = -1; that of n: [n0, n1).
        const Pos a = t.s[u] > 0 ? k0 : 1 - k1, b = t.s[u] > 0 ? k1 : 1 - k0;
        spikes[count++] = {delta, o + a + n0, c};
        spikes[count++] = {delta, o + b + n0, -c};
        spikes[count++] = {delta, o + a + n1, -c};
        spikes[count++] = {delta, o + b + n1, c};
      }
  }
  std::sort(spikes, spikes + count,
            [](const Spike& x, const Spike& y) { return x.delta != y.delta ? x.delta < y.delta : x.at < y.at; });
  Wide sum = 0;
  for (int first = 0; first < count;) {
    int last = first;  // the spikes of this distance: [first, last)
    while (last < count && spikes[last].delta == spikes[first].delta) ++last;
    const Pos delta = spikes[first].delta, lo = 1, hi = len - delta;  // Sp nonzero at 1 .. len - 1
    // W(i) = slope i + offset between spikes: each spike (at, step) adds step (i - at + 1) from at on.
    Pos slope = 0, offset = 0;
    double part = 0;
    for (int e = first; e < last; ++e) {
      slope += spikes[e].step, offset += spikes[e].step * (1 - spikes[e].at);
      const Pos from = spikes[e].at > lo ? spikes[e].at : lo;
      const Pos next = e + 1 < last ? spikes[e + 1].at : hi;
      const Pos to = next < hi ? next : hi;
      if (from >= to || (slope == 0 && offset + slope * from == 0)) continue;
      double weight = static_cast<double>(slope * from + offset), step = static_cast<double>(slope);
      const double* x = head.data() + delta;
      const double* y = tail.data() + delta;
      double s0 = 0, s1 = 0;  // two chains: the additions' latency, not their count, bounds the loop
      Pos i = from;
      for (; i + 1 < to; i += 2) {
        const Index at = static_cast<Index>(i);
        s0 += weight * (head[at] * x[at] + tail[at] * y[at]);
        s1 += (weight + step) * (head[at + 1] * x[at + 1] + tail[at + 1] * y[at + 1]);
        weight += 2 * step;
      }
      if (i < to) {
        const Index at = static_cast<Index>(i);
        s0 += weight * (head[at] * x[at] + tail[at] * y[at]);
      }
      part += s0 + s1;
    }
    sum += part;
    first = last;
  }
  return sum;
}

// The products of two moving positions that move oppositely, over the windows past both ends: for
// a pair (op moving up, om down) and an m-run [k0, k1), sum over n in [n0, n1) and k of Sp[n + k +
// op] Sp[n - k + om]. For each y = n - k + om the other factor runs over every other position from
// y + op - om + 2 ka to y + op - om + 2 kb (k in [ka, kb), the run clipped by n's range): a
// difference of T2 (sums of Sp over the positions below x of x's parity). Where the run clips, the
// T2 is read at y + D (D = op - om + 2 k0 or 2 k1: a lag); where n's range does, at E - y (E = op +
// om + 2 n0 or 2 n1: a reflection). So every pair and run is up to four pieces sum_y c Sp[y]
// T2[y + D] or T2[E - y] over ranges of y; the pieces of one D (or E) share a sweep, their
// coefficients summed as steps at the ends of their ranges (11 sweeps of at most len instead of 20
// loops a tau, both ends in each). T2 of the start in T2h, of the end in T2t (len + 2 each).
struct Piece {
  int reflected;  // 0: T2[y + key], 1: T2[key - y]
  Pos key, at, step;
};

Wide opposite_way_terms(const Geometry& g, std::span<const double> head, std::span<const double> tail, std::span<double> T2h,
                        std::span<double> T2t) {
  const Pos len = g.len, n0 = -(len - 1), n1 = 0;
  T2h[0] = T2h[1] = T2t[0] = T2t[1] = 0.0;
  for (Index x = 2; x <= static_cast<Index>(len) + 1; ++x) {
    const bool inside = x - 2 >= 1 && x - 2 < static_cast<Index>(len);  // Sp[0] = 0, zero from len on
    T2h[x] = T2h[x - 2] + (inside ? head[x - 2] : 0.0), T2t[x] = T2t[x - 2] + (inside ? tail[x - 2] : 0.0);
  }
  Piece pieces[6 * 4 * 4 * 2];
  int count = 0;
  auto add = [&](int reflected, Pos key, Pos lo, Pos hi, Pos c) {  // c on [lo, hi]
    if (lo > hi) return;
    pieces[count++] = {reflected, key, lo, c};
    pieces[count++] = {reflected, key, hi + 1, -c};
  };
  for (Pos j = 0; j < 6; ++j) {
    const Pos k0 = j * g.m, k1 = k0 + g.m;
    const Terms t = g.terms(k0);
    for (int u = 0; u < 4; ++u)
      for (int v = u + 1; v < 4; ++v) {
        if (t.s[u] == t.s[v]) continue;
        const Pos c = 2 * t.a[u] * t.a[v];
        const Pos op = t.s[u] > 0 ? t.o[u] : t.o[v], om = t.s[u] > 0 ? t.o[v] : t.o[u];
        // y in [lo, hi]: every y there has ka < kb; kb = k1 up to yb, ka = k0 from ya on.
        const Pos lo = std::max<Pos>(n0 - (k1 - 1) + om, 1), hi = std::min<Pos>(n1 - 1 - k0 + om, len - 1);
        const Pos yb = n1 + om - k1, ya = n0 + om - k0;
        add(0, op - om + 2 * k1, lo, std::min(hi, yb), c);
        add(1, op + om + 2 * n1, std::max(lo, yb + 1), hi, c);
        add(0, op - om + 2 * k0, std::max(lo, ya), hi, -c);
        add(1, op + om + 2 * n0, lo, std::min(hi, ya - 1), -c);
      }
  }
  std::sort(pieces, pieces + count, [](const Piece& x, const Piece& y) {
    if (x.reflected != y.reflected) return x.reflected < y.reflected;
    return x.key != y.key ? x.key < y.key : x.at < y.at;
  });
  auto at2 = [len](Pos x) -> Index {  // T2's index for x >= 0: constant by parity from len on
    return static_cast<Index>(x < len ? x : len + ((x - len) & 1));
  };
  Wide sum = 0;
  for (int first = 0; first < count;) {
    int last = first;
    while (last < count && pieces[last].reflected == pieces[first].reflected && pieces[last].key == pieces[first].key)
      ++last;
    const bool reflected = pieces[first].reflected == 1;
    const Pos key = pieces[first].key;
    Pos weight = 0;
    double part = 0;
    for (int e = first; e + 1 < last; ++e) {
      weight += pieces[e].step;
      if (weight == 0) continue;
      const Pos from = pieces[e].at, to = pieces[e + 1].at;  // [from, to), within [1, len - 1]
      double s0 = 0;
      for (Pos y = from; y < to; ++y) {
        const Pos x = reflected ? key - y : y + key;
        if (x < 0) continue;
        const Index i = at2(x), at = static_cast<Index>(y);
        s0 += head[at] * T2h[i] + tail[at] * T2t[i];
      }
      part += static_cast<double>(weight) * s0;
    }
    sum += part;
    first = last;
  }
  return sum;
}

// The products with a fixed position in the windows past both ends, from X[f][p] = sum over both
// ends and their windows of Sp[n + fixed_f] Sp[n + p] = sum_{i=1}^{fixed_f - 1} Sp[i] Sp[i + p -
// fixed_f] (f = 0 gives nothing: Sp[n] = 0 for n < 0). X[3] is the ends' autocorrelation read
// backwards; X[1] a correlation of each end's first h values with the end; X[2] the same as X[1]
// when len is even (len - h = h), one point longer and one lag further when it is odd. X[1] and X[2]
// share their coefficient (phi_1 = phi_2 = -beta), so only their sum Y = X[1] + X[2] is kept.
// X[1] and X[3] go in the FFT buffer past the transforms' part, Y at its start once they are read
// out. Three FFTs of length n = fft_length(2 len) where their two spectra fit the half of the buffer
// the preparation has touched (4 n <= P); otherwise, near the largest m, X[1] from three
// autocorrelation sums that stay within 2 n doubles (fixed_terms), not the buffer's fresh half.
bool three_transforms(Pos len, const Theo1Workspace& w) {
  return 4 * fft_length(2 * static_cast<Index>(len)) <= w.buffer.size() / 2;
}

Wide fixed_terms(const Geometry& g, std::span<const double> head, std::span<const double> tail, Theo1Workspace& w) {
  const Pos len = g.len, h = g.h;
  const Index L = static_cast<Index>(len), H = static_cast<Index>(h);
  const Index n = fft_length(2 * L);  // at least h + len: no wrap-around for X[1] either
  std::span<double> X1, X3;
  if (three_transforms(len, w)) {
    // X[3] and X[1] from three FFTs: the ends' autocorrelations and their correlations with their
    // first h values, both real, come back together from one inverse (docs/total.md).
    ends_correlations(head, tail, H, n, w);
    const double* d = w.buffer.data();
    X3 = w.buffer.subspan(2 * n, L + 1), X1 = w.buffer.subspan(2 * n + L + 1, L + 1);
    const double scale = 1.0 / static_cast<double>(n);
    X3[0] = 0.0;
    for (Index p = 1; p <= L; ++p) X3[p] = d[2 * (L - p)] * scale;
    for (Index p = 0; p <= L; ++p) X1[p] = d[2 * ((p + n - H) % n) + 1] * scale;
  } else {
    // X[1][p] = c(p - h), c(e) the sum over both ends of sum_{i < h} Sp[i] Sp[i + e]: for e >= 0 the
    // ends' autocorrelation less that of their values from h on, for e < 0 the autocorrelation of
    // their first h values at -e. Three autocorrelation sums (two FFTs each, of length n and twice
    // of at most n / 2) in the buffer's first 2 n doubles, X[3] and X[1] past its first n.
    // 2 L + 2 <= n: n = fft_length(2 L) is above 2 L, as len = 3 m is no power of two
    X3 = w.buffer.subspan(n, L + 1), X1 = w.buffer.subspan(n + L + 1, L + 1);
    autocorrelation_sum(head, tail, n, w);
    X3[0] = 0.0;
    for (Index p = 1; p <= L; ++p) X3[p] = w.buffer[L - p];
    for (Index p = H; p <= L; ++p) X1[p] = w.buffer[p - H];
    autocorrelation_sum(head.subspan(H), tail.subspan(H), fft_length(2 * (L - H)), w);
    for (Index p = H; p <= L; ++p) X1[p] -= w.buffer[p - H];
    autocorrelation_sum(head.first(H), tail.first(H), fft_length(2 * H), w);
    for (Index p = 0; p < H; ++p) X1[p] = w.buffer[H - p];
  }
  const std::span<double> Y = w.buffer.first(L + 1);  // X[1] + X[2]
  Y[0] = X1[0];
  for (Index p = 1; p <= L; ++p)
    Y[p] = X1[p] + (len % 2 == 0 ? X1[p] : X1[p - 1] + (p >= 2 ? head[H] * head[p - 1] + tail[H] * tail[p - 1] : 0.0));
  // The fixed positions' values, read once.
  double y_at[4], x3_at[4];
  for (int e = 1; e < 4; ++e) {
    const Index at = static_cast<Index>(g.fixed[e]);
    y_at[e] = Y[at], x3_at[e] = X3[at];
  }
  Wide sum = 0;                  // every k: the split into moving and fixed positions is not mirror-symmetric
  for (Pos j = 0; j < 6; ++j) {  // per m-run of k the moving positions' coefficients are constant
    const Pos k0 = j * g.m;
    const Terms t0 = g.terms(k0);
    for (Pos k = k0; k < k0 + g.m; ++k) {
      const double beta = g.beta(t0, k);
      double moving_y = 0, moving_3 = 0;
      for (int i = 0; i < 4; ++i) {
        const Index at = static_cast<Index>(t0.pos(i, k));
        moving_y += t0.a[i] * Y[at], moving_3 += t0.a[i] * X3[at];
      }
      const double phi3 = t0.at_len + beta;  // phi_1 = phi_2 = -beta
      const double fixed_y = -beta * (y_at[1] + y_at[2]) + phi3 * y_at[3];
      const double fixed_3 = -beta * (x3_at[1] + x3_at[2]) + phi3 * x3_at[3];
      sum += -beta * (2 * moving_y + fixed_y) + phi3 * (2 * moving_3 + fixed_3);
    }
  }
  return sum;
}

// The sum over every window of 3m values of the prepared sequence of the 6m squared terms z_k
// (MTOTVAR's kernel; HTOTVAR's on the frequencies), in two pieces (total_fast.hpp): piece 0 the
// whole record's autocorrelation weighted, less the windows' moving products past both ends, and
// the removed quadratic's terms; piece 1 the products at fixed positions (fixed_terms, the FFTs).
// Valid input checked by the caller.
void window_piece(Theo1Workspace& w, std::span<double> scratch, std::uint64_t m, int piece, MtotPieces& out) {
  const Index N = w.r.size();
  const Geometry g(static_cast<Pos>(m));
  const Index len = static_cast<Index>(g.len), windows = N - len + 1;
  // The arrays needed while the FFT buffer is free live in it (its first P doubles are already
  // touched by the preparation): on this scale first touching fresh memory costs as much as the
  // arithmetic (docs/total.md). The caller's scratch holds the end's prefix sums (the start's are the
  // record's, w.s1): each piece makes them in its own.
  const std::span<const double> head = w.s1.first(len);
  const std::span<double> tail = scratch.first(len);
  tail[0] = 0.0;
  for (Index i = 1; i < len; ++i) tail[i] = tail[i - 1] + w.r[N - i];
  if (piece == 1) {
    out.fixed = fixed_terms(g, head, tail, w);
    return;
  }
  // Every window that meets the record, the residual zero outside: the autocorrelation weighted.
  const std::span<double> A = w.buffer.first(len + 1), B = w.buffer.subspan(len + 1, len + 1);
  kernel_autocorrelation(g, A, B, w.buffer.subspan(2 * len + 2, static_cast<Index>(g.m)));
  Wide sum = static_cast<Wide>(A[0]) * w.ac[0];
  for (Index d = 1; d < len; ++d) sum += 2 * static_cast<Wide>(A[d]) * w.ac[d];
  // Less the windows that stick out at the start, and at the end (the sum of a window's squares does
  // not change when the window is reversed: the end's residuals are read backwards).
  sum -= same_way_terms(g, head, tail);
  // A and B no longer needed: T2 of both ends in their place.
  sum -= opposite_way_terms(g, head, tail, w.buffer.first(len + 2), w.buffer.subspan(len + 2, len + 2));
  out.moving = sum;
  // The removed quadratic c i^2 adds the same q_k (z_k of the window t^2) to every window.
  const Wide c = w.curvature;
  out.quadratic = 0;
  if (c != 0) {
    const std::span<double> G = w.buffer.first(len + 1);  // G[t] = sum over windows of U_n[t]
    G[0] = 0.0;
    for (Index t = 0; t < len; ++t) G[t + 1] = G[t] + (w.s1[windows + t] - w.s1[t]);
    Wide cross = 0, square = 0;
    for_each_run_piece(g, [&](Pos k0, Pos k1, double weight, const Terms& run) {
      for (Pos k = k0; k < k1; ++k) {
        const Terms t = g.at(run, k);
        const Wide q = g.apply(t, k, [](Pos tau) { return Geometry::sum_t2(tau); });
        cross += weight * q * g.apply(t, k, [&](Pos tau) { return static_cast<Wide>(G[static_cast<Index>(tau)]); });
        square += weight * q * q;
      }
    });
    out.quadratic = 2 * c * cross + static_cast<Wide>(windows) * c * c * square;
  }
}

bool window_defined(const Theo1Workspace& w, std::span<double> scratch, std::uint64_t m, std::uint64_t least) {
  return w.ready && m >= least && 3 * m <= w.r.size() && scratch.size() >= mtotvar_scratch_size(w.r.size());
}

// The pieces' sum, in the order of one pass.
Wide window_sum(const MtotPieces& p) { return p.moving - p.fixed + p.quadratic; }

}  // namespace

std::size_t mtotvar_scratch_size(std::size_t n_phase) { return n_phase; }  // the end's prefix sums

void mtotvar_piece(Theo1Workspace& w, std::span<double> scratch, std::uint64_t m, int piece, MtotPieces& out) {
  if (window_defined(w, scratch, m, 1)) window_piece(w, scratch, m, piece, out);
}

TotalVariance mtotvar_from_pieces(const Theo1Workspace& w, std::uint64_t m, double tau0_s, const MtotPieces& p) {
  const std::uint64_t N = w.r.size();
  if (!w.ready || m < 1 || 3 * m > N || !(tau0_s > 0)) return {};
  // The mean over windows of the mean of the 6m squares, / (2 m^2 tau^2).
  const double windows = static_cast<double>(N - 3 * m + 1), md = static_cast<double>(m), tau = md * tau0_s;
  const double var = static_cast<double>(window_sum(p)) / (6.0 * md * windows * 2.0 * md * md * tau * tau);
  return {var, N - 3 * m + 1, 1};
}

TotalVariance htotvar_from_pieces(const Theo1Workspace& w, std::uint64_t m, double tau0_s, const MtotPieces& p) {
  const std::uint64_t N = w.r.size();  // frequencies
  if (!w.ready || m < 2 || 3 * m > N || !(tau0_s > 0)) return {};
  // z sums m frequencies: H = z / (m tau0); the mean over windows of the mean of the 6m squares / 6.
  const double windows = static_cast<double>(N - 3 * m + 1), md = static_cast<double>(m), scale = md * tau0_s;
  const double var = static_cast<double>(window_sum(p)) / (6.0 * md * windows * 6.0 * scale * scale);
  return {var, N - 3 * m + 1, 1};
}

TotalVariance mtotvar_fast(Theo1Workspace& w, std::span<double> scratch, std::uint64_t m, double tau0_s) {
  if (!window_defined(w, scratch, m, 1)) return {};
  MtotPieces p;
  for (int piece = 0; piece < mtotvar_pieces; ++piece) window_piece(w, scratch, m, piece, p);
  return mtotvar_from_pieces(w, m, tau0_s, p);
}

TotalVariance htotvar_fast(Theo1Workspace& w, std::span<double> scratch, std::uint64_t m, double tau0_s) {
  if (!window_defined(w, scratch, m, 2)) return {};
  MtotPieces p;
  for (int piece = 0; piece < mtotvar_pieces; ++piece) window_piece(w, scratch, m, piece, p);
  return htotvar_from_pieces(w, m, tau0_s, p);
}

}  // namespace gyrochar
