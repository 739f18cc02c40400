#include "heat_map.hpp"

#include <fmt/format.h>
#include <plplot/plstream.h>

#include <algorithm>
#include <array>
#include <cmath>

namespace gyrochar {
namespace {

enum Colour : PLINT { ink = 1 };  // colour map 0: heat_map_palette()

// Character heights relative to PLplot's default, as gyrochar-decode's curve panels.
constexpr PLFLT text_scale = 0.55;

// Viridis (perceptually uniform, readable in grey and by the colour-blind): five control points,
// linear in RGB between them.
constexpr std::array<PLFLT, 5> at{0.0, 0.25, 0.5, 0.75, 1.0};
constexpr std::array<PLFLT, 5> red{68 / 255.0, 59 / 255.0, 33 / 255.0, 94 / 255.0, 253 / 255.0};
constexpr std::array<PLFLT, 5> green{1 / 255.0, 82 / 255.0, 145 / 255.0, 201 / 255.0, 231 / 255.0};
constexpr std::array<PLFLT, 5> blue{84 / 255.0, 139 / 255.0, 140 / 255.0, 98 / 255.0, 37 / 255.0};

struct TimeUnit {
  const char* name;
  double s;
};
// The unit the time axis reads best in, from the span it covers.
TimeUnit time_unit(double span_s) {
  if (span_s > 2 * 86400.0) return {"d", 86400.0};
  if (span_s > 2 * 3600.0) return {"h", 3600.0};
  if (span_s > 2 * 60.0) return {"min", 60.0};
  return {"s", 1.0};
}

bool has_value(double v) { return v > 0 && std::isfinite(v); }

}  // namespace

Palette heat_map_palette() { return {{255, 255, 255}, {0, 0, 0}}; }

void draw_heat_map(plstream& pls, const HeatMap& map) {
  pls.adv(0);
  pls.schr(0, text_scale);
  pls.col0(ink);
  double lo = INFINITY, hi = -INFINITY;
  for (const HeatMap::Column& c : map.columns)
    for (const double v : c.value)
      if (has_value(v)) lo = std::min(lo, std::log10(v)), hi = std::max(hi, std::log10(v));
  if (!(hi >= lo) || map.tau_s.empty()) return draw_empty_panel(pls, map.title, "no window completed yet");
  if (hi - lo < 1e-3) lo -= 0.05, hi += 0.05;  // a flat map still gets a colour scale

  // Rows: log tau, each cell reaching halfway to its neighbours (the outer ones as far out).
  const std::size_t rows = map.tau_s.size();
  std::vector<double> edge(rows + 1);  // log10 tau of the row boundaries
  for (std::size_t r = 1; r < rows; ++r) edge[r] = 0.5 * (std::log10(map.tau_s[r - 1]) + std::log10(map.tau_s[r]));
  edge[0] = rows > 1 ? 2 * std::log10(map.tau_s[0]) - edge[1] : std::log10(map.tau_s[0]) - 0.15;
  edge[rows] = rows > 1 ? 2 * std::log10(map.tau_s[rows - 1]) - edge[rows - 1] : std::log10(map.tau_s[0]) + 0.15;
  const double t_lo = map.columns.front().start_s, t_hi = map.columns.back().end_s;
  const TimeUnit unit = time_unit(t_hi - t_lo);

  pls.vpor(0.08, 0.80, 0.10, 0.92);  // the colour bar gets the right
  pls.wind(t_lo / unit.s, t_hi / unit.s, edge.front(), edge.back());
  pls.scmap1n(256);
  pls.scmap1l(true, static_cast<PLINT>(at.size()), at.data(), red.data(), green.data(), blue.data());
  for (const HeatMap::Column& c : map.columns) {
    for (std::size_t r = 0; r < rows && r < c.value.size(); ++r) {
      if (!has_value(c.value[r])) continue;  // blank: no estimate, or the frame never came
      pls.col1((std::log10(c.value[r]) - lo) / (hi - lo));
      const std::array<PLFLT, 4> x{c.start_s / unit.s, c.end_s / unit.s, c.end_s / unit.s, c.start_s / unit.s};
      const std::array<PLFLT, 4> y{edge[r], edge[r], edge[r + 1], edge[r + 1]};
      pls.fill(4, x.data(), y.data());
    }
  }
  pls.col0(ink);
  pls.width(1.0);
  pls.box("bcnst", 0, 0, "bcnlstv", 0, 0);
  pls.lab(fmt::format("time since the start of the run [{}]", unit.name).c_str(), "averaging time #gt [s]",
          map.title.c_str());

  // The colour bar beside the map: its own viewport, log10 of the value upwards.
  pls.vpor(0.84, 0.86, 0.10, 0.92);
  pls.wind(0, 1, lo, hi);
  constexpr int slices = 128;
  for (int k = 0; k < slices; ++k) {
    const double a = lo + (hi - lo) * k / slices, b = lo + (hi - lo) * (k + 1) / slices;
    pls.col1((k + 0.5) / slices);
    const std::array<PLFLT, 4> x{0, 1, 1, 0}, y{a, a, b, b};
    pls.fill(4, x.data(), y.data());
  }
  pls.col0(ink);
  pls.box("bc", 0, 0, "bcmstv", 0, 0);
  pls.mtex("r", 5.0, 0.5, 0.5, fmt::format("log#d10#u {} [{}]", map.value_name, map.unit).c_str());
}

bool write_heat_maps(const std::string& prefix, const std::vector<HeatMap>& maps, std::string& why) {
  return write_figure(
      prefix, maps.size(), heat_map_palette(), 1500, 900, [&](plstream& pls, std::size_t k) { draw_heat_map(pls, maps[k]); },
      why);
}

}  // namespace gyrochar
