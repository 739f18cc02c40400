#pragma once
// Power-law noise in discrete time, and the exact second moments of the Allan-family estimators
// under it: the expected variance, the covariance of any two terms, the equivalent degrees of
// freedom (EDF) of an estimate and the covariance of two estimates. One mechanism serves the
// confidence intervals, the noise identification and the IEEE-952 fit. Freestanding, no heap.
//
// Noise. Phase x = (1 - B)^(-d) w, B the backshift operator, w white with unit variance and
// d = (2 - alpha)/2, where alpha is the exponent of the frequency spectrum S_y(f) ~ f^alpha:
//   alpha  +2 white PM (d 0)   +1 flicker PM (1/2)   0 white FM (1)   -1 flicker FM (3/2)
//          -2 random-walk FM (2)   -3 flicker-walk FM (5/2)   -4 random-run FM (3).
// Half-integer d is Kasdin's fractional integration with an infinite past, so every difference of
// order > d - 1/2 is stationary. The generalized autocovariance of x (defined up to a polynomial
// that every estimator's filter annihilates) has a closed form, with psi the digamma function:
//   d = 0:       R(k) = [k = 0]
//   d = j >= 1:  R(k) = (-1)^j |k| prod_{i=1}^{j-1} (k^2 - i^2) / (2 (2j-1)!)
//   d = j + 1/2: R(k) = (-1)^(j+1) prod_{i=1}^{j} (k^2 - (i-1/2)^2) (psi(|k|+j+1/2) + psi(|k|-j+1/2)) / (2 pi (2j)!)
// (the limits of Hosking's Gamma(1-2d) Gamma(k+d) / (Gamma(d) Gamma(1-d) Gamma(k+1-d)) at integer
// and half-integer d). The prefix sums P of x are the same kind of noise with d + 1.
//
// Terms. Each statistic averages squared terms, each a fixed filter of the phase (newest point e):
//   AVAR  x[e] - 2 x[e-m] + x[e-2m]                       (on x)
//   HVAR  x[e] - 3 x[e-m] + 3 x[e-2m] - x[e-3m]           (on x)
//   MVAR  P[e+1] - 3 P[e+1-m] + 3 P[e+1-2m] - P[e+1-3m]   (on P; an x filter is moved onto P
//                                                          by x[k] = P[k+1] - P[k] to pair with it)
// so the covariance of two terms, sum_{a,b} f_a g_b R(lag + o_a - o_b), is exact and O(1).
//
// Estimates. An estimate sums the squares of n terms whose newest points are first, first +
// stride, ... (stride 1: fully overlapped; m/S: the pyramid's strided taus; m: non-overlapped).
// For Gaussian terms with covariances c, E[sum t_i^2] = sum c_ii and
// Cov[sum t_i^2, sum u_j^2] = 2 sum_{i,j} c(e_i - e_j)^2, so EDF = (n c(0))^2 / sum_{i,j} c(e_i - e_j)^2.
// The double sums are sums over lags weighted by the number of pairs at each lag: exact where the
// lags within the terms' reach are few (at most a few thousand), and otherwise a trapezoid rule on
// nodes graded towards the lags where c is not smooth (dense there), accurate to about 1e-4
// (tests/core/test_noise_model.cpp checks it against the exact sums).
//
// Every function is deterministic, allocates nothing, reads no clock and never fails hard.
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "gyrochar/stat.hpp"

namespace gyrochar {

/// True when statistic s converges for noise alpha (alpha + 2 D > 1, alpha in -4..+2).
constexpr bool noise_supported(Stat s, int alpha) {
  return alpha <= 2 && alpha >= -4 && alpha + 2 * difference_order(s) > 1;
}

/// Generalized autocovariance R(k) of (1 - B)^(-twice_d / 2) w, twice_d in 0..8. O(1).
double generalized_autocovariance(int twice_d, std::int64_t k);

/// Cov[term of (a, m_a) with newest point e, term of (b, m_b) with newest point e - lag] for
/// noise alpha with unit innovation variance, in squared phase units (the MVAR term is a SUM of m
/// second differences). 0 when either statistic does not converge for alpha. O(1).
double term_covariance(int alpha, Stat a, std::uint64_t m_a, Stat b, std::uint64_t m_b, std::int64_t lag);

/// First-order Gauss-Markov rate noise, sampled: the rate samples y_k (each the mean rate over one
/// tau0) form an AR(1) sequence of unit stationary variance and lag-1 correlation phi = e^(-a),
/// a = tau0 / Tc, and the phase is their running sum (one tau0 a sample: multiply by tau0^2 and the
/// rate's variance sigma^2). Cov[term (a_stat, m_a) newest e, term (b_stat, m_b) newest e - lag],
/// as term_covariance(). Exact: the generalized autocovariances of the phase and of its prefix
/// sums are, up to polynomials the terms annihilate (s = a|k|, h = sinh(a/2)),
///   level 0 (x): -[e^-s - 1 + s + (sinh a - a)|k|] / (4 h^2)
///   level 1 (P): [e^-s - 1 + s - s^2/2 + s^3/6 + d1 |k| + d3 |k|^3] / (16 h^4),
///                d1 = sinh a (1 - 2h^2/3) - a = -a^5/30 - ..., d3 = 2 sinh(a) h^2 / 3 - a^3/6 = a^5/24 + ...
/// written so that nothing cancels catastrophically when Tc >> tau0 (exponential remainders by
/// their series, d1 and d3 by theirs). O(1). a > 0.
double markov_term_covariance(double a, Stat a_stat, std::uint64_t m_a, Stat b_stat, std::uint64_t m_b, std::int64_t lag);

/// The terms of one estimate: newest points first, first + stride, ..., first + (n - 1) stride.
struct TermGrid {
  Stat stat = Stat::avar;
  std::uint64_t m = 1;       // averaging factor
  std::uint64_t stride = 1;  // a power of two (1: fully overlapped)
  std::uint64_t first = 0;   // newest point of the first term
  std::uint64_t n = 0;       // number of terms
};

/// The terms an unbroken run of n_phase points forms for (stat, m) with terms every `stride`
/// points on the global grid (newest point a multiple of stride). n = 0 when none fits. O(1).
TermGrid unbroken_grid(Stat stat, std::uint64_t m, std::uint64_t stride, std::uint64_t n_phase);

/// Up to five power-law noises whose sums pair_sums() forms at once (a noise mixture).
inline constexpr std::size_t max_noises = 5;
struct NoiseSet {
  std::array<int, max_noises> alpha{};
  std::size_t count = 0;
};

/// Over all pairs of terms (i of grid a, j of grid b) with lag e_i - e_j, for the noises of `set`:
///   cc[t][u] = sum c_t c_u    (c_t the term covariance of noise t, unit innovations)
///   c[t]     = sum c_t
/// cc is symmetric. O(nodes x taps x noises) with at most a few thousand nodes.
struct PairSums {
  std::array<std::array<double, max_noises>, max_noises> cc{};
  std::array<double, max_noises> c{};
};
PairSums pair_sums(const NoiseSet& set, const TermGrid& a, const TermGrid& b);

/// pair_sums(set, a1, b1) and pair_sums(set, a2, b2), the same to the last bit, in one pass where
/// the two pairs have the same kernel (the same statistics, m and strides; say the same grids at
/// two lengths of the run): the covariances at the lags both sums visit are evaluated once.
void pair_sums_of_two(const NoiseSet& set, const TermGrid& a1, const TermGrid& b1, const TermGrid& a2, const TermGrid& b2,
                      PairSums& out1, PairSums& out2);

/// The same sums with first-order Gauss-Markov rates beside the noises of `set` (the IEEE-952
/// fit's exact covariance of a model with Markov terms): c_j the term covariance of Markov rate j
/// (markov_term_covariance() with a = rates[j], unit stationary variance),
///   cm[j][t] = sum c_j c_t,   mm[j][l] = sum c_j c_l,   c[j] = sum c_j.
/// Beyond the kernel's span c_j is exactly c_j(edge) e^(-a |lag - edge|) and is summed to e^-27 of
/// that; inside, the nodes of pair_sums(). Flicker noises beyond three kernel widths take the
/// power law pair_sums() integrates there. O(nodes x (taps + noises)); empty on a rate <= 0.
inline constexpr std::size_t max_markov_rates = 2;
struct MarkovPairSums {
  std::array<std::array<double, max_noises>, max_markov_rates> cm{};
  std::array<std::array<double, max_markov_rates>, max_markov_rates> mm{};
  std::array<double, max_markov_rates> c{};
};
MarkovPairSums markov_pair_sums(const NoiseSet& set, std::span<const double> rates, const TermGrid& a, const TermGrid& b);

/// A sinusoidal rate sin(theta k + phi) (theta = 2 pi f tau0 in (0, pi], the phase phi uniform
/// over the turn), in the units of markov_term_covariance() (multiply by A^2 tau0^2): its phase
/// -cos(theta k + phi) / theta has the autocovariance cos(theta k) / (2 theta^2) over phi, its prefix
/// sums that over 4 sin^2(theta / 2). Cov[term (a_stat, m_a) newest e, term (b_stat, m_b) newest
/// e - lag] over phi: Re(e^(i theta lag) F_a conj(F_b)) times that, F the terms' filters' responses
/// at theta. O(1). 0 for theta outside (0, pi].
double sinusoid_term_covariance(double theta, Stat a_stat, std::uint64_t m_a, Stat b_stat, std::uint64_t m_b,
                                std::int64_t lag);

/// The cross sums of sinusoids with the noises of `set`: cs[j][t] = sum c_j c_t over all pairs of
/// terms of grids a and b, c_j the term covariance of sinusoid j (sinusoid_term_covariance() with
/// theta = thetas[j]), c_t that of noise t. A sinusoid with a random phase adds 4 A^2 tau0^2 h_t
/// cs[j][t] to the covariance of two estimates' sums of squares (h_t noise t's innovation
/// variance); its own part is of order 1/n^2 (deterministic given phi) and is not summed. Summed
/// where c_t is not zero (the kernel's span; flicker noises directly to three kernel widths, then
/// their power-law tail as markov_pair_sums() takes it, four periods of the slowest sinusoid
/// further, where the oscillating c_j has cancelled the rest) on nodes no further apart than a
/// tenth of a period.
/// Zero where theta m / 2 > 64 for either grid: the sinusoid's variance there is below A^2 / 4096.
/// O(nodes x (taps + noises)).
inline constexpr std::size_t max_sinusoid_rates = 2;
struct SinusoidPairSums {
  std::array<std::array<double, max_noises>, max_sinusoid_rates> cs{};
};
SinusoidPairSums sinusoid_pair_sums(const NoiseSet& set, std::span<const double> thetas, const TermGrid& a,
                                    const TermGrid& b);

/// How far the correlation of the estimates over grids a and b under noise alpha, as pair_sums()
/// computes it in double precision, can be off through rounding (a bound, typically far above the
/// actual error). The closed forms of c are sums of R at arguments as wide as the kernel, nearly
/// cancelling where one term is much shorter than the other: R grows as |k|^(2d - 1) (to |k|^5
/// for random-walk FM paired with a modified Allan term), so a modified Allan estimate ten octaves
/// below an Allan one has no correct digit left under random-walk and flicker FM. 0 when the
/// statistic does not converge for alpha. O(1).
double pair_sums_rounding(int alpha, const TermGrid& a, const TermGrid& b);

/// EDF of the estimate over `grid` for pure noise alpha: (n c(0))^2 / sum_{i,j} c(e_i - e_j)^2.
/// 0 when the statistic does not converge for alpha or the grid has no term. See pair_sums().
double exact_edf(int alpha, const TermGrid& grid);

/// The shape of the estimate's distribution beyond its EDF: with kappa_2 = 2 tr C^2 and kappa_3 =
/// 8 tr C^3 the second and third cumulants of sum t_i^2 (C the covariance of its n terms), the
/// "skew degrees of freedom" nu3 = 8 kappa_2^3 / kappa_3^2. The estimate is then distributed about
/// as mean x (a + b chi2_nu3), b = 1 / sqrt(EDF nu3), a = 1 - b nu3 (mean, variance and skewness
/// matched); nu3 = EDF is the plain chi-squared. Where the EDF is small (the last octaves) the
/// plain chi-squared interval holds the truth 72-75 % of the time instead of 68.3 %, this one
/// 66-69 % (docs/metrology.md). tr C^3 = sum_{u,v} c(u) c(v) c(u+v) (n - range(0, u, u+v))+ over
/// lattice lags, exact for up to 256 lags each way and a Riemann sum on every q-th lag beyond (c is
/// smooth on the scale of m there; unmodified white PM, whose c lives on three lags, is summed
/// exactly at any m). 0 when there is no EDF. O(min(lags, 256)^2).
double exact_skew_dof(int alpha, const TermGrid& grid);

/// The five noises of the Allan and modified Allan statistics, alpha = 2, 1, 0, -1, -2 (index
/// 2 - alpha), whose sums PairSumCache keeps.
NoiseSet allan_noises();

/// Remembers pair_sums(allan_noises(), a, b) for readers that run again and again on a growing
/// run (the board, every report), in caller-owned storage. For a pair of grids long enough that
/// every lag within the terms' reach has pairs at both ends, the sums are a linear function of the
/// coarser grid's number of terms (exactly, for a grid with itself; to within one term for two
/// grids): the cache keeps that function, computed once, and evaluates it in O(1). For shorter
/// grids it keeps the last sums with the term counts they were computed for, and scales them with
/// the coarser grid's terms until either grid has grown by 2 % (10 % for grids of different taus,
/// whose covariance only weights the IEEE-952 fit). A full table is not an error: the sums are
/// then computed afresh. No allocation; Allan and modified Allan only.
/// Where a PairSumSource is attached, get() asks it first: sums it gives are neither kept nor computed.
class PairSumSource {
 public:
  /// True, with the sums in `out`, when this source has pair_sums(allan_noises(), a, b) (or an
  /// approximation its owner vouches for).
  virtual bool find(const TermGrid& a, const TermGrid& b, PairSums& out) const = 0;
  /// True, with the sums in `out`, when this source has sinusoid_pair_sums(set, thetas, a, b) to the
  /// last bit. None by default.
  virtual bool find_sinusoids(const NoiseSet&, std::span<const double>, const TermGrid&, const TermGrid&,
                              SinusoidPairSums&) const {
    return false;
  }

 protected:
  ~PairSumSource() = default;
};

class PairSumCache {
 public:
  struct Entry {
    bool used = false;
    bool linear = false;
    Stat stat_a = Stat::avar, stat_b = Stat::avar;
    std::uint64_t m_a = 0, m_b = 0, stride_a = 0, stride_b = 0;
    std::uint64_t from = 0;          // linear: valid from this many coarse terms
    std::uint64_t n_a = 0, n_b = 0;  // not linear: the term counts of `sums`
    PairSums slope, sums;            // linear: sums = slope * n + sums (the intercept)
  };
  explicit PairSumCache(std::span<Entry> storage) : entries_(storage) {}
  /// pair_sums(allan_noises(), a, b), from the cache where it can. O(1) once cached.
  PairSums get(const TermGrid& a, const TermGrid& b);
  /// sinusoid_pair_sums(set, thetas, a, b), the same to the last bit: from the attached source where
  /// it has them (the analyzer makes every pair's once for its three fits), else computed; not kept.
  SinusoidPairSums sinusoid_sums(const NoiseSet& set, std::span<const double> thetas, const TermGrid& a, const TermGrid& b);
  /// Asks `source` first from now on (null: none); it must outlive its use here.
  void attach(const PairSumSource* source) { source_ = source; }
  /// Forgets everything (a new configuration). O(capacity).
  void clear();

 private:
  Entry* slot(const TermGrid& a, const TermGrid& b);  // null: not kept
  std::span<Entry> entries_;
  const PairSumSource* source_ = nullptr;
};

}  // namespace gyrochar
