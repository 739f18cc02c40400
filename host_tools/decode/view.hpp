#pragma once
// gyrochar-decode for people: the terminal view of every node and the end-of-run summary. The
// node's IEEE-952 fit is shown with its summary (protocol version 2: status, chi2/dof, points,
// quantization); where a gyro's true parameters are known (a simulation), they are shown beside.
#include <string>
#include <string_view>

#include "rows.hpp"

namespace gyrochar::decoding {

/// The terminal view: input counters, then per shown node its state, metadata, link health, node
/// faults, the tau table (tau, ADEV and MDEV with confidence intervals, n, EDF, noise) and the
/// IEEE-952 fit (its summary, and each term: value and uncertainty, whether resolved; with `truth`,
/// the true value of the nodes it names beside). Plain text, no terminal control codes.
/// O(nodes x taus).
std::string format_view(const Decoder& decoder, const InputCounters& input, const NodeFilter& shown, const DisplayRate& rate,
                        ConfidenceIntervals& intervals, const TrueTermsByNode* truth = nullptr);

/// The end-of-run summary for stderr: one line for the input, one per node with its link health.
/// Each line starts with "`program`: ".
std::string format_summary(const Decoder& decoder, const InputCounters& input, const NodeFilter& shown,
                           std::string_view program = "gyrochar-decode");

}  // namespace gyrochar::decoding
