#include "verdict_output.hpp"

#include <fmt/format.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>

#include "units.hpp"

namespace gyrochar {
namespace {

std::string number(double v) { return std::isfinite(v) ? fmt::format("{}", v) : std::string(); }
std::string csv_number(double v) { return std::isnan(v) ? std::string() : fmt::format("{}", v); }

}  // namespace

std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string q = "\"";
  for (const char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

std::string decision_columns(const Limit& limit) {
  const std::string q = limit.quantity();
  return fmt::format(",{},{},{},{}", csv_field(q + " verdict"), csv_field(q + " estimate [" + limit.unit + "]"),
                     csv_field(q + " lower"), csv_field(q + " upper"));
}

std::string decision_fields(const Limit& limit, const Decision* d) {
  if (d == nullptr) return ",,,,";
  const auto v = [&](double x) { return d->estimate.usable ? number(x / limit.unit_si) : std::string(); };
  return fmt::format(",{},{},{},{}", name(d->verdict), v(d->estimate.value), v(d->estimate.low), v(d->estimate.high));
}

std::string summary_header(const std::vector<Limit>& limits) {
  std::string h = "source,node,run_s,samples,fit_status,chi2_per_dof";
  for (const auto& u : units::ieee952)
    h += fmt::format(",{}", csv_field(fmt::format("{} [{}]", u.letter, u.name))) +
         fmt::format(",{} u,{} status", u.letter, u.letter);
  h += ",verdict";
  for (const Limit& l : limits) h += decision_columns(l);
  return h;
}

std::string summary_row(const GyroSummary& g, const std::vector<Limit>& limits) {
  std::string r = fmt::format("{},{},{},{},{},{}", csv_field(g.source), csv_field(g.node), number(g.run_s), g.samples,
                              csv_field(g.fit_status), g.fit_status.empty() ? "" : number(g.chi2_per_dof));
  for (const SummaryTerm& t : g.terms)
    r += fmt::format(",{},{},{}", t.known ? number(t.value) : "", t.known ? number(t.uncertainty) : "", csv_field(t.status));
  r += fmt::format(",{}", g.decisions.empty() ? "" : name(overall(g.decisions)));
  for (std::size_t i = 0; i < limits.size(); ++i)
    r += decision_fields(limits[i], i < g.decisions.size() ? &g.decisions[i] : nullptr);
  return r;
}

bool summary_compatible(const std::string& path, const std::vector<Limit>& limits, std::string& why) {
  std::ifstream in(path);
  if (!in) return true;  // absent (or unreadable: opening it for appending says why)
  std::string first;
  if (!std::getline(in, first) || first.empty()) return true;
  if (first == summary_header(limits)) return true;
  why = "its header differs from this run's (other limits, or not a gyrochar summary): give another file";
  return false;
}

bool append_summary(const std::string& path, const std::vector<Limit>& limits, const std::vector<GyroSummary>& rows,
                    std::string& why) {
  std::FILE* f = std::fopen(path.c_str(), "a");
  if (f == nullptr) {
    why = std::strerror(errno);
    return false;
  }
  std::string text;
  if (std::ftell(f) == 0 || (std::fseek(f, 0, SEEK_END) == 0 && std::ftell(f) == 0)) text = summary_header(limits) + "\n";
  for (const GyroSummary& g : rows) text += summary_row(g, limits) + "\n";
  const bool written = std::fwrite(text.data(), 1, text.size(), f) == text.size();
  const int saved = errno;
  if (std::fclose(f) != 0 || !written) {
    why = fmt::format("write failed: {}", std::strerror(written ? errno : saved));
    return false;
  }
  return true;
}

std::string acceptance_table(const std::vector<Limit>& limits, const std::vector<Decision>& decisions) {
  std::string out = fmt::format(
      "\nAcceptance: {} (each bound one-sided {:g} %: pass when the upper bound is within the "
      "limit, fail when the lower bound is beyond it)\n",
      name(overall(decisions)), 100 * (1 + decision_confidence) / 2);
  out += fmt::format("  {:<14} {:>12} {:<14} {:>12} {:>12} {:>12}  {:<10} {}\n", "limit", "value", "unit", "estimate",
                     "lower", "upper", "verdict", "");
  for (std::size_t i = 0; i < limits.size(); ++i) {
    const Limit& l = limits[i];
    const Decision& d = decisions[i];
    const auto shown = [&](double v) { return d.estimate.usable ? fmt::format("{:.4g}", v / l.unit_si) : "-"; };
    std::string why = d.reason;
    if (d.verdict == Verdict::undecided && !std::isnan(d.decide_at_s))
      why += std::isinf(d.decide_at_s)
                 ? ": the estimate sits on the limit"
                 : fmt::format(": expected to decide at a run of {}", format_run_length(d.decide_at_s));
    out += fmt::format("  {:<14} {:>12.4g} {:<14} {:>12} {:>12} {:>12}  {:<10} {}\n", l.quantity(), l.value_si / l.unit_si,
                       l.unit, shown(d.estimate.value), shown(d.estimate.low), shown(d.estimate.high), name(d.verdict), why);
  }
  return out;
}

std::string acceptance_csv(const std::vector<Limit>& limits, const std::vector<Decision>& decisions) {
  std::string out = std::string("\n") + acceptance_csv_header + "\n";
  for (std::size_t i = 0; i < limits.size(); ++i) {
    const Limit& l = limits[i];
    const Decision& d = decisions[i];
    const auto v = [&](double x) { return d.estimate.usable ? csv_number(x / l.unit_si) : std::string(); };
    out += fmt::format("{},{},{},{},{},{},{},{},{}\n", csv_field(l.quantity()), csv_number(l.value_si / l.unit_si),
                       csv_field(l.unit), v(d.estimate.value), v(d.estimate.low), v(d.estimate.high), name(d.verdict),
                       csv_number(d.decide_at_s), csv_field(d.reason));
  }
  return out;
}

nlohmann::json acceptance_json(const std::vector<Limit>& limits, const std::vector<Decision>& decisions) {
  using nlohmann::json;
  json list = json::array();
  for (std::size_t i = 0; i < limits.size(); ++i) {
    const Limit& l = limits[i];
    const Decision& d = decisions[i];
    const auto v = [&](double x) { return d.estimate.usable ? json(x / l.unit_si) : json(nullptr); };
    list.push_back({{"quantity", l.quantity()},
                    {"limit", l.value_si / l.unit_si},
                    {"unit", l.unit},
                    {"line", l.line},
                    {"estimate", v(d.estimate.value)},
                    {"lower", v(d.estimate.low)},
                    {"upper", v(d.estimate.high)},
                    {"verdict", name(d.verdict)},
                    {"decides_at_s", std::isfinite(d.decide_at_s) ? json(d.decide_at_s) : json(nullptr)},
                    {"decides_never", std::isinf(d.decide_at_s)},
                    {"why", d.reason}});
    if (!d.estimate.kind.empty()) list.back()["estimate_kind"] = d.estimate.kind;  // a live node's verdict
  }
  return {{"confidence", decision_confidence},
          {"rule", "pass: upper bound within the limit; fail: lower bound beyond it; undecided otherwise"},
          {"verdict", name(overall(decisions))},
          {"limits", std::move(list)}};
}

}  // namespace gyrochar
