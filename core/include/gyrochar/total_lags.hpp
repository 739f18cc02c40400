#pragma once
// Exact MTOTVAR and HTOTVAR at short averaging factors of records too long for the lag sums'
// workspace (total_fast.hpp needs about 2 fft_length(2 N) doubles: 17 GB at 4.3 10^8 points): one
// pass over the record, then O(m^3) a tau, in a few megabytes (docs/total.md, "Short taus of long
// records, from the differences' lag sums").
//
// A window's term z_k is linear in the window's 3m values and blind to a line (the window's own
// detrending removes it), so it is a fixed combination of the window's second differences:
// z_k(n) = sum_v c_k[v] w[n + v], v < 3m - 2, w[j] = x[j+2] - 2 x[j+1] + x[j] (HTOTVAR runs
// MTOTVAR's kernel on the frequencies: there w is the phase's third differences). The sum over the
// windows of z_k^2 is then sum over v, v' of c_k[v] c_k[v'] times the products w[j] w[j + v' - v]
// summed over the j the windows reach: the whole record's sum at that lag, less its first v
// products and its last 3m - 3 - v' ones. One pass makes those sums at every lag below L, for every
// m with 3m - 2 <= L at once.
//
// The record must be integers (counts: PhaseSpan's int32 or int64 kinds): the differences are then
// integers, so is every sum of the table, and the pass keeps them exact (it adds 8192 products in
// double, which holds them while 8192 |w|^2 < 2^53, then adds those sums as two doubles). Each term
// is a combination of the differences whose coefficients c_k[v] are multiples of 1 / D, D = h (3m
// - h), h = floor(3m / 2) (the half means' slope), so D c_k[v] are integers too, and the estimate is
// the sum of their products with the table's: formed in double-double (about 106 bits), rounded
// once. That matters: the coefficients grow like m^2 while the terms do not, so the sum cancels by
// a factor that grows like m^5 (HTOTVAR: about 10^8 at m = 32). In double (or in long double, on phase
// given as doubles) that cost up to 8 digits; in double-double on exact sums, the estimate keeps
// about 15 of them. Phase given as doubles takes total_fast.hpp or the direct estimators instead.
//
// Freestanding: no heap; the caller passes the workspaces.
#include <cstddef>
#include <cstdint>
#include <span>

#include "gyrochar/rows.hpp"
#include "gyrochar/total.hpp"

namespace gyrochar {

/// The largest averaging factor the lag tables serve: 3 m - 2 lags, O(N (3 m - 2)) for the pass.
inline constexpr std::uint64_t lag_table_max_m = 128;

/// An integer held exactly as two doubles, hi + lo (|lo| at most half a unit of hi's last place):
/// every integer below 2^106.
struct ExactSum {
  double hi = 0, lo = 0;
};

/// The products of the differences w (of order 2 or 3) of a record at every lag d < lags: over the
/// whole record, and its first and last c of each lag (c < lags).
struct LagTable {
  std::size_t lags = 0;
  std::size_t values = 0;           // the differences, N - order
  int order = 0;                    // of the differences: 2 or 3
  std::span<const ExactSum> total;  // total[d] = sum_j w[j] w[j + d]
  std::span<const ExactSum> head;   // head[d lags + c]: the first c products of lag d
  std::span<const ExactSum> tail;   // tail[d lags + c]: the last c
  // false: doubles, too few values, too many lags, too small a workspace, or differences too large
  // for exact sums (8192 |w|^2 >= 2^53)
  bool ready = false;
};

/// ExactSums of workspace lag_table needs: the three tables, and the sums of 16 stripes.
std::size_t lag_table_size(std::size_t lags);

/// The lag products of the differences of order `order` (2: MTOTVAR's, 3: HTOTVAR's) of the integer
/// record x, at every lag below `lags` (at most 3 lag_table_max_m - 2), in `work`
/// (lag_table_size(lags)), exactly. The record goes in 16 stripes, run as rows on `runner` (null: in
/// turn): exact sums, the same on any number of threads. O(N lags), 190 KB of stack a row.
/// With `group` > 1 the table is that of the record's sums over consecutive groups of `group`
/// samples (floor(N / group) of them, formed as they are read, never held): MTOTVAR at m of those
/// sums is the decimated mtotvar(x, group, m group) times group^4 (docs/total.md). O(N + (N /
/// group) lags).
LagTable lag_table(PhaseSpan x, int order, std::size_t lags, std::span<ExactSum> work, const RowRunner* runner = nullptr,
                   std::uint64_t group = 1);

/// Doubles of scratch mtotvar_lagged and htotvar_lagged need at averaging factor m.
std::size_t lagged_scratch_size(std::uint64_t m);

/// MTOTVAR at averaging factor m from the lag table of the phase's second differences (order 2,
/// 3 m - 2 <= lags): exactly the estimator mtotvar(x, 1, m, tau0_s, .) computes (same n, stride 1),
/// rounded once. O(m^3). Undefined input gives n = 0.
TotalVariance mtotvar_lagged(const LagTable& t, std::uint64_t m, double tau0_s, std::span<double> scratch);

/// HTOTVAR at averaging factor m >= 2 from the lag table of the phase's third differences (order
/// 3): exactly htotvar(x, 1, m, tau0_s, .), rounded once. O(m^3). Undefined input (or m = 1, the
/// overlapping Hadamard variance) gives n = 0.
TotalVariance htotvar_lagged(const LagTable& t, std::uint64_t m, double tau0_s, std::span<double> scratch);

}  // namespace gyrochar
