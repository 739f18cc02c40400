#pragma once
// What the values are and the unit the deviations come out in: gyrochar-analyze's --type with
// --unit, --pulse-weight, --pulse-unit, --nominal-hz and --rate-unit resolved to ReportUnits.
// gyrochar-analyze and the Python module (host_tools/python) share it, so that both accept the
// same units and refuse the rest with the same messages.
#include <optional>
#include <stdexcept>
#include <string>

#include "analysis.hpp"
#include "analysis_report.hpp"

namespace gyrochar {

/// The unit options as the command line gives them.
struct UnitOptions {
  DataType type = DataType::phase;
  std::string unit;                   // --unit; empty: the type's default (s, or 1)
  std::string pulse_weight;           // --pulse-weight: "1.5arcsec", "1.5 arcsec", or "1.5" in pulse_unit
  std::string pulse_unit = "arcsec";  // --pulse-unit
  bool pulse_unit_given = false;
  std::optional<double> nominal_hz;  // --nominal-hz: freq values in Hz around it
  std::string rate_unit = "deg/h";   // --rate-unit
  bool rate_unit_given = false;
};

/// A unit option refused: option() names it as the program does ("--unit"), what() says why.
class UnitError : public std::invalid_argument {
 public:
  UnitError(std::string option, const std::string& why) : std::invalid_argument(why), option_(std::move(option)) {}
  const std::string& option() const { return option_; }

 private:
  std::string option_;
};

/// The ReportUnits of `o` (input described as e.g. "counts of 1.5 arcsec", "phase in s"). Throws
/// UnitError for a unit that does not fit the type, an unknown unit, a pulse weight that is not a
/// positive angle whose value in rad is a normal double, or an option the type does not take. O(1).
ReportUnits resolve_units(const UnitOptions& o);

}  // namespace gyrochar
