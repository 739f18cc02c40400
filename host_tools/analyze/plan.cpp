#include "plan.hpp"

#include <fmt/format.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <charconv>

#include "dynamic.hpp"

namespace gyrochar {

namespace {

std::uint64_t machine_budget() {
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGESIZE);
  return pages > 0 && page > 0 ? static_cast<std::uint64_t>(pages) * static_cast<std::uint64_t>(page) / 2
                               : std::uint64_t{1} << 32;
}

}  // namespace

std::uint64_t memory_budget() {
  std::uint64_t budget = machine_budget();
  rlimit limit{};
  if (getrlimit(RLIMIT_AS, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY)
    budget = std::min<std::uint64_t>(budget, limit.rlim_cur / 2);
  return budget;
}

std::string memory_budget_reason() {
  rlimit limit{};
  if (getrlimit(RLIMIT_AS, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY && limit.rlim_cur / 2 < machine_budget())
    return fmt::format("half of its address-space limit, ulimit -v {} KiB", limit.rlim_cur >> 10);
  return "half of the machine's memory";
}

const char* name(TauRule rule) {
  switch (rule) {
    case TauRule::octave: return "octave";
    case TauRule::decade: return "decade";
    case TauRule::all: return "all";
    case TauRule::list: break;
  }
  return "list";
}

TauRule tau_rule(std::string_view text) {
  for (const TauRule rule : {TauRule::octave, TauRule::decade, TauRule::all})
    if (text == name(rule)) return rule;
  return TauRule::list;
}

std::vector<std::uint64_t> parse_tau_list(std::string_view text, std::string& why) {
  std::vector<std::uint64_t> m;
  for (std::size_t begin = 0; begin <= text.size();) {
    const std::size_t comma = std::min(text.find(',', begin), text.size());
    const std::string_view item = text.substr(begin, comma - begin);
    begin = comma + 1;
    if (item.empty() && comma == text.size()) break;  // a trailing comma ends the list, as getline splits it
    std::uint64_t v = 0;
    const auto [end, ec] = std::from_chars(item.data(), item.data() + item.size(), v);
    if (ec != std::errc() || end != item.data() + item.size() || v == 0) {
      why.assign(1, '\'').append(item).append("' is not octave, decade, all or a positive averaging factor");
      return {};
    }
    if (!m.empty() && v <= m.back()) {
      why = "averaging factors must increase";
      return {};
    }
    m.push_back(v);
  }
  if (m.empty()) why = "empty list";
  return m;
}

std::optional<StrideFactor> StrideFactor::parse(std::string_view text) {
  if (text == "full") return full();
  std::uint32_t s = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), s);
  if (ec != std::errc() || end != text.data() + text.size() || !valid_stride_factor(s)) return std::nullopt;
  return StrideFactor(s);
}

TauPlan plan_taus(AnalysisOptions& o, TauRule rule, StrideFactor stride, const std::vector<std::uint64_t>& listed,
                  std::uint64_t n_phase, std::uint64_t budget) {
  TauPlan plan;
  o.stride_factor = stride.requested();
  // Counts of a known length under full hold their record and take the batch kernel (the same
  // sums as the characterizer's, at 4 bytes a point instead of its history near N/4) while the
  // record fits in memory at its worst (12 bytes a point while it widens to int64).
  o.hold_counts = o.type == DataType::counts && stride.is_full() && n_phase > 0 && o.values_hint < budget / 12;
  // Phase and frequency of a known length (any tau rule) hold the staged points (8 bytes a point)
  // and sum the taus over them (phase_batch_taus(), float_batch.hpp): O(N) per tau where the
  // characterizer visits every tau at every point. Under full, or under a stride factor of at
  // least N/8, whose pyramid would hold more than the record (3S points of 24 bytes and more);
  // a smaller one keeps the characterizer's few MiB.
  const bool wide = stride.is_full() || (n_phase > 0 && stride.requested() >= n_phase / 8);
  o.hold_phase = o.type != DataType::counts && wide && (rule == TauRule::all || n_phase > 0) && o.values_hint < budget / 24;
  o.hold_prefix_sums = o.hold_phase && rule == TauRule::all;
  plan.held = o.hold_counts || o.hold_phase;
  // "full" resolved, here only: every tau up to N/4 fully overlapped; for "all" every m up to N/2
  // (all of them). A held record has no history to bound S.
  if (stride.is_full()) o.stride_factor = full_stride_factor(rule == TauRule::all ? 2 * n_phase : n_phase, plan.held);
  const std::uint32_t s = o.stride_factor;
  plan.generated = rule != TauRule::list;
  o.m_list.clear();
  switch (rule) {
    case TauRule::octave: o.m_list = octave_taus(n_phase); break;
    case TauRule::decade:
      for (const std::uint64_t m : decade_taus(n_phase ? n_phase : std::uint64_t{1} << 40))
        (tau_representable(m, s) ? o.m_list : plan.not_formed).push_back(m);
      break;
    case TauRule::all: o.m_list = all_taus(n_phase, s); break;
    case TauRule::list: o.m_list = listed; break;
  }
  if (o.m_list.empty()) return plan;
  // Generated taus stop where their history would not fit in memory (a large S on standard
  // input); a list that does not fit is the caller's to refuse.
  while (!plan.held && plan.generated && o.m_list.size() > 1 && history_bytes(o.type, s, o.m_list.back()) > budget) {
    plan.cut_above = o.m_list.back();
    o.m_list.pop_back();
  }
  o.theo_m_list = theo_taus(name(rule), o.m_list, n_phase);
  return plan;
}

TauPlan plan_taus(AnalysisOptions& o, const std::string& taus, const std::vector<std::uint64_t>& listed,
                  std::uint64_t n_phase, std::uint64_t budget) {
  return plan_taus(o, tau_rule(taus), StrideFactor::of(o.stride_factor), listed, n_phase, budget);
}

std::vector<std::uint64_t> plan_window_taus(AnalysisOptions& o, TauRule rule, StrideFactor stride,
                                            const std::vector<std::uint64_t>& listed, std::uint64_t window,
                                            std::uint64_t window_phase) {
  std::vector<std::uint64_t> m_list;
  switch (rule) {
    case TauRule::octave: m_list = octave_taus(window_phase); break;
    case TauRule::decade: m_list = decade_taus(window_phase); break;
    case TauRule::all:  // "full" here: every m up to half the window's phase points, at most full_stride_cap
      m_list = all_taus(window_phase, resolve_stride_factor(stride.requested(), window_phase / 2));
      break;
    case TauRule::list: m_list = listed; break;
  }
  o.m_list = window_taus(m_list, window);
  // "full" for the taus kept: every one of them fully overlapped, at most full_stride_cap.
  if (!o.m_list.empty()) o.stride_factor = resolve_stride_factor(stride.requested(), o.m_list.back());
  return o.m_list;
}

}  // namespace gyrochar
