#include "live_view.hpp"

#include <fmt/format.h>

#include <nlohmann/json.hpp>
#include <string>

#include "confidence.hpp"

namespace gyrochar {
namespace {

constexpr const char* ieee_names[] = {"Q", "N", "B", "K", "R"};
constexpr const char* ieee_units[] = {"arcsec", "deg/sqrt(h)", "deg/h", "deg/h/sqrt(h)", "deg/h/h"};
constexpr double ieee_factors[] = {1.0, 1.0 / 60.0, 1.0, 60.0, 3600.0};  // from arcsec and s

const char* unit_name(const NodeView& v) {
  return v.scale && v.scale->angle_unit == protocol::AngleUnit::arcsec ? "deg/h" : "unit/s";
}

}  // namespace

void print_view(std::FILE* out, const Decoder& decoder, double t_s, bool clear) {
  if (clear) std::fprintf(out, "\033[H\033[J");
  std::fprintf(out, "gyrochar live view   t = %.1f s (%.2f h)\n", t_s, t_s / 3600.0);
  for (const auto& [address, v] : decoder.nodes()) {
    const LinkHealth& h = v.health;
    std::fprintf(out, "\nnode 0x%02X  %s  reports %llu complete, %llu incomplete, %llu lost; frames missing %llu; "
                 "restarts %llu; offline %llu; duplicates %llu\n",
                 address, v.online ? "online " : "OFFLINE", static_cast<unsigned long long>(h.reports_complete),
                 static_cast<unsigned long long>(h.reports_incomplete), static_cast<unsigned long long>(h.reports_lost),
                 static_cast<unsigned long long>(h.frames_missing), static_cast<unsigned long long>(h.restarts),
                 static_cast<unsigned long long>(h.offline_events), static_cast<unsigned long long>(h.duplicates));
    if (v.scale && v.scale->angle_unit != protocol::AngleUnit::arcsec)
      std::fprintf(out, "  deviations in %s per second (the node's unit)\n", protocol::name(v.scale->angle_unit));
    std::fprintf(out, "  %10s %13s %30s %12s %9s  %s\n", "tau [s]", fmt::format("ADEV [{}]", unit_name(v)).c_str(),
                 fmt::format("MDEV [{}] (68% CI)", unit_name(v)).c_str(), "n", "edf", "noise");
    for (std::size_t i = 0; i < v.status.tau_count && i < v.taus.size(); ++i) {
      const TauView& t = v.taus[i];
      if (!t.adev.received || !t.adev.valid) continue;
      const Interval ci = confidence_interval(t.mdev.dev, t.mdev.edf);
      const std::string mdev = !t.mdev.valid ? "-"
                               : ci.valid   ? fmt::format("{:.4g} [{:.3g}, {:.3g}]", t.mdev.dev, ci.low, ci.high)
                                            : fmt::format("{:.4g}", t.mdev.dev);
      std::fprintf(out, "  %10.4g %13.4g %30s %12llu %9.3g  %s\n", v.tau_s(i), t.adev.dev, mdev.c_str(),
                   static_cast<unsigned long long>(t.n), t.mdev.edf, protocol::name(t.mdev.noise));
    }
    std::fprintf(out, "  IEEE-952:");
    for (std::size_t k = 0; k < 5; ++k) {
      const Ieee952View& p = v.ieee952[k];
      if (p.received && p.resolved)
        std::fprintf(out, "  %s %.3g %s (+-%.0f%%)", ieee_names[k], p.value * ieee_factors[k], ieee_units[k],
                     100 * p.rel_uncertainty);
      else if (p.received)
        std::fprintf(out, "  %s not resolved", ieee_names[k]);
    }
    std::fprintf(out, "\n");
  }
  std::fflush(out);
}

void write_csv_header(std::FILE* out) {
  std::fprintf(out, "time_s,node,seq,tau_index,tau_s,m,n,adev,mdev,mdev_ci_low,mdev_ci_high,edf_adev,edf_mdev,noise\n");
}

void write_csv_rows(std::FILE* out, const NodeView& v, std::uint8_t seq, double t_s) {
  for (std::size_t i = 0; i < v.status.tau_count && i < v.taus.size(); ++i) {
    const TauView& tv = v.taus[i];
    if (!tv.adev.valid && !tv.mdev.valid) continue;
    const Interval ci = confidence_interval(tv.mdev.dev, tv.mdev.edf);
    std::fprintf(out, "%.6f,%u,%u,%zu,%.6g,%llu,%llu,%.7e,%.7e,%s,%s,%.4g,%.4g,%s\n", t_s, v.address, seq, i,
                 v.tau_s(i), static_cast<unsigned long long>(tv.m), static_cast<unsigned long long>(tv.n),
                 static_cast<double>(tv.adev.dev), static_cast<double>(tv.mdev.dev),
                 ci.valid ? fmt::format("{:.7e}", ci.low).c_str() : "", ci.valid ? fmt::format("{:.7e}", ci.high).c_str() : "",
                 tv.adev.edf, tv.mdev.edf, protocol::name(tv.mdev.noise));
  }
}

void write_json_line(std::FILE* out, const NodeView& v, std::uint8_t seq, double t_s) {
  nlohmann::json j = {{"time_s", t_s}, {"node", v.address}, {"seq", seq}, {"session", v.session},
                      {"samples", v.status.sample_count},
                      {"health", {{"reports_complete", v.health.reports_complete},
                                  {"reports_incomplete", v.health.reports_incomplete},
                                  {"reports_lost", v.health.reports_lost},
                                  {"frames_missing", v.health.frames_missing},
                                  {"restarts", v.health.restarts}}}};
  j["taus"] = nlohmann::json::array();
  for (std::size_t i = 0; i < v.status.tau_count && i < v.taus.size(); ++i) {
    const TauView& tv = v.taus[i];
    j["taus"].push_back({{"index", i}, {"m", tv.m}, {"tau_s", v.tau_s(i)}, {"n", tv.n},
                         {"adev", tv.adev.dev}, {"adev_valid", tv.adev.valid}, {"edf_adev", tv.adev.edf},
                         {"mdev", tv.mdev.dev}, {"mdev_valid", tv.mdev.valid}, {"edf_mdev", tv.mdev.edf},
                         {"noise", protocol::name(tv.mdev.noise)}});
  }
  for (std::size_t k = 0; k < 5; ++k)
    if (v.ieee952[k].received)
      j["ieee952"][ieee_names[k]] = {{"value", v.ieee952[k].value}, {"resolved", v.ieee952[k].resolved},
                                     {"rel_uncertainty", v.ieee952[k].rel_uncertainty}};
  std::fprintf(out, "%s\n", j.dump().c_str());
}

}  // namespace gyrochar
