#pragma once
// gyrochar-decode's acceptance verdicts (--limits, common/limits.hpp) and its self-contained HTML
// report (--report, common/html_report.hpp), per node, from the Decoder's view of it.
//
// Estimates of a node: a term from the node's latest fit (its value and relative standard
// uncertainty, as sent; the fit's summary must say ok and the term be resolved), a deviation from
// the tau whose m tau0 is the limit's tau (its EDF as sent; no skewness travels: the plain
// chi-squared interval). The run length is the node's sample count times tau0.
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "decoder.hpp"
#include "display_units.hpp"
#include "limits.hpp"
#include "verdict_output.hpp"
#include "rows.hpp"

namespace gyrochar::decoding {

/// The verdict of each limit for `node`, in the limits' order. Undecided, saying why, while the
/// node's angle unit, tau0, fit or tau are unknown or the node reports pulses. O(limits x taus).
std::vector<Decision> node_decisions(const NodeView& node, const std::vector<Limit>& limits);

/// Whether `limit` applies to tau `tau_index` of `node` (a row of the per-tau CSV): a term limit to
/// every tau (the report's fit, as the fit_ columns), a deviation limit to the tau whose m tau0 is
/// its tau. O(1).
bool limit_applies(const Limit& limit, const NodeView& node, std::size_t tau_index);

/// The per-tau CSV's verdict columns with --limits (after its other columns, each with its leading
/// comma): "verdict" (the node's over all limits, as the summary's), then per limit
/// "<quantity> limit [unit]" and its decision_columns (verdict_output.hpp), and for a term limit
/// "<quantity> estimate kind" (unconstrained, or shown where the node sends no unconstrained
/// estimate; empty without an estimate). O(limits).
std::string verdict_csv_header(const std::vector<Limit>& limits);
/// Their number. O(1).
std::size_t verdict_csv_columns(const std::vector<Limit>& limits);
/// A tau row's fields: `decisions` (node_decisions of the node as its report closed), a limit's
/// fields empty where it does not apply to the row. O(limits).
std::string verdict_csv_fields(const std::vector<Limit>& limits, const std::vector<Decision>& decisions,
                               const NodeView& node, std::size_t tau_index);

/// The verdicts of every shown node, for the end of the view: a block per node. O(nodes x limits).
std::string format_verdicts(const Decoder& decoder, const NodeFilter& shown, const std::vector<Limit>& limits);

/// A JSON lines record {"type": "acceptance", "time", "node", "session", "verdict", "limits": [...]}
/// (the analyzer's "acceptance" members per limit). O(limits).
nlohmann::json acceptance_record(double time_s, const NodeView& node, const std::vector<Limit>& limits,
                                 const std::vector<Decision>& decisions);

/// The production summary row of a node (production_summary.hpp). O(limits).
GyroSummary node_summary(const NodeView& node, const std::string& source, const std::vector<Limit>& limits);

/// The HTML report of every shown node: per node its provenance (input, node, configuration, sample
/// count, gaps, link health), the ADEV/MDEV plot with intervals and the fitted model, the tau table
/// with intervals, the fit's terms and status, and the verdicts. O(nodes x taus).
std::string decode_html(const Decoder& decoder, const InputCounters& input, const NodeFilter& shown, const DisplayRate& rate,
                        ConfidenceIntervals& intervals, const std::vector<Limit>& limits, const std::string& command);

}  // namespace gyrochar::decoding
