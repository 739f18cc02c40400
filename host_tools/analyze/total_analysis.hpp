#pragma once
// The total and Theo family in gyrochar-analyze (core/include/gyrochar/total.hpp, docs/total.md):
// TOTDEV, MTOTDEV, TTOTDEV, HTOTDEV, Theo1 and TheoH rows from the phase record the analyzer holds
// when one of them is asked for (8 bytes a point: the record as doubles; counts stay exact up to
// 2^53 pulses), beside one buffer of block sums (4 bytes a point) for the decimated MTOTDEV.
//
// Each row borrows from the Allan-family row of the same run at the same tau (for Theo1 and
// TheoBR, at the largest tau at or below 0.75 m tau0): its noise identification, and its EDF where
// SP 1065 has no formula for the total statistic at that noise (TOTDEV for white and flicker PM,
// HTOTDEV below m = 16 or for PM noise). Where alpha is known the deviations carry Stable32's bias
// corrections (TOTDEV for flicker and random-walk FM, HTOTDEV for alpha <= 0). TheoH's rows below
// its switch point are the overlapping ADEV rows themselves.
#include <memory>
#include <span>
#include <vector>

#include "analysis.hpp"
#include "gyrochar/total_fast.hpp"

namespace gyrochar {

/// Memory for the lag sums' workspaces, not zero-filled: from 8 MiB up aligned to 2 MiB and offered
/// to transparent huge pages (madvise; a hint the kernel may refuse), so that first touching the
/// 0.9 GB of a 10^7-point record costs one fault every 2 MiB, not every 4 KiB (BENCHMARKS.md, the
/// exact MTOTDEV at 10^7). Throws std::bad_alloc.
struct FreeDoubles {
  void operator()(double* p) const noexcept;
};
using HugeArray = std::unique_ptr<double[], FreeDoubles>;
HugeArray huge_array(std::size_t n);

/// The record prepared for the lag sums (total_fast.hpp), kept between the statistics of one run:
/// Theo1, TheoH, MTOTDEV and TTOTDEV share the preparation of the phase points, HTOTDEV prepares
/// their first differences. One preparation is held at a time (at 10^7 points 1.5 GB), the other
/// kind replacing it; MTOTVAR's scratch is allocated beside it on first use.
class LagSumRecord {
 public:
  /// The preparation of x (frequencies: of y[k] = x[k+1] - x[k]), made on first use.
  Theo1Workspace& prepared(std::span<const double> x, bool frequencies);
  /// mtotvar_scratch_size of the prepared record's length, allocated on first use.
  std::span<double> scratch();

 private:
  HugeArray work_, scratch_;  // not zero-filled: prepare writes before it reads
  std::vector<double> y_;
  Theo1Workspace w_;
  bool frequencies_ = false;
  std::size_t scratch_size_ = 0;
};

/// The rows of total statistic `stat` (is_total(stat)) of phase points `phase` (phase unit /
/// phase_scale: the engine's representation), at o.m_list (TOTDEV, MTOTDEV, TTOTDEV, HTOTDEV,
/// TheoH's ADEV part) or o.theo_m_list (Theo1, TheoH's TheoBR part), the exact estimator where it
/// costs at most 2^26 operations per tau and the decimated one with o.total_stride_factor beyond;
/// Theo1 (and TheoBR's Theo1 factor) exact at every tau by lag sums (total_fast.hpp) unless
/// o.theo_decimated, and MTOTDEV/TTOTDEV/HTOTDEV the same unless o.total_decimated (each also falls
/// back to the plan when its lag-sum workspace would pass the memory budget).
/// `allan`: the run's oadev, mdev and ohdev rows at its taus. Allocates the block-sum buffer and the
/// rows; O(N) per tau for TOTDEV, O(N S) to O(N S^2 / m) for the others (docs/total.md).
/// `lag_sums`: the run's one LagSumRecord.
std::vector<AnalysisRow> total_rows(DevStat stat, std::span<const double> phase, double phase_scale,
                                    const AnalysisOptions& o, const std::vector<AnalysisRow>& allan, LagSumRecord& lag_sums);

}  // namespace gyrochar
