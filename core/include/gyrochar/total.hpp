#pragma once
// The total and Theo family (NIST SP 1065 sections 5.2.11 to 5.2.16): variances that reflect the
// record at its ends (TOTVAR, MTOTVAR, TTOTVAR, HTOTVAR) or reach tau = 0.75 of it (Theo1, TheoBR,
// TheoH), with more degrees of freedom at long tau than the Allan family. They need the whole
// record, so they are offline: the caller holds the phase record (and any scratch) and these
// functions read it. Freestanding: no heap, no exceptions, no clock.
//
// Phase x[0..N) in any unit ("phase unit": s for clocks, pulses or degrees for a gyro), sample
// interval tau0_s, tau = m tau0_s. Every variance comes out in (phase unit / s)^2 (TTOTVAR: phase
// unit^2), like the Allan family's; its n is the number of terms Stable32 prints ("#").
//
// Definitions (0-based; SP 1065 eq. 25, 27, 29, 30):
//   TOTVAR   sum_{i=1}^{N-2} (x*[i-m] - 2 x[i] + x*[i+m])^2 / (2 tau^2 (N-2)), x* the record reflected
//            oddly about both end points (x*[-j] = 2 x[0] - x[j], x*[N-1+j] = 2 x[N-1] - x[N-1-j]).
//            n = N - 2.
//   MTOTVAR  for each of the N - 3m + 1 sub-sequences of 3m phase points: remove the line through
//            the means of its two halves (halves of floor(3m/2) points; the distance of their
//            centres is the slope's run), extend it to 9m points by even (mirror) reflection at both
//            ends, and average the 6m squared modified-Allan terms z_k over the extension,
//            z_k = sum_{j=k}^{k+m-1} (e[j+2m] - 2 e[j+m] + e[j]); MTOTVAR = mean over the
//            sub-sequences / (2 m^2 tau^2). n = N - 3m + 1.
//   TTOTVAR  tau^2 MTOTVAR / 3 (phase unit^2).
//   HTOTVAR  the same on the N - 1 frequencies y[k] = (x[k+1] - x[k]) / tau0 with sub-sequences of
//            3m of them, Hadamard terms (third differences of m-averages): mean / (6 m^2). At m = 1
//            Stable32 (and this) gives the overlapping Hadamard variance instead. n = N - 3m.
//   Theo1    sum_{i=0}^{N-m-1} sum_{k=1}^{m/2} (x[i] - x[i+k] - x[i+m-k] + x[i+m])^2 / k
//            / (0.75 (N - m) (m tau0)^2), m even, 10 <= m <= N - 1, at tau = 0.75 m tau0
//            (Stable32 lists m as its averaging factor). n = (N - m) m / 2 as Stable32 prints it.
//   TheoBR   Theo1 times the bias ratio (1 / (n+1)) sum_{i=0}^{n} AVAR(9 + 3i) / Theo1(12 + 4i)
//            (the two at the same tau, 9 + 3i = 0.75 (12 + 4i)), n = floor(N / 6 - 3) as Stable32
//            computes it (SP 1065 prints floor(0.1 N / 3 - 3)); a pair whose AVAR needs more than N
//            points (N a multiple of 6, last i) is left out.
//   TheoH    AVAR below tau = k, TheoBR from 0.75 m tau0 >= k on, k the largest octave tau0 2^j at
//            or below 10 % of the record.
//
// Cost. TOTVAR is O(N) per tau. The exact MTOTVAR/HTOTVAR cost O(m) per sub-sequence, O(N m) per
// tau, and Theo1 O(N m / 2): fine up to 10^5 points and moderate m, hopeless at 10^7 and m = 10^6
// (total_fast.hpp computes the same Theo1 from lag sums: O(N log N) once, about O(m log^2 m) a tau).
// So each has a decimated variant with a stride factor S (a different estimator of the same
// quantity, documented in docs/total.md with its error against the exact one):
//   - MTOTVAR/HTOTVAR on blocks of b = m / S samples (b a power of two dividing m): the record as
//     block sums (MTOTVAR) or every b-th phase point (HTOTVAR), sub-sequences starting on block
//     boundaries and terms z_k at block boundaries: O(N S / b) = O(N S^2 / m) per tau. Blocks of 1
//     are the exact estimator.
//   - Theo1 (and the AVAR of TheoBR) with sub-sequences i every d = m / S samples, each one's inner
//     sum exact: O(N S / 2) per tau, unbiased, the EDF slightly lower. d = 1 is the exact estimator.
//   - TheoBR's ratio over at most `ratio_taus` of its n + 1 taus, evenly spread.
#include <cstddef>
#include <cstdint>
#include <span>
#include <type_traits>

#include "gyrochar/rows.hpp"

namespace gyrochar {

template <class R, class T>
concept SpanOf = std::is_convertible_v<const R&, std::span<const T>>;

/// The phase record as every function here reads it: doubles, or integers (a counter's phase in
/// pulses, 4 or 8 bytes a point). Each statistic here is blind to a line in the phase (a constant
/// frequency), so a counter's residuals from any line give the same variances as its phase, to
/// rounding (fewer roundings: the residuals are smaller). Integers convert to double exactly up to
/// 2^53. A view: it holds no values.
class PhaseSpan {
 public:
  PhaseSpan() = default;
  /// Any contiguous range of doubles, int32 or int64 values (a std::span, a std::vector).
  template <class R>
  requires SpanOf<R, double> PhaseSpan(const R& r) : PhaseSpan(std::span<const double>(r), Kind::f64) {}
  template <class R>
  requires SpanOf<R, std::int32_t> PhaseSpan(const R& r) : PhaseSpan(std::span<const std::int32_t>(r), Kind::i32) {}
  template <class R>
  requires SpanOf<R, std::int64_t> PhaseSpan(const R& r) : PhaseSpan(std::span<const std::int64_t>(r), Kind::i64) {}

  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  bool integers() const { return kind_ != Kind::f64; }
  /// f(std::span<const T>) on the values as they are held; returns what f returns.
  template <class F>
  decltype(auto) visit(F&& f) const {
    switch (kind_) {
      case Kind::i32: return f(std::span<const std::int32_t>(static_cast<const std::int32_t*>(data_), size_));
      case Kind::i64: return f(std::span<const std::int64_t>(static_cast<const std::int64_t*>(data_), size_));
      default: return f(std::span<const double>(static_cast<const double*>(data_), size_));
    }
  }

 private:
  enum class Kind { f64, i32, i64 };
  template <class T>
  PhaseSpan(std::span<const T> s, Kind kind) : data_(s.data()), size_(s.size()), kind_(kind) {}
  const void* data_ = nullptr;
  std::size_t size_ = 0;
  Kind kind_ = Kind::f64;
};

struct TotalVariance {
  double var = 0.0;          // variance (units above)
  std::uint64_t n = 0;       // terms as Stable32 counts them (decimated: sub-sequences or terms used); 0: undefined
  std::uint64_t stride = 1;  // 1: the exact estimator; > 1: the decimated one (block or sub-sequence stride, samples)
};

/// TOTVAR of phase x at averaging factor m (1 <= m <= N - 1, N >= 3). O(N), reads x only.
/// Undefined input (N < 3, m out of range, tau0_s <= 0) gives n = 0.
TotalVariance totvar(PhaseSpan x, std::uint64_t m, double tau0_s);

/// TOTVAR as totvar() with the terms that need no reflection given: those of m <= i <= N - 1 - m,
/// (x_{i-m} - 2 x_i + x_{i+m})^2, are the overlapping AVAR's N - 2m terms at the same m, and
/// `interior` is their sum (an Allan engine's, exact for counts: docs/total.md). Only the 2 (m - 1)
/// reflected terms are summed here: O(m), reads x only. Needs 1 <= m and 2m <= N - 1 (else, or
/// with a negative or NaN sum, n = 0).
TotalVariance totvar_from_interior(PhaseSpan x, std::uint64_t m, double tau0_s, double interior);

/// The block sums MTOTVAR's decimated variant holds at a time: those of this many sub-sequence
/// starts (and the 3 m / block - 1 more the last one reaches), not the whole record's.
inline constexpr std::size_t total_window = 65536;

/// Scratch (doubles) MTOTVAR and HTOTVAR need for averaging factor m on blocks of `block` samples:
/// 9 m / block + 1, and for MTOTVAR on blocks of more than one sample a window of block sums,
/// total_window + 3 m / block.
constexpr std::size_t total_scratch_size(std::uint64_t m, std::uint64_t block) {
  const std::uint64_t S = m / block;
  return static_cast<std::size_t>(9 * S + 1 + (block > 1 ? total_window + 3 * S : 0));
}

/// MTOTVAR at averaging factor m of phase x, on the sums of x over consecutive blocks of `block`
/// samples (block = 1: x itself, the exact estimator; block must divide m and m / block be even
/// when block > 1), summed a window at a time into the scratch: the record is never copied. Needs
/// floor(N / block) >= 3 m / block; scratch of total_scratch_size(). O((N / block) (m / block) + N),
/// no allocation. Undefined input gives n = 0.
TotalVariance mtotvar(PhaseSpan x, std::uint64_t block, std::uint64_t m, double tau0_s, std::span<double> scratch);

/// HTOTVAR at averaging factor m of phase x, on the phase points every `block` samples (block = 1:
/// exact; block must divide m and m / block be even when block > 1). m = 1 gives the overlapping
/// Hadamard variance, as Stable32. Needs N - 1 >= 3 m; scratch of total_scratch_size().
/// O((N / block) (m / block)), no allocation. Undefined input gives n = 0.
TotalVariance htotvar(PhaseSpan x, std::uint64_t block, std::uint64_t m, double tau0_s, std::span<double> scratch);

/// Theo1 at averaging factor m (even, 10 <= m <= N - 1; smaller even m >= 2 are computed too) at
/// tau = 0.75 m tau0_s, with sub-sequences every `stride` samples (1: exact). O((N - m) m / (2
/// stride)), reads x only. Undefined input gives n = 0.
TotalVariance theo1(PhaseSpan x, std::uint64_t m, double tau0_s, std::uint64_t stride = 1);

/// Overlapping AVAR (SP 1065 eq. 11) with terms every `stride` samples (1: every one, the fully
/// overlapped estimator). O((N - 2m) / stride). Undefined input gives n = 0.
TotalVariance oavar(PhaseSpan x, std::uint64_t m, double tau0_s, std::uint64_t stride = 1);

struct TheoBiasRatio {
  double ratio = 0.0;         // (1 / taus) sum AVAR(9 + 3i) / Theo1(12 + 4i); 0: undefined
  std::uint64_t taus = 0;     // taus averaged
  std::uint64_t defined = 0;  // taus of the definition (n + 1, less the one N may leave out)
  bool exact = true;          // every tau of the definition, each estimate exact
};

/// TheoBR's bias ratio of phase x (N >= 24, so that n >= 1). With stride_factor S = 0 every
/// estimate is exact; otherwise Theo1 at m and AVAR at 0.75 m use the sub-sequence strides m / S
/// and 0.75 m / S (1 below S): the ratio averages many taus, each need not be exact. At most
/// `ratio_taus` (>= 2) of the n + 1 taus, evenly spread (all when
/// ratio_taus >= n + 1). The taus' estimates are rows for `runner` (rows.hpp; null: in turn, here),
/// summed in the same order either way: the same bits. O(taus N S) when decimated, O(N^3) exact; no
/// allocation.
TheoBiasRatio theo_bias_ratio(PhaseSpan x, double tau0_s, std::uint32_t stride_factor, std::uint64_t ratio_taus,
                              const RowRunner* runner = nullptr);

/// The last index i of TheoBR's definition for N >= 24 phase points: floor(N / 6 - 3), less one when
/// AVAR(9 + 3 i) would need N + 1 points. O(1).
std::uint64_t theo_bias_last(std::uint64_t n_phase);
/// The j-th of `count` indices spread evenly over 0..last (first and last included; j itself when
/// count = last + 1). O(1).
std::uint64_t theo_bias_index(std::uint64_t j, std::uint64_t count, std::uint64_t last);

/// TheoH's switch point k in samples: the largest power of two at or below (N - 1) / 10 (at least 1).
/// AVAR rows below it (m < k), TheoBR rows at 0.75 m >= k.
std::uint64_t theoh_switch(std::uint64_t n_phase);

// The estimator the offline analysis runs: the exact one where it costs at most
// total_exact_budget operations (about a tenth of a second), the decimated one with stride
// factor S otherwise (S = 0: always exact).
inline constexpr double total_exact_budget = 67108864.0;  // 2^26

/// Operations of the exact MTOTVAR/HTOTVAR (15 m per sub-sequence) or Theo1 ((N - m) m / 2) at m.
double total_exact_cost(bool theo, std::uint64_t m, std::uint64_t n_phase);

/// Block (MTOTVAR, HTOTVAR) at averaging factor m: 1 (exact) when the exact cost fits the budget,
/// m <= S or S = 0; otherwise the largest power of two b <= m / S that divides m with m / b even
/// (1 when there is none: an odd m is always exact). O(log m).
std::uint64_t total_block(std::uint64_t m, std::uint64_t n_phase, std::uint32_t S);
/// Sub-sequence stride of Theo1 (and of TheoBR's estimates) at m: 1 where exact as above,
/// otherwise m / S. O(1).
std::uint64_t theo1_stride(std::uint64_t m, std::uint64_t n_phase, std::uint32_t S);

/// How many of TheoBR's n + 1 taus the analysis averages: all when S = 0 or when exact Theo1 at
/// every one fits total_exact_budget, otherwise 64. 0 when N < 24. O(N).
std::uint64_t theo_bias_taus(std::uint64_t n_phase, std::uint32_t S);

/// Stable32's bias corrections: the expected ratio of a total variance to the Allan-family variance
/// it stands for, which Stable32 divides out where alpha is known (1 where no correction applies).
/// TOTVAR: 1 - a m / (N - 1) (Howe, "Total variance explained", 1999: a = 1/(3 ln 2) flicker FM,
/// 0.75 random-walk FM, 0 otherwise). HTOTVAR at m >= 2: 1 + a (Howe et al., PTTI 2000: a = -0.005
/// white FM, -0.149 flicker FM, -0.229 random-walk FM, -0.283 flicker walk FM, -0.321 random run FM).
/// MTOTVAR has none in Stable32.
double totvar_bias(int alpha, double n_phase, double m);
double htotvar_bias(int alpha, std::uint64_t m);

// EDF (NIST SP 1065 section 5.2 and tables 7 to 11; alpha the power-law exponent of S_y).
// Each returns 0 ("not available") where the formula has no row for alpha.

/// TOTVAR: b N / m - c (SP 1065 table 7: white FM 1.50, 0; flicker FM 1.17, 0.22; random-walk FM
/// 0.93, 0.36), alpha in {0, -1, -2}.
double edf_totvar(int alpha, double n_phase, double m);
/// MTOTVAR and TTOTVAR: b N / m - c (SP 1065 table 8: white PM 1.90, 2.1; flicker PM 1.20, 1.40;
/// white FM 1.10, 1.2; flicker FM 0.85, 0.50; random-walk FM 0.75, 0.31), alpha in {2 .. -2}.
double edf_mtotvar(int alpha, double n_phase, double m);
/// HTOTVAR (m >= 16; below, the overlapping Hadamard EDF): (N / m) / (b0 + b1 m / N) (SP 1065 table
/// 9: white FM 0.559, 1.004; flicker FM 0.868, 1.140; random-walk FM 0.938, 1.696), alpha in
/// {0, -1, -2}.
double edf_htotvar(int alpha, double n_phase, double m);
/// Theo1 and TheoBR at averaging factor m (SP 1065 table 11, with r = 0.75 m), alpha in {2 .. -2}.
double edf_theo1(int alpha, double n_phase, double m);

}  // namespace gyrochar
