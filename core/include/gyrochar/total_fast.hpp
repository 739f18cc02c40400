#pragma once
// Exact Theo1 without the O(N m) double sum (derivation in docs/total.md, "Exact Theo1 in
// O(N log N + m log^2 m)"). The record is prepared once: a least-squares quadratic removed (Theo1's
// terms do not see a line and see a quadratic only as a known constant, added back exactly), the
// prefix sums of the residual and of its square, and the residual's autocorrelation at every lag
// by FFT. Each Theo1(m) is then a sum over k of a few lag sums, corrected at the record's two ends
// by the autocorrelations of its first and last m points and by two triangular sums (pairs of
// points whose midpoint lies in the first, or last, m / 2 points), each by FFT.
//
// Freestanding: no heap; the caller passes one workspace of theo1_workspace_size(N) doubles.
// Rounding: the estimate is a difference of sums of products of residual phase values, so its
// absolute error is a few units of rounding times log2(N) times the sum of the squared residuals
// weighted by the harmonic sum over k; docs/total.md states the bound and where it matters.
#include <cstddef>
#include <cstdint>
#include <span>

#include "gyrochar/total.hpp"

namespace gyrochar {

/// Smallest power of two at or above n (n >= 1). O(log n).
std::size_t fft_length(std::size_t n);

/// In-place complex FFT of `data` (n interleaved re, im pairs, n a power of two up to the table's
/// length): forward exp(-2 pi i k p / n), inverse exp(+2 pi i k p / n) unscaled. O(n log n).
void fft(std::span<double> data, std::size_t n, std::span<const double> twiddle, bool inverse);
/// Doubles of the twiddle table of FFTs up to length P (a power of two): 2 P up to P = 2^16, then
/// 2^17 and about 2 P / 256 more (3.2 MB at P = 2^25). O(log P).
std::size_t fft_twiddle_size(std::size_t P);
/// Fills the twiddle table of FFTs up to length P (fft_twiddle_size(P) doubles): cos, sin of 2 pi k /
/// len for every stage len <= P, k < len / 2, the stages up to 2^16 whole, each larger one as two
/// short lists whose products are its twiddles (total_fast.cpp). O(P / 256 + 2^16).
void fft_twiddles(std::span<double> twiddle, std::size_t P);

/// Doubles of workspace theo1_prepare needs for a record of N phase points: the residual, its two
/// prefix sums, its autocorrelation (4 N + 2), the FFT's twiddles
/// (fft_twiddle_size(P)) and buffer (2 P), P = fft_length(2 N).
std::size_t theo1_workspace_size(std::size_t n_phase);

struct Theo1Workspace {
  std::span<double> r;       // x less its least-squares quadratic
  std::span<double> s1, s2;  // prefix sums of r and r^2 (N + 1 each)
  std::span<double> ac;      // sum_i r[i] r[i+d], d < N
  std::span<double> twiddle, buffer;
  std::size_t P = 0;       // the twiddle table's FFT length
  double curvature = 0.0;  // the removed quadratic's coefficient of i^2
  bool ready = false;      // false: N < 3 or the workspace too small
};

/// Prepares x (N >= 3) in `work` (theo1_workspace_size(N) doubles). O(N log N). The FFT's work goes
/// as rows to `runner` (rows.hpp; null: in turn, here), the same bits either way.
Theo1Workspace theo1_prepare(PhaseSpan x, std::span<double> work, const RowRunner* runner = nullptr);

/// Theo1 at averaging factor m (even, 2 <= m <= N - 1), exactly the estimator theo1(x, m, tau0_s, 1)
/// computes (same n, stride 1), to rounding. O(N + m log^2 m) on a prepared record (the O(N) part is
/// a few passes over the lags below m). Undefined input gives n = 0.
TotalVariance theo1_fast(Theo1Workspace& w, std::uint64_t m, double tau0_s);

/// theo1_fast in pieces that may run on different threads, each on a workspace of its own: a copy
/// of the prepared one with an FFT buffer of the same size (the rest is only read). Piece 0: the
/// lag sums over the whole record with the end autocorrelations; 1 and 2: the triangles of the
/// even and of the odd residuals at the ends (docs/total.md), the dearest two for large m. Each
/// piece writes its own fields; theo1_from_pieces then gives theo1_fast's bits (theo1_fast is the
/// pieces in turn). Undefined m leaves the pieces untouched and gives n = 0.
inline constexpr int theo1_pieces = 3;
struct Theo1Pieces {
  double sums = 0.0;
  double even[2] = {}, odd[2] = {};  // the head's and the tail's triangles
};
void theo1_piece(Theo1Workspace& w, std::uint64_t m, int piece, Theo1Pieces& out);
TotalVariance theo1_from_pieces(const Theo1Workspace& w, std::uint64_t m, double tau0_s, const Theo1Pieces& pieces);

/// The cross-correlation c(e) = sum_p a[p] b[p+e] of two real sequences by FFT of length n (a power
/// of two, at most w.P, n >= a.size() + b.size() for no wrap-around): c(e) for e in (-n, n) left at
/// w.buffer[e mod n]. O(n log n).
void cross_correlation(std::span<const double> a, std::span<const double> b, std::size_t n, Theo1Workspace& w);

/// The sum of the autocorrelations of two real sequences, acf(a)(e) + acf(b)(e), acf(a)(e) = sum_p
/// a[p] a[p+e], by one FFT pair of length n (as cross_correlation): left at w.buffer[e] for
/// 0 <= e < n - max(a.size(), b.size()). O(n log n).
void autocorrelation_sum(std::span<const double> a, std::span<const double> b, std::size_t n, Theo1Workspace& w);

/// For two real sequences a and b of equal length and their first `first` values: acf(a)(e) +
/// acf(b)(e), and c(e) = sum over p < first of a[p] a[p+e] + b[p] b[p+e], both times n, left at
/// w.buffer[2 (e mod n)] and w.buffer[2 (e mod n) + 1] for e in (-n, n) (n a power of two, n >=
/// 2 a.size(), 4 n doubles of buffer). Three FFTs of length n. O(n log n).
void ends_correlations(std::span<const double> a, std::span<const double> b, std::size_t first, std::size_t n,
                       Theo1Workspace& w);

/// Doubles of scratch mtotvar_fast needs beside a prepared Theo1Workspace of N points: N (the end's
/// prefix sums; the workspace's FFT buffer holds the rest).
std::size_t mtotvar_scratch_size(std::size_t n_phase);

/// MTOTVAR at averaging factor m (1 <= m <= N / 3), exactly the estimator mtotvar(x, 1, m, tau0_s, .)
/// computes (same n, stride 1), to rounding, from the record prepared by theo1_prepare: the
/// whole record's autocorrelation weighted per lag, less the windows that stick out of either end
/// (docs/total.md, "MTOTVAR exactly, from lag sums"). O(m log m) a tau on a prepared record.
/// Undefined input (or scratch smaller than mtotvar_scratch_size(N)) gives n = 0.
TotalVariance mtotvar_fast(Theo1Workspace& w, std::span<double> scratch, std::uint64_t m, double tau0_s);

/// mtotvar_fast (and htotvar_fast) in pieces that may run on different threads, each on a workspace
/// and scratch of its own (as theo1_piece): piece 0 the whole record's lag sums weighted, less the
/// windows' moving products past the ends, and the removed quadratic's terms; piece 1 the products
/// at fixed positions past the ends (three FFTs of fft_length(6 m): the dearest near the largest
/// m). Each piece writes its own fields; mtotvar_from_pieces (htotvar_from_pieces on the prepared
/// frequencies) then gives mtotvar_fast's (htotvar_fast's) bits. Undefined m leaves the pieces
/// untouched; from_pieces gives n = 0.
inline constexpr int mtotvar_pieces = 2;
struct MtotPieces {
  long double moving = 0, fixed = 0, quadratic = 0;
};
void mtotvar_piece(Theo1Workspace& w, std::span<double> scratch, std::uint64_t m, int piece, MtotPieces& out);
TotalVariance mtotvar_from_pieces(const Theo1Workspace& w, std::uint64_t m, double tau0_s, const MtotPieces& pieces);
TotalVariance htotvar_from_pieces(const Theo1Workspace& w, std::uint64_t m, double tau0_s, const MtotPieces& pieces);

/// HTOTVAR at averaging factor m (2 <= m <= (N - 1) / 3), exactly the estimator htotvar(x, 1, m,
/// tau0_s, .) computes (same n, stride 1), to rounding: MTOTVAR's kernel on the N - 1 frequencies,
/// so `w` is theo1_prepare of y[k] = x[k+1] - x[k] (the frequencies times tau0), not of x; scratch
/// of mtotvar_scratch_size(N - 1). m = 1 is the overlapping Hadamard variance (htotvar, O(N)), not
/// this kernel: n = 0 here. O(m log m) a tau on a prepared record.
TotalVariance htotvar_fast(Theo1Workspace& w, std::span<double> scratch, std::uint64_t m, double tau0_s);

/// theo_bias_ratio with every Theo1 and AVAR exact, Theo1 by theo1_fast: at most `ratio_taus` of the
/// definition's taus, evenly spread (all when ratio_taus >= n + 1). O(taus (N + m log^2 m)).
TheoBiasRatio theo_bias_ratio_fast(PhaseSpan x, Theo1Workspace& w, double tau0_s, std::uint64_t ratio_taus);

}  // namespace gyrochar
