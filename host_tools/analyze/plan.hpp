#pragma once
// How gyrochar-analyze plans a run before it reads the values: the taus of a rule (octave, decade,
// all, a list) for the input's length, the stride factor "full" resolves to, whether the record is
// held for the batch kernels, and where generated taus stop for memory. gyrochar-analyze and the
// Python module (host_tools/python) share it, so that both give the same rows for the same values.
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "analysis.hpp"

namespace gyrochar {

/// Bytes the history may take: half the machine's memory, or half the process's address-space
/// limit when one is set. O(1).
std::uint64_t memory_budget();
/// Where memory_budget() comes from, for a message ("half of the machine's memory", ...).
std::string memory_budget_reason();

/// Which taus a run asks for: a rule that generates them from the input's length, or a list.
enum class TauRule { octave, decade, all, list };
/// "octave", "decade", "all", "list". A static string, never null.
const char* name(TauRule rule);
/// The rule called `text` (octave, decade, all); anything else is a list (parse_tau_list).
TauRule tau_rule(std::string_view text);
/// A list of averaging factors "1,10,100": positive and strictly increasing. Empty with `why`
/// set when the text is not one. O(length).
std::vector<std::uint64_t> parse_tau_list(std::string_view text, std::string& why);

/// The stride factor S asked for: "full" (the planning step chooses S from the input's length:
/// plan_taus, plan_window_taus) or a power of two the core's characterizer accepts
/// (valid_stride_factor). The one place a tool's text becomes a stride factor.
class StrideFactor {
 public:
  static StrideFactor full() { return StrideFactor(0); }
  /// "full", or S in decimal; nothing when the text is neither. O(length).
  static std::optional<StrideFactor> parse(std::string_view text);
  /// S as AnalysisOptions::stride_factor takes it before planning (0: full).
  static StrideFactor of(std::uint32_t requested) { return StrideFactor(requested); }
  bool is_full() const { return s_ == 0; }
  /// S given; 0 when full (not yet resolved).
  std::uint32_t requested() const { return s_; }
  /// What parse() accepts, for a message.
  static constexpr const char* accepted = "a power of two from 2 to 2^24, or full";

 private:
  explicit StrideFactor(std::uint32_t s) : s_(s) {}
  std::uint32_t s_;
};

struct TauPlan {
  bool generated = false;                 // octave, decade or all (not a list)
  bool held = false;                      // o.hold_counts or o.hold_phase
  std::vector<std::uint64_t> not_formed;  // decade taus the stride factor cannot form
  std::uint64_t cut_above = 0;            // generated taus stopped below this m (memory); 0: none
};

/// The planning step of a whole-record run: fills o.hold_counts, o.hold_phase, o.stride_factor (when 0: "full" for n_phase), o.m_list and
/// o.theo_m_list for tau rule `taus` ("octave", "decade", "all"; anything else: the list `listed`,
/// strictly increasing) over at most n_phase phase points (0: unknown). Reads o.type and
/// o.values_hint (the number of values, or an upper bound). Generated taus stop where their history
/// would pass `budget` bytes. o.m_list comes out empty when n_phase is too small for any tau.
/// O(taus).
TauPlan plan_taus(AnalysisOptions& o, TauRule rule, StrideFactor stride, const std::vector<std::uint64_t>& listed,
                  std::uint64_t n_phase, std::uint64_t budget);
/// plan_taus() with the rule as text (the Python module) and the stride factor in o.stride_factor.
TauPlan plan_taus(AnalysisOptions& o, const std::string& taus, const std::vector<std::uint64_t>& listed,
                  std::uint64_t n_phase, std::uint64_t budget);

/// The planning step of a dynamic run (dynamic.hpp): the taus of `rule` (or `listed`) over one
/// window of `window` values (`window_phase` phase points) that fit it (window_taus), and
/// o.stride_factor resolved for them ("full": every one of them fully overlapped, at most
/// full_stride_cap). Empty when none fits. O(taus).
std::vector<std::uint64_t> plan_window_taus(AnalysisOptions& o, TauRule rule, StrideFactor stride,
                                            const std::vector<std::uint64_t>& listed, std::uint64_t window,
                                            std::uint64_t window_phase);

}  // namespace gyrochar
