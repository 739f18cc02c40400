// What gyrochar-analyze watches while it reads the values (read_pass.hpp).
#include "read_pass.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "request.hpp"
#include "hal/program/exit_codes.hpp"

namespace gyrochar {

namespace {

bool progress_line_open = false;  // a progress line without its newline is on stderr

}  // namespace

void InputShape::add(std::span<double> values) {
  for (std::size_t i = 0; i < values.size(); ++i) {
    double& v = values[i];
    if (f0_ > 0) {
      const double f = v;
      v = (f - f0_) / f0_;
      if (f != f0_ && !std::isnormal(v))
        throw BadValue(i, fmt::format("(f - F0) / F0 of {:g} Hz with F0 = {:g} Hz is {:g}, below the smallest "
                                      "normal double (2.2e-308)",
                                      f, f0_, v));
      raw_lo_ = n_ == 0 ? f : std::min(raw_lo_, f);
      raw_hi_ = n_ == 0 ? f : std::max(raw_hi_, f);
      converted_vary_ |= n_ > 0 && v != first_;
    }
    if (n_ == 0) first_ = lo_ = hi_ = v;
    lo_ = std::min(lo_, v);
    hi_ = std::max(hi_, v);
    // Phase: every step equal to the first; frequency and counts: every value equal to the first.
    if (phase_ && n_ == 1) step_ = v - last_;
    bent_ |= phase_ ? n_ > 1 && v - last_ != step_ : v != first_;
    last_ = v;
    ++n_;
  }
}

void InputShape::check_conversion() const {
  if (f0_ > 0 && raw_lo_ != raw_hi_ && !converted_vary_)
    bad("--nominal-hz", fmt::format("the values vary from {:g} to {:g} Hz, but (f - F0) / F0 with F0 = {:g} Hz makes "
                                    "every one {:g}: their differences are below the resolution of a double at F0 "
                                    "({:.2g} Hz). Are they fractional frequency already (then without --nominal-hz)?",
                                    raw_lo_, raw_hi_, f0_, first_, std::nextafter(f0_, HUGE_VAL) - f0_));
}

void check_zeros(bool all_zero, const InputShape& shape, const std::string& source) {
  if (!all_zero) return;
  if (!shape.straight())
    bad(source, fmt::format("every deviation is 0, but the values (from {:g} to {:g}) are not {}: the squares of their "
                            "differences underflow a double (smallest normal 2.2e-308): the values are too small; "
                            "scale them",
                            shape.lowest(), shape.highest(), shape.shape()));
  print_error(analyze_program, "note", fmt::format("every deviation is 0: the values are {}", shape.shape()));
}
bool all_zero(const std::vector<AnalysisRow>& rows) {
  return std::all_of(rows.begin(), rows.end(), [](const AnalysisRow& r) { return r.dev == 0; });
}

Progress::~Progress() { end_progress_line(); }

void Progress::values(std::size_t n, std::uint64_t bytes_read) {
  values_ += n;
  if (!enabled_ || values_ < next_) return;
  next_ = values_ + (1u << 20);
  progress_line_open = true;
  const std::uint64_t size = file_.size_bytes();
  if (size > 0)
    std::fprintf(stderr, "\rgyrochar-analyze: reading: %5.1f %%",
                 100.0 * static_cast<double>(bytes_read) / static_cast<double>(size));
  else std::fprintf(stderr, "\rgyrochar-analyze: reading: %llu values", static_cast<unsigned long long>(values_));
}

std::function<void(const char*, std::size_t, std::size_t)> stage_progress() {
  return [shown = std::size_t{0}](const char* stage, std::size_t done, std::size_t total) mutable {
    if (done < total && 1000 * done / total == 1000 * shown / total) return;  // every 0.1 %
    shown = done < total ? done : 0;                                          // the next stage starts from 0
    progress_line_open = done < total;
    std::fprintf(stderr, "\rgyrochar-analyze: %s: %zu of %zu taus%s", stage, done, total, done < total ? "" : "\n");
  };
}

void end_progress_line() {
  if (progress_line_open) std::fputc('\n', stderr);
  progress_line_open = false;
}

void bad_data(const std::string& source, const DataFileError& e) {
  bad(source, e.line() ? fmt::format("line {}: {}", e.line(), e.what()) : e.what());
}

}  // namespace gyrochar
