#include "dynamic.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <iterator>
#include <stdexcept>

namespace gyrochar {

std::vector<std::uint64_t> window_taus(const std::vector<std::uint64_t>& m_list, std::uint64_t window_values) {
  std::vector<std::uint64_t> m;
  for (const std::uint64_t v : m_list)
    if (v <= window_values / 4) m.push_back(v);
  return m;
}

DynamicAnalyzer::DynamicAnalyzer(const AnalysisOptions& options, std::uint64_t window, std::uint64_t step)
    : options_(options), window_(window), step_(step) {
  if (window == 0 || step == 0) throw std::invalid_argument("a window and a step of at least one value");
  Analyzer check(options_);  // the options' problems now, not at the first value
}

void DynamicAnalyzer::add(std::span<const double> values) {
  for (std::size_t done = 0; done < values.size();) {
    if (values_ == next_index_ * step_) open_.push_back({next_index_++, 0, std::make_unique<Analyzer>(options_)});
    // A piece that ends where the next window starts or the oldest one completes.
    std::uint64_t piece = std::min<std::uint64_t>(values.size() - done, next_index_ * step_ - values_);
    piece = std::min(piece, window_ - open_.front().added);
    const auto part = values.subspan(done, static_cast<std::size_t>(piece));
    for (Open& w : open_) {
      try {
        w.analyzer->add(part);
      } catch (const BadValue& e) {
        throw BadValue(done + e.index(), e.what());
      }
      w.added += piece;
    }
    values_ += piece;
    done += static_cast<std::size_t>(piece);
    if (open_.front().added == window_) {
      const Open& w = open_.front();
      completed_.push_back({w.index, w.index * step_, w.analyzer->result()});
      open_.pop_front();
    }
  }
}

std::vector<WindowAnalysis> DynamicAnalyzer::take_completed() { return std::exchange(completed_, {}); }

// ---------------------------------------------------------------------------------------------
// Outputs

double window_start_s(const DynamicReport& r, const WindowAnalysis& w) {
  return static_cast<double>(w.first_value) * r.tau0_s;
}

double window_end_s(const DynamicReport& r, const WindowAnalysis& w) {
  const std::uint64_t last = w.first_value + r.window - (r.type == DataType::phase ? 1 : 0);
  return static_cast<double>(last) * r.tau0_s;
}

namespace {

std::string upper(const char* s) {
  std::string u(s);
  for (char& c : u) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return u;
}

// The taus of the windows' rows of statistic s (the same in every window: they share the length).
std::vector<const AnalysisRow*> rows_of(const WindowAnalysis& w, DevStat s) {
  std::vector<const AnalysisRow*> rows;
  for (const AnalysisRow& row : w.analysis.rows)
    if (row.stat == s) rows.push_back(&row);
  return rows;
}

}  // namespace

std::string format_dynamic_table(const DynamicReport& r) {
  std::string out;
  auto to = std::back_inserter(out);
  fmt::format_to(to,
                 "# {} data: {}; {} values, tau0 = {} s; dynamic: windows of {} values ({} s) every {} values ({} s), "
                 "{} complete\n",
                 name(r.type), r.units.input, r.values, r.tau0_s, r.window, static_cast<double>(r.window) * r.tau0_s, r.step,
                 static_cast<double>(r.step) * r.tau0_s, r.windows.size());
  if (r.windows.empty()) return out;
  const double k = r.units.factor();
  for (const DevStat s : r.stats) {
    const std::vector<const AnalysisRow*> taus = rows_of(r.windows.front(), s);
    fmt::format_to(to, "# {} in {} per window (rows) and tau (columns, s)\n{:>12} {:>12}", upper(name(s)), r.units.unit(s),
                   "start [s]", "end [s]");
    for (const AnalysisRow* row : taus) fmt::format_to(to, " {:>11.5g}", row->tau_s);
    out += '\n';
    for (const WindowAnalysis& w : r.windows) {
      fmt::format_to(to, "{:>12.6g} {:>12.6g}", window_start_s(r, w), window_end_s(r, w));
      for (const AnalysisRow* row : rows_of(w, s)) fmt::format_to(to, " {:>11.4e}", row->dev * k);
      out += '\n';
    }
  }
  return out;
}

std::string format_dynamic_csv(const DynamicReport& r) {
  std::string out = std::string("window,start,end,") + csv_header + "\n";
  for (const WindowAnalysis& w : r.windows) {
    const std::string where = fmt::format("{},{},{},", w.index, window_start_s(r, w), window_end_s(r, w));
    for (const AnalysisRow& row : w.analysis.rows) out += where + csv_fields(row, r.units) + "\n";
  }
  return out;
}

nlohmann::json dynamic_to_json(const DynamicReport& r) {
  using nlohmann::json;
  json windows = json::array();
  for (const WindowAnalysis& w : r.windows) {
    json rows = json::array();
    for (const AnalysisRow& row : w.analysis.rows) rows.push_back(row_json(row, r.units));
    windows.push_back({{"index", w.index},
                       {"start", window_start_s(r, w)},
                       {"end", window_end_s(r, w)},
                       {"stride_factor", w.analysis.stride_factor},
                       {"results", std::move(rows)}});
  }
  return {{"tau0", r.tau0_s},
          {"type", name(r.type)},
          {"units", units_json(r.units)},
          {"confidence", r.confidence},
          {"dynamic",
           {{"window", r.window},
            {"step", r.step},
            {"window_s", static_cast<double>(r.window) * r.tau0_s},
            {"step_s", static_cast<double>(r.step) * r.tau0_s},
            {"values", r.values}}},
          {"windows", std::move(windows)}};
}

std::vector<HeatMap> dynamic_heat_maps(const DynamicReport& r) {
  std::vector<HeatMap> maps;
  const double k = r.units.factor(), half_step_s = 0.5 * static_cast<double>(r.step) * r.tau0_s;
  for (const DevStat s : r.stats) {
    HeatMap h;
    h.title = fmt::format("dynamic {}: windows of {:.4g} s every {:.4g} s", upper(name(s)),
                          static_cast<double>(r.window) * r.tau0_s, static_cast<double>(r.step) * r.tau0_s);
    h.value_name = upper(name(s));
    h.unit = r.units.unit(s);
    if (!r.windows.empty())
      for (const AnalysisRow* row : rows_of(r.windows.front(), s)) h.tau_s.push_back(row->tau_s);
    for (const WindowAnalysis& w : r.windows) {
      const double centre = 0.5 * (window_start_s(r, w) + window_end_s(r, w));
      HeatMap::Column c{centre - half_step_s, centre + half_step_s, std::vector<double>(h.tau_s.size(), NAN)};
      for (const AnalysisRow* row : rows_of(w, s)) {  // a tau without a row (no term) stays blank
        const auto at = std::find(h.tau_s.begin(), h.tau_s.end(), row->tau_s);
        if (at != h.tau_s.end()) c.value[static_cast<std::size_t>(at - h.tau_s.begin())] = row->dev * k;
      }
      h.columns.push_back(std::move(c));
    }
    maps.push_back(std::move(h));
  }
  return maps;
}

}  // namespace gyrochar
