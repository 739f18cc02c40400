// resolve_units (host_tools/analyze/input_units.hpp), the one resolution of the unit options that
// gyrochar-analyze and the Python module share: what it accepts (oracle: the unit definitions,
// 1 arcsec = pi / 648000 rad, 1 deg/h = pi / 648000 rad/s) and the option and reason of each
// refusal, which the program prints as "gyrochar-analyze: option: reason" (test_tool_errors,
// test_analyze_cli) and the module raises as ValueError("argument: reason") (tests/python).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>

#include "input_units.hpp"

namespace gyrochar {
namespace {

constexpr double arcsec_rad = std::numbers::pi / 648000.0;

UnitOptions of(DataType type, std::string unit = "", std::string pulse_weight = "") {
  UnitOptions o;
  o.type = type;
  o.unit = std::move(unit);
  o.pulse_weight = std::move(pulse_weight);
  return o;
}

// The option and reason of the refusal of `o` ("" when it is accepted).
std::string refusal(const UnitOptions& o) {
  try {
    resolve_units(o);
  } catch (const UnitError& e) {
    return e.option() + ": " + e.what();
  }
  return "";
}

TEST(ResolveUnits, AcceptsEachTypesUnits) {
  const ReportUnits clock = resolve_units(of(DataType::phase));
  EXPECT_FALSE(clock.gyro);
  EXPECT_EQ(clock.input, "phase in s");
  EXPECT_EQ(resolve_units(of(DataType::freq)).input, "fractional frequency");

  const ReportUnits counts = resolve_units(of(DataType::counts, "", "1.5 arcsec"));
  EXPECT_TRUE(counts.gyro);
  EXPECT_DOUBLE_EQ(counts.phase_unit_si, 1.5 * arcsec_rad);
  EXPECT_EQ(counts.input, "counts of 1.5 arcsec");
  EXPECT_DOUBLE_EQ(counts.rate.rad_per_s, arcsec_rad);  // deg/h by default: 3600 arcsec / 3600 s

  UnitOptions bare = of(DataType::counts, "", "2");  // the unit from --pulse-unit
  bare.pulse_unit = "urad";
  bare.pulse_unit_given = true;
  EXPECT_DOUBLE_EQ(resolve_units(bare).phase_unit_si, 2e-6);

  UnitOptions rate = of(DataType::freq, "deg/s");
  rate.rate_unit = "rad/s";
  rate.rate_unit_given = true;
  const ReportUnits r = resolve_units(rate);
  EXPECT_DOUBLE_EQ(r.phase_unit_si, std::numbers::pi / 180);
  EXPECT_DOUBLE_EQ(r.rate.rad_per_s, 1.0);

  UnitOptions hz = of(DataType::freq);
  hz.nominal_hz = 10e6;
  EXPECT_EQ(resolve_units(hz).input, "frequency in Hz, nominal 10000000 Hz");
}

TEST(ResolveUnits, RefusesNamingTheOptionAndTheCause) {
  EXPECT_EQ(refusal(of(DataType::phase, "furlong")),
            "--unit: phase is in s or an angle unit (rad, mrad, urad, deg, arcsec), not 'furlong'");
  EXPECT_EQ(refusal(of(DataType::freq, "Hz")), "--unit: frequency in Hz needs --nominal-hz");
  EXPECT_EQ(refusal(of(DataType::counts)), "--pulse-weight: counts need the angle of one pulse, e.g. 1.5arcsec");
  EXPECT_EQ(refusal(of(DataType::counts, "deg")), "--unit: counts take --pulse-weight instead");
  EXPECT_EQ(refusal(of(DataType::counts, "", "1parsec")),
            "--pulse-weight: unknown angle unit 'parsec' (rad, mrad, urad, deg, arcsec)");
  EXPECT_EQ(refusal(of(DataType::counts, "", "-1arcsec")),
            "--pulse-weight: '-1arcsec' is not a positive angle such as 1.5arcsec");
  EXPECT_NE(refusal(of(DataType::counts, "", "1e-320arcsec")).find("below the smallest normal double"), std::string::npos);
  EXPECT_EQ(refusal(of(DataType::phase, "", "1arcsec")), "--pulse-weight: only applies to --type counts");

  UnitOptions contradiction = of(DataType::counts, "", "1deg");
  contradiction.pulse_unit_given = true;  // arcsec
  EXPECT_EQ(refusal(contradiction), "--pulse-weight: unit deg contradicts --pulse-unit arcsec");
  UnitOptions clock_rate = of(DataType::phase);
  clock_rate.rate_unit_given = true;
  EXPECT_EQ(refusal(clock_rate), "--rate-unit: only applies to gyro data (counts, or --unit with an angle or a rate)");
  UnitOptions bad_rate = of(DataType::phase, "deg");
  bad_rate.rate_unit = "mph";
  EXPECT_EQ(refusal(bad_rate), "--rate-unit: unknown unit 'mph' (deg/h, deg/s, rad/s)");
  UnitOptions phase_hz = of(DataType::phase);
  phase_hz.nominal_hz = 5e6;
  EXPECT_EQ(refusal(phase_hz), "--nominal-hz: only applies to --type freq");
  UnitOptions negative_hz = of(DataType::freq);
  negative_hz.nominal_hz = -1;
  EXPECT_EQ(refusal(negative_hz), "--nominal-hz: must be a positive frequency in Hz");
}

TEST(ResolveUnits, IsAnInvalidArgument) {
  EXPECT_THROW(resolve_units(of(DataType::phase, "furlong")), std::invalid_argument);
}

}  // namespace
}  // namespace gyrochar
