#pragma once
// The acceptance verdicts as the tools write them (a table for people, CSV, JSON), and the
// production summary (--summary FILE.csv of gyrochar-analyze and gyrochar-decode): one CSV row
// per gyro (a file, or a node on a bus) with its IEEE-952 terms, their uncertainties and status,
// and its acceptance verdicts; appended to FILE, whose header is written once. A file whose header
// differs (other limits) is refused, so that one file never mixes columns.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "limits.hpp"

namespace gyrochar {

/// The verdicts for people (after the table), as CSV (a second table after a blank line, header
/// acceptance_csv_header) and as JSON {"confidence", "rule", "verdict", "limits": [...]}.
std::string acceptance_table(const std::vector<Limit>& limits, const std::vector<Decision>& decisions);
inline constexpr const char* acceptance_csv_header = "limit,limit_value,unit,estimate,lower,upper,verdict,decides_at_s,why";
std::string acceptance_csv(const std::vector<Limit>& limits, const std::vector<Decision>& decisions);
nlohmann::json acceptance_json(const std::vector<Limit>& limits, const std::vector<Decision>& decisions);

struct SummaryTerm {
  bool known = false;                 // the fit has a value for it
  double value = 0, uncertainty = 0;  // in the term's gyro unit (units::ieee952)
  std::string status;                 // "resolved", "not resolved", "not in model", "" (no fit)
};

struct GyroSummary {
  std::string source;  // the input file, or "can0 node 3"
  std::string node;    // node address; empty for a file
  double run_s = 0;    // run length
  std::uint64_t samples = 0;
  std::string fit_status;  // "ok", "model rejected", ...; empty: no fit
  double chi2_per_dof = 0;
  std::array<SummaryTerm, 5> terms{};  // Q N B K R
  std::vector<Decision> decisions;     // in the order of the limits
};

/// `s` as a CSV field: quoted (quotes doubled) when it holds a separator, a quote or a line break.
std::string csv_field(const std::string& s);

/// One limit's decision as CSV columns, as the production summary and the decoder's per-tau CSV
/// (--limits) give them: ",<quantity> verdict,<quantity> estimate [unit],<quantity> lower,
/// <quantity> upper" (each with its leading comma), the bounds the decision bounds of limits.hpp in
/// the limit's unit. The fields of `decision`, or empty ones for none (null). O(1).
std::string decision_columns(const Limit& limit);
std::string decision_fields(const Limit& limit, const Decision* decision);

/// The header line (no newline): source,node,run_s,samples,fit_status,chi2_per_dof, then per term
/// "N [deg/sqrt(h)]","N u","N status", then verdict, then per limit its decision_columns.
/// O(limits).
std::string summary_header(const std::vector<Limit>& limits);
/// One row (no newline). O(limits).
std::string summary_row(const GyroSummary& gyro, const std::vector<Limit>& limits);

/// Checks before a run that `path` can take rows for `limits`: absent, empty, or with the same
/// header line. False with `why` otherwise. O(header).
bool summary_compatible(const std::string& path, const std::vector<Limit>& limits, std::string& why);
/// Appends `rows` to `path`, first the header when the file is absent or empty. False with `why`
/// when it cannot be written. O(rows).
bool append_summary(const std::string& path, const std::vector<Limit>& limits, const std::vector<GyroSummary>& rows,
                    std::string& why);

}  // namespace gyrochar
