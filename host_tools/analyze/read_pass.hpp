#pragma once
// What gyrochar-analyze watches while it reads the values (run.hpp): their shape (a constant or a
// straight line, whose deviations are 0 by right, and --nominal-hz's conversion), the progress
// line on stderr, and the data file's errors as the run's. Errors are thrown as ToolError
// (request.hpp).
#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "analysis.hpp"
#include "datafile.hpp"

namespace gyrochar {

// What the values say about numerical collapse, as they are read: --nominal-hz's conversion
// y = (f - F0) / F0, refused where it loses the values, and whether the input is constant
// (frequency, counts) or a straight line (phase), whose deviations are all 0 by right.
class InputShape {
 public:
  InputShape(DataType type, double nominal_hz) : phase_(type == DataType::phase), f0_(nominal_hz) {}

  /// Converts `values` in place (--nominal-hz) and takes note of them. Throws BadValue for a value
  /// f != F0 that the conversion takes to 0 or below the smallest normal double. O(n).
  void add(std::span<double> values);
  /// bad() when --nominal-hz made values that vary all equal: f - F0 rounded them away (values
  /// far below F0 given as Hz: fractional frequency, whose analysis needs no --nominal-hz).
  void check_conversion() const;
  /// Every deviation of such an input is 0: a constant (frequency, counts), a straight line (phase).
  bool straight() const { return !bent_; }
  const char* shape() const { return phase_ ? "a straight line (a constant frequency)" : "constant"; }
  double lowest() const { return lo_; }
  double highest() const { return hi_; }

 private:
  bool phase_;
  double f0_;
  std::uint64_t n_ = 0;
  double first_ = 0, last_ = 0, step_ = 0, lo_ = 0, hi_ = 0;
  double raw_lo_ = 0, raw_hi_ = 0;
  bool bent_ = false, converted_vary_ = false;
};

/// After a whole analysis whose every deviation is 0 (all_zero): a note for a constant or straight
/// input, bad() otherwise (the squares of the differences underflowed to exactly 0).
void check_zeros(bool all_zero, const InputShape& shape, const std::string& source);
bool all_zero(const std::vector<AnalysisRow>& rows);

/// Prints how far the reading got, about every 2^20 values, when enabled; nothing for short inputs.
class Progress {
 public:
  Progress(bool enabled, const DataFile& file) : enabled_(enabled), file_(file) {}
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;
  /// n more values read, the file's bytes_read() after them.
  void values(std::size_t n, std::uint64_t bytes_read);

 private:
  bool enabled_;
  const DataFile& file_;
  std::uint64_t values_ = 0, next_ = 1u << 20;
};

/// The engine's progress callback (AnalysisOptions::on_progress): "summing: k of n taus", "theoh: k
/// of n taus", ... on stderr.
std::function<void(const char*, std::size_t, std::size_t)> stage_progress();
/// Ends a progress line left open on stderr, before an error line. O(1).
void end_progress_line();

/// bad() for a data file's error, with its line when it has one.
[[noreturn]] void bad_data(const std::string& source, const DataFileError& e);

}  // namespace gyrochar
