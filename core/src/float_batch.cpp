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

#if defined(__x86_64__) && defined(__linux__) && !defined(__clang__)
__attribute__((target_clones("avx2", "default")))
#endif
void steady_terms(const double* x, const double* ph, const double* pl, std::size_t from, std::size_t size,
                  std::size_t m, double out[3]) {
  Lanes sa{0, 0, 0, 0}, st{0, 0, 0, 0}, sh{0, 0, 0, 0};
  const Lanes three{3.0, 3.0, 3.0, 3.0};
  std::size_t e = from;
  for (; e + 4 <= size; e += 4) {
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
  double s[3] = {(sa[0] + sa[1]) + (sa[2] + sa[3]), (st[0] + st[1]) + (st[2] + st[3]), (sh[0] + sh[1]) + (sh[2] + sh[3])};
  for (; e < size; ++e) {
    double a = 0, h = 0, t = 0;
    FloatArith::x_terms(x[e], x[e - m], x[e - 2 * m], x[e - 3 * m], a, h);
    FloatArith::p_term({ph[e], pl[e]}, {ph[e - m], pl[e - m]}, {ph[e - 2 * m], pl[e - 2 * m]},
                       {ph[e - 3 * m], pl[e - 3 * m]}, t);
    s[0] += a * a;
    s[1] += t * t;
    s[2] += h * h;
  }
  for (std::size_t k = 0; k < 3; ++k) out[k] = s[k];
}

// The decimated series x_0, x_m, x_2m, ...: the characterizer's decimate(), point by point.
void decimate(const FloatRecord& r, std::size_t m, TauResult<double>& result, NoiseIdAccumulator& noise) {
  constexpr auto avar_d = static_cast<std::size_t>(SumKind::avar_nonoverlapped);
  constexpr auto hvar_d = static_cast<std::size_t>(SumKind::hvar_nonoverlapped);
  double d[3] = {0, 0, 0};  // the last three decimated points, newest first
  std::size_t have = 0;
  for (std::size_t e = 0; e < r.x.size(); e += m) {
    const double x = r.x[e];
    double a = 0, h = 0;
    if (have >= 2 && FloatArith::x_term2(x, d[0], d[1], a)) {
      result.sum[avar_d] += a * a;
      ++result.n[avar_d];
    }
    if (have >= 3 && FloatArith::x_terms(x, d[0], d[1], d[2], a, h)) {
      result.sum[hvar_d] += h * h;
      ++result.n[hvar_d];
    }
    d[2] = d[1];
    d[1] = d[0];
    d[0] = x;
    if (have < 3) ++have;
    noise.add(x);
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
  decimate(record, lag, result, noise);
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

}  // namespace gyrochar
