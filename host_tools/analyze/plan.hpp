#pragma once
// How gyrochar-analyze plans a run before it reads the values: the taus of a rule (octave, decade,
// all, a list) for the input's length, the stride factor "full" resolves to, whether the record is
// held for the batch kernels, and where generated taus stop for memory. gyrochar-analyze and the
// Python module (host_tools/python) share it, so that both give the same rows for the same values.
#include <cstdint>
#include <string>
#include <vector>

#include "analysis.hpp"

namespace gyrochar {

/// Bytes the history may take: half the machine's memory, or half the process's address-space
/// limit when one is set. O(1).
std::uint64_t memory_budget();
/// Where memory_budget() comes from, for a message ("half of the machine's memory", ...).
std::string memory_budget_reason();

struct TauPlan {
  bool generated = false;                 // octave, decade or all (not a list)
  bool held = false;                      // o.hold_counts or o.hold_phase
  std::vector<std::uint64_t> not_formed;  // decade taus the stride factor cannot form
  std::uint64_t cut_above = 0;            // generated taus stopped below this m (memory); 0: none
};

/// Fills o.hold_counts, o.hold_phase, o.stride_factor (when 0: "full" for n_phase), o.m_list and
/// o.theo_m_list for tau rule `taus` ("octave", "decade", "all"; anything else: the list `listed`,
/// strictly increasing) over at most n_phase phase points (0: unknown). Reads o.type and
/// o.values_hint (the number of values, or an upper bound). Generated taus stop where their history
/// would pass `budget` bytes. o.m_list comes out empty when n_phase is too small for any tau.
/// O(taus).
TauPlan plan_taus(AnalysisOptions& o, const std::string& taus, const std::vector<std::uint64_t>& listed,
                  std::uint64_t n_phase, std::uint64_t budget);

}  // namespace gyrochar
