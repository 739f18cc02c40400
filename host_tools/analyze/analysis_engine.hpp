#pragma once
// Inside the offline engine (analysis.hpp), not for its callers: what its engines share (the
// interface, the read-out of the sums into rows, the record kept for the total family) and the
// engines over a held record (held_engines.cpp): the batch kernels of counts and of phase or
// frequency. The characterizer's engine is analysis.cpp's own.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "analysis.hpp"
#include "gyrochar/arith.hpp"
#include "gyrochar/estimates.hpp"
#include "held_memory.hpp"

namespace gyrochar {

struct EngineBase {
  virtual ~EngineBase() = default;
  virtual void add(std::span<const double> values) = 0;
  virtual Analysis result(const AnalysisOptions& o) const = 0;
  virtual PhaseRecord record(const AnalysisOptions& o) const = 0;
  virtual HeldCounts held_counts() const { return {}; }
  virtual std::vector<std::byte> checkpoint() const { throw std::invalid_argument(no_checkpoint); }
  virtual std::string restore(std::span<const std::byte>) { throw std::invalid_argument(no_checkpoint); }
  static constexpr const char* no_checkpoint =
      "a checkpoint holds the characterizer's state, not a held record: not with the total family or a "
      "record of known length held in memory";
};

// The read-out every engine shares: the noise identification of every tau (Allan and Hadamard
// curves), then each statistic's rows with their EDF and interval, and the total family from the
// record. `a` has its counts filled in; the rows are appended.
void read_out(Analysis& a, const std::vector<TauSums>& sums, DataType type, const AnalysisOptions& o, PhaseSpan record);

// The sums the read-out of `o` needs, as phase_batch_taus()' kinds (float_batch.hpp): those of
// each statistic asked for; AVAR, MVAR (R(n)) and the noise sums of the decimated series (lag-1,
// B1) to identify the noise; all of them for the total family.
unsigned sums_needed(const AnalysisOptions& o);

// The record for the total family: phase relative to the first point (the statistics ignore a
// constant); for frequency data the running sum of the values less the first value, that is the
// phase less the line of that slope (the statistics ignore a line too: each is built of second or
// higher differences of the phase or of the line-free residuals of its sub-sequences, and the
// reflections at the ends continue a line); for counts the running sum of the counts (exact in
// integers). A frequency offset would make the running sum a ramp that loses, at every step, the
// rounding of the ramp's size (on a 1.3e-8 offset, 1e-10 of TOTDEV at long tau); less it, and
// summed in double-double (the characterizer's FloatArith::add_prefix), each point is the exact sum
// to about one rounding.
struct KeptRecord {
  KeptRecord(DataType data_type, bool keep_it) : type(data_type), on(keep_it) {}
  // Room for `values` (a bound; untouched room costs no memory): the points are not copied as
  // they grow, nor written to fresh pages twice.
  void reserve(std::uint64_t values) {
    if (on) points.reserve(values + 1);
  }
  void keep(double value) {
    if (!on) return;
    if (type == DataType::phase) {
      if (points.empty()) first = value;
      points.push_back(value - first);
    } else if (type == DataType::freq) {
      if (points.empty()) {
        first = value;
        points.push_back(0.0);
      }
      sum = FloatArith::add_prefix(sum, value - first);
      points.push_back(sum.hi);
    } else {
      if (points.empty()) points.push_back(0.0);
      points.push_back(points.back() + value);
    }
  }
  DataType type;
  bool on;
  double first = 0.0;      // the first phase value, or the first frequency
  FloatArith::Prefix sum;  // frequency data: the running sum in double-double
  Held<double> points;
};

/// Counts with the record held: every tau summed over it by the batch kernel (core batch.hpp).
std::unique_ptr<EngineBase> make_count_batch_engine(std::uint32_t stride_factor, const std::vector<std::uint64_t>& m_list,
                                                    bool keep_record, std::uint64_t values_hint);
/// Phase or frequency with the record held: every tau summed by phase_batch_taus() over the points,
/// or with prefix_sums by float_batch_taus() (float_batch.hpp; dense tau lists).
std::unique_ptr<EngineBase> make_float_batch_engine(DataType type, std::uint32_t stride_factor,
                                                    const std::vector<std::uint64_t>& m_list, bool keep_record,
                                                    std::uint64_t values_hint, bool prefix_sums);

}  // namespace gyrochar
