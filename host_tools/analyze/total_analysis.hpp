#pragma once
// The total and Theo family in gyrochar-analyze (core/include/gyrochar/total.hpp, docs/total.md):
// TOTDEV, MTOTDEV, TTOTDEV, HTOTDEV, Theo1 and TheoH rows from the phase record the analyzer holds
// when one of them is asked for: a counter's residuals as the batch engine holds them (4 bytes a
// point while they fit in int32), else the phase as doubles (8 bytes a point; counts stay exact up
// to 2^53 pulses). Nothing else the size of the record: the decimated MTOTDEV sums its blocks a
// window at a time (for counts, from their sums over a block of 64 or more: GroupSums).
//
// Each row borrows from the Allan-family row of the same run at the same tau (for Theo1 and
// TheoBR, at the largest tau at or below 0.75 m tau0): its noise identification, and its EDF where
// SP 1065 has no formula for the total statistic at that noise (TOTDEV for white and flicker PM,
// HTOTDEV below m = 16 or for PM noise). Where alpha is known the deviations carry Stable32's bias
// corrections (TOTDEV for flicker and random-walk FM, HTOTDEV for alpha <= 0). TheoH's rows below
// its switch point are the overlapping ADEV rows themselves.
#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "analysis.hpp"
#include "gyrochar/total_fast.hpp"
#include "held_memory.hpp"

namespace gyrochar {

/// One thread's access to the prepared record: the preparation itself, or a copy of it with an FFT
/// buffer of its own (the rest is read only by the taus), and its MTOTVAR scratch.
struct LagSumView {
  Theo1Workspace* work = nullptr;
  std::span<double> scratch;
};

/// The record prepared for the lag sums (total_fast.hpp), kept between the statistics of one run:
/// Theo1, TheoH, MTOTDEV and TTOTDEV share the preparation of the phase points, HTOTDEV prepares
/// their first differences. One preparation is held at a time (at 10^7 points 0.9 GB), the other
/// kind replacing it. A second thread's FFT buffer and scratch are allocated beside it on first
/// use, when the memory budget has room for them (2 fft_length(2 N) + N doubles: 0.6 GB at 10^7,
/// touched only as far as that thread's taus reach).
class LagSumRecord {
 public:
  /// The preparation of x (frequencies: of y[k] = x[k+1] - x[k]), made on first use, as one view per
  /// thread for up to `threads` threads (1 or 2). The first view is the preparation's own.
  std::span<LagSumView> views(PhaseSpan x, bool frequencies, unsigned threads);
  /// TheoBR's bias ratio as TheoH's rows computed it (analysis.hpp).
  TheoBias theoh_bias;

 private:
  // The lag sums' workspaces (0.9 GB at 10^7 points), not zero-filled: each writes before it reads.
  UninitializedDoubles work_, scratch_, second_buffer_, second_scratch_;
  std::vector<double> y_;
  Theo1Workspace w_, second_;
  std::array<LagSumView, 2> views_{};
  bool frequencies_ = false;
};

/// The sums of an integer record over consecutive groups of g samples (floor(N / g) of them, modulo
/// 2^64 as total_lags.hpp forms them), held as int32 while every one fits and as int64 otherwise: the lag tables of counts' decimated
/// MTOTDEV (total_lags.hpp) read their blocks' sums from these, g times fewer values than the record,
/// instead of summing the record again for every tau. Sums over groups of k g of the record are the
/// sums over groups of k of these, the same integers. O(N), 4 N / g bytes (8 N / g when wide).
class GroupSums {
 public:
  GroupSums(PhaseSpan x, std::uint64_t g);
  std::uint64_t group() const { return g_; }
  PhaseSpan sums() const { return wide_.empty() ? PhaseSpan(narrow_) : PhaseSpan(wide_); }

 private:
  std::uint64_t g_;
  std::vector<std::int32_t> narrow_;
  std::vector<std::int64_t> wide_;
};

/// The rows of total statistic `stat` (is_total(stat)) of phase points `phase` (phase unit /
/// phase_scale: the engine's representation), at o.m_list (TOTDEV, MTOTDEV, TTOTDEV, HTOTDEV,
/// TheoH's ADEV part) or o.theo_m_list (Theo1, TheoH's TheoBR part), the exact estimator where it
/// costs at most 2^26 operations per tau and the decimated one with o.total_stride_factor beyond;
/// Theo1 (and TheoBR's Theo1 factor) exact at every tau by lag sums (total_fast.hpp) unless
/// o.theo_decimated, and MTOTDEV/TTOTDEV/HTOTDEV the same unless o.total_decimated (each also falls
/// back to the plan when its lag-sum workspace would pass the memory budget).
/// `allan`: the run's oadev, mdev and ohdev rows at its taus. `exact_sums`: the engine's sums where
/// they are exact sums of the held record's own terms (counts; else empty): TOTDEV takes its
/// unreflected terms from the overlapping AVAR's sum at the same m. Allocates the kernels' scratch
/// and the rows; O(N) per tau for TOTDEV (O(m) with exact sums), O(N S) to O(N S^2 / m) for the
/// others (docs/total.md). `lag_sums`: the run's one LagSumRecord.
std::vector<AnalysisRow> total_rows(DevStat stat, PhaseSpan phase, double phase_scale, const AnalysisOptions& o,
                                    const std::vector<AnalysisRow>& allan, std::span<const TauSums> exact_sums,
                                    LagSumRecord& lag_sums);

}  // namespace gyrochar
