#pragma once
// gyrochar-analyze's acceptance verdicts (--limits FILE, common/limits.hpp): the estimate of each
// limited quantity taken from the analysis (the fit of both curves for Q N B K R, the OADEV or
// MDEV row at the limit's tau), the verdicts in the table, CSV and JSON, and the analyzer's exit
// code for them.
#include <cstdint>
#include <string>
#include <vector>

#include "analysis_report.hpp"
#include "limits.hpp"
#include "verdict_output.hpp"

namespace gyrochar {

/// Exit codes of gyrochar-analyze --limits beyond the common table (hal/program/exit_codes.hpp):
/// every limit decided and met is 0; one undecided and none failed 5; one failed 6.
inline constexpr int exit_limits_undecided = 5;
inline constexpr int exit_limits_failed = 6;
int exit_code_of(Verdict overall);

/// The averaging factor of an adev or mdev limit's tau for tau0 (nearest integer), 0 when tau is not
/// a whole multiple of tau0 within 1e-9 relative, or for a term. O(1).
std::uint64_t limit_m(const Limit& limit, double tau0_s);

/// A fitted term's estimate for a verdict: its unconstrained value and uncertainty where the fit
/// gives them (Ieee952Parameter: unbiased where the model holds), else its own. O(1).
LimitEstimate fitted_term_estimate(const Ieee952Parameter& p, double run_s);

/// The decision of every limit for `r` over `rows` (every row computed, in engine units; the
/// report's own rows may be a subset) and a run of run_s seconds. Limits need gyro data (the
/// caller checks). O(limits x rows).
std::vector<Decision> decide_limits(const std::vector<Limit>& limits, const Report& r, const std::vector<AnalysisRow>& rows,
                                    double run_s);

}  // namespace gyrochar
