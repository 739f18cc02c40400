#include "plan.hpp"

#include <fmt/format.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>

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
  if (getrlimit(RLIMIT_AS, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY) budget = std::min<std::uint64_t>(budget, limit.rlim_cur / 2);
  return budget;
}

std::string memory_budget_reason() {
  rlimit limit{};
  if (getrlimit(RLIMIT_AS, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY && limit.rlim_cur / 2 < machine_budget())
    return fmt::format("half of its address-space limit, ulimit -v {} KiB", limit.rlim_cur >> 10);
  return "half of the machine's memory";
}

TauPlan plan_taus(AnalysisOptions& o, const std::string& taus, const std::vector<std::uint64_t>& listed,
                  std::uint64_t n_phase, std::uint64_t budget) {
  TauPlan plan;
  // Counts of a known length under full hold their record and take the batch kernel (the same
  // sums as the characterizer's, at 4 bytes a point instead of its history near N/4) while the
  // record fits in memory at its worst (12 bytes a point while it widens to int64).
  o.hold_counts = o.type == DataType::counts && o.stride_factor == 0 && n_phase > 0 && o.values_hint < budget / 12;
  // Phase and frequency of a known length (any tau rule) hold the staged points (8 bytes a point)
  // and sum the taus over them (phase_batch_taus(), float_batch.hpp): O(N) per tau where the
  // characterizer visits every tau at every point. Under full, or under a stride factor of at
  // least N/8, whose pyramid would hold more than the record (3S points of 24 bytes and more);
  // a smaller one keeps the characterizer's few MiB.
  const bool wide = o.stride_factor == 0 || (n_phase > 0 && o.stride_factor >= n_phase / 8);
  o.hold_phase = o.type != DataType::counts && wide && (taus == "all" || n_phase > 0) && o.values_hint < budget / 24;
  o.hold_prefix_sums = o.hold_phase && taus == "all";
  plan.held = o.hold_counts || o.hold_phase;
  // full: every tau up to N/4 fully overlapped; for "all" every m up to N/2 (all of them).
  if (o.stride_factor == 0) o.stride_factor = full_stride_factor(taus == "all" ? 2 * n_phase : n_phase);
  const std::uint32_t s = o.stride_factor;
  plan.generated = taus == "octave" || taus == "decade" || taus == "all";
  o.m_list.clear();
  if (taus == "octave") {
    o.m_list = octave_taus(n_phase);
  } else if (taus == "decade") {
    for (const std::uint64_t m : decade_taus(n_phase ? n_phase : std::uint64_t{1} << 40))
      (tau_representable(m, s) ? o.m_list : plan.not_formed).push_back(m);
  } else if (taus == "all") {
    o.m_list = all_taus(n_phase, s);
  } else {
    o.m_list = listed;
  }
  if (o.m_list.empty()) return plan;
  // Generated taus stop where their history would not fit in memory (a large S on standard
  // input); a list that does not fit is the caller's to refuse.
  while (!plan.held && plan.generated && o.m_list.size() > 1 && history_bytes(o.type, s, o.m_list.back()) > budget) {
    plan.cut_above = o.m_list.back();
    o.m_list.pop_back();
  }
  o.theo_m_list = theo_taus(plan.generated ? taus : "list", o.m_list, n_phase);
  return plan;
}

}  // namespace gyrochar
