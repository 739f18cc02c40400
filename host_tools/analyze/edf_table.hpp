#pragma once
// The exact EDF of a dense tau list (--taus all: every m) at the cost of a few hundred taus.
//
// The exact EDF of a fully overlapped estimate and its skew degrees of freedom (noise_model.hpp)
// depend on the geometry only: the statistic, the noise alpha, m and the run's n_phase points.
// Each costs up to a few thousand covariance evaluations, so every m of a long run (N/2 taus)
// would cost O(N) of them. Both change smoothly with m: this table computes them exactly at
// anchor taus (dense_anchors(): neither m nor the number of terms changes by more than 2^(1/16)
// from one anchor to the next, so every m near the end of the curve, where the terms run out,
// and both sides of each kink, where the terms cross a multiple of m) and interpolates log EDF
// linearly in log m between anchors. At an anchor the value is the exact one; between anchors it
// is within 2e-3 of it (measured: 1.0e-3 at worst, tests/host/test_edf_table.cpp, at every m),
// a small fraction of the interval's own width at any EDF. The skewness (noise_model.hpp's
// exact_skew_dof(), itself a Riemann sum at long lags that is not smooth in m) is interpolated the
// same way: the interval's bounds stay within 5e-3 of those from the exact values (measured:
// 4.2e-3), where the deviation's own standard error is 7 % or more (EDF below 100).
//
// For stride-1 taus of the overlapping statistics (oadev, mdev, tdev, ohdev); the analyzer uses
// it from m = 64 on where the list holds at least every other m (analysis.cpp). Allocates its anchors (O(log N) of them, and
// every m of the last few dozen); may throw std::bad_alloc.
#include <cstdint>
#include <span>
#include <vector>

#include "gyrochar/estimates.hpp"
#include "gyrochar/noise_model.hpp"

namespace gyrochar {

class EdfTable {
 public:
  /// The anchors of `stat` for taus m_min <= m <= m_max (m_max the longest with a term) over an
  /// unbroken run of n_phase points, their exact values computed with `cache`.
  /// O(anchors x alphas) exact EDFs.
  EdfTable(DevStat stat, std::uint64_t n_phase, std::uint64_t m_min, std::uint64_t m_max, PairSumCache& cache);

  /// Anchors computed (what the table costs).
  std::size_t anchors() const { return anchors_.size(); }
  /// True for m_min <= m <= m_max.
  bool covers(std::uint64_t m) const { return !anchors_.empty() && m >= anchors_.front().m && m <= anchors_.back().m; }

  /// The EDF of the unbroken estimate at m for noise alpha (0 where the statistic does not
  /// converge), and with `skew` its skew degrees of freedom (0 where the EDF is 200 or more: the read-out
  /// needs it below 100 only). m must be covered. O(log anchors), and the skewness of the two
  /// anchors around m the first time it is asked for (not for two threads at once).
  struct Value {
    double edf = 0;
    double skew_dof = 0;
  };
  Value at(std::uint64_t m, int alpha, bool skew = true) const;

  /// What estimate() gives with the exact EDF, the EDF and skewness taken from the table: the
  /// smallest plausible EDF of `noise`, scaled by the share of terms formed (gaps). o.edf must
  /// be EdfModel::exact. O(alphas x log anchors).
  Estimate estimate(const TauSums& t, std::uint64_t n_phase, const NoiseId& noise, const EstimateOptions& o) const;

 private:
  struct Anchor {
    std::uint64_t m = 0;
    Value value[7];  // index 2 - alpha
    bool skew_known[7] = {};
  };
  DevStat stat_;
  std::uint64_t n_phase_;
  mutable std::vector<Anchor> anchors_;  // the skewness filled in when first read
};

/// The sums of an unbroken fully overlapped tau m of `stat` over n_phase points, of unit
/// variance: what estimate() takes to give the EDF of that geometry. O(1).
TauSums unbroken_sums(DevStat stat, std::uint64_t m, std::uint64_t n_phase);

/// The anchors of a dense tau list for the statistics' grids (fully overlapped) over n_phase
/// points, m_min <= m <= m_max: neighbours within 2^(1/16) of each other in m and in the fewest
/// terms, and on both sides of every m where a grid's terms cross 1, 2, 3 or 4 times m.
std::vector<std::uint64_t> dense_anchors(std::span<const Stat> stats, std::uint64_t n_phase, std::uint64_t m_min,
                                         std::uint64_t m_max);

/// The pair sums identify_noise() reads at each fully overlapped tau of a dense list from m_min on
/// (Allan with itself, modified Allan with itself, the two), for a PairSumCache to ask first:
/// exact at the anchors, interpolated between them (each diagonal sum log-linearly in m, within
/// 2e-3 of the exact one, tests/host/test_edf_table.cpp). Holds the anchors' sums only, so a list
/// of N/2 taus costs O(log N) memory, not a cache entry a tau. Allocates; may throw std::bad_alloc.
class DenseNoiseSums final : public PairSumSource {
 public:
  /// The anchors for the taus m_min <= m of m_list over an unbroken run of n_phase points, their
  /// exact sums computed through `cache`. O(anchors) pair sums.
  DenseNoiseSums(std::span<const std::uint64_t> m_list, std::uint64_t n_phase, std::uint64_t m_min, PairSumCache& cache);
  /// Anchors computed (what the sums cost).
  std::size_t anchors() const { return anchors_.size(); }
  /// The sums of grids a and b when both are the unbroken fully overlapped grids of one covered m
  /// (Allan or modified Allan). O(log anchors).
  bool find(const TermGrid& a, const TermGrid& b, PairSums& out) const override;

 private:
  struct Anchor {
    std::uint64_t m = 0;
    PairSums aa, mm, am;
  };
  std::uint64_t n_phase_;
  std::vector<Anchor> anchors_;
};

}  // namespace gyrochar
