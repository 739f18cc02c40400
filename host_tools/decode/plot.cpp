#include "plot.hpp"

#include <fmt/format.h>
#include <plplot/plstream.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>

#include "figure.hpp"
#include "heat_map.hpp"

namespace gyrochar::decoding {
namespace {

// Colour map 0 (index 0 is the background) and what each colour draws.
enum Colour : PLINT {
  background,
  ink,
  adev_colour,
  mdev_colour,
  q_colour,
  n_colour,
  b_colour,
  k_colour,
  r_colour,
  sum_colour,
  grid_colour,
  truth_colour
};
constexpr std::array<std::array<PLINT, 3>, 12> palette{{
    {255, 255, 255},  // background: white
    {0, 0, 0},        // axes, text, read-off points: black
    {31, 119, 180},   // ADEV: blue
    {214, 39, 40},    // MDEV: red
    {148, 103, 189},  // Q: purple
    {44, 160, 44},    // N: green
    {255, 127, 14},   // B: orange
    {140, 86, 75},    // K: brown
    {23, 190, 207},   // R: cyan
    {90, 90, 90},     // the model's sum: dark grey
    {215, 215, 215},  // grid: light grey
    {227, 119, 194},  // the simulated (true) model: pink
}};

// Character heights relative to PLplot's default.
constexpr PLFLT text_scale = 0.55, glyph_scale = 0.4, label_scale = 0.45;

// Glyphs (UTF-8, drawn by cairo with the system fonts).
constexpr const char* adev_glyph = "●";
constexpr const char* mdev_glyph = "■";
constexpr const char* read_off_glyph = "◆";

constexpr std::array<PLINT, 5> term_colours{q_colour, n_colour, b_colour, k_colour, r_colour};

struct Range {
  double lo = INFINITY, hi = -INFINITY;
  void add(double v) {
    if (v > 0 && std::isfinite(v)) lo = std::min(lo, v), hi = std::max(hi, v);
  }
};

void draw_series(plstream& pls, const std::vector<PlotPoint>& points, PLINT colour, const char* glyph) {
  std::vector<PLFLT> x, y, ex, low, high;
  for (const PlotPoint& p : points) {
    if (!(p.dev > 0)) continue;  // no place on a log axis
    x.push_back(std::log10(p.tau_s));
    y.push_back(std::log10(p.dev));
    if (p.ci.valid && p.ci.low > 0) {
      ex.push_back(x.back());
      low.push_back(std::log10(p.ci.low));
      high.push_back(std::log10(p.ci.high));
    }
  }
  pls.col0(colour);
  pls.width(1.2);
  pls.erry(static_cast<PLINT>(ex.size()), ex.data(), low.data(), high.data());
  pls.schr(0, glyph_scale);
  pls.string(static_cast<PLINT>(x.size()), x.data(), y.data(), glyph);
  pls.schr(0, text_scale);
}

void draw_panel(plstream& pls, const NodePlot& p, double confidence) {
  pls.adv(0);
  pls.col0(ink);
  Range y;
  for (const auto* series : {&p.adev, &p.mdev}) {
    for (const PlotPoint& q : *series) {
      y.add(q.dev);
      if (q.ci.valid) y.add(q.ci.low), y.add(q.ci.high);
    }
  }
  if (!(y.hi > 0)) return draw_empty_panel(pls, p.title, "no positive deviation with a known tau yet");
  const double y_lo = std::floor(std::log10(y.lo) - 0.05), y_hi = std::ceil(std::log10(y.hi) + 0.05);
  const double x_lo = std::log10(p.tau_min_s), x_hi = std::log10(p.tau_max_s);
  pls.vpor(0.08, 0.60, 0.10, 0.92);  // the legend, outside on the right, gets the rest
  pls.wind(x_lo, x_hi, y_lo, y_hi);
  pls.col0(grid_colour);
  pls.width(0.5);
  pls.box("ghl", 0, 0, "ghl", 0, 0);
  pls.col0(ink);
  pls.width(1.0);
  pls.box("bcnlst", 0, 0, "bcnlstv", 0, 0);
  pls.lab("averaging time #gt [s]",
          fmt::format("ADEV, MDEV [{}], error bars: {:.1f}% confidence", p.rate_name, 100.0 * confidence).c_str(),
          p.title.c_str());

  // Legend entries in drawing order.
  std::vector<std::string> text{"ADEV (overlapping)", "MDEV"};
  std::vector<PLINT> opts{PL_LEGEND_SYMBOL, PL_LEGEND_SYMBOL}, colours{adev_colour, mdev_colour}, styles{1, 1};
  std::vector<const char*> glyphs{adev_glyph, mdev_glyph};

  const auto draw_line = [&](const PlotLine& line, PLINT colour, PLINT style, PLFLT width) {
    std::vector<PLFLT> x, v;
    for (std::size_t k = 0; k < line.tau_s.size(); ++k) {
      if (!(line.dev[k] > 0)) continue;
      x.push_back(std::log10(line.tau_s[k]));
      v.push_back(std::log10(line.dev[k]));
    }
    pls.col0(colour);
    pls.lsty(style);
    pls.width(width);
    pls.line(static_cast<PLINT>(x.size()), x.data(), v.data());
    text.push_back(line.label);
    opts.push_back(PL_LEGEND_LINE);
    colours.push_back(colour);
    styles.push_back(style);
    glyphs.push_back("");
  };
  for (const PlotLine& line : p.terms) {
    const bool sum = !line.term;
    draw_line(line, sum ? sum_colour : term_colours[static_cast<std::size_t>(*line.term)], sum ? 1 : 2,
              sum ? 2.0 : 1.5);
  }
  if (p.truth) draw_line(*p.truth, truth_colour, 3, 2.0);  // long dashes: told apart from the terms'
  pls.lsty(1);
  draw_series(pls, p.adev, adev_colour, adev_glyph);
  draw_series(pls, p.mdev, mdev_colour, mdev_glyph);
  if (!p.read_offs.empty()) {
    pls.col0(ink);
    for (const ReadOffPoint& r : p.read_offs) {
      const PLFLT x = std::log10(r.tau_s), v = std::log10(r.dev);
      pls.schr(0, glyph_scale);
      pls.string(1, &x, &v, read_off_glyph);
      pls.schr(0, label_scale);
      const bool right = x < x_hi - 0.2 * (x_hi - x_lo);  // beside the marker, inside the frame
      pls.ptex(x + (right ? 0.015 : -0.015) * (x_hi - x_lo), v, 1, 0, right ? 0.0 : 1.0, r.label.c_str());
    }
    pls.schr(0, text_scale);
    text.push_back("read-off points");
    opts.push_back(PL_LEGEND_SYMBOL);
    colours.push_back(ink);
    styles.push_back(1);
    glyphs.push_back(read_off_glyph);
  }
  for (const std::string& note : p.notes) {  // text only: what the fit says
    text.push_back(note);
    opts.push_back(PL_LEGEND_NONE);
    colours.push_back(ink);
    styles.push_back(1);
    glyphs.push_back("");
  }

  const auto n = static_cast<PLINT>(text.size());
  std::vector<const char*> labels;
  for (const std::string& t : text) labels.push_back(t.c_str());
  const std::vector<PLFLT> widths(text.size(), 1.5), scales(text.size(), 0.6 * glyph_scale / text_scale);
  const std::vector<PLINT> numbers(text.size(), 1), text_colours(text.size(), ink);
  PLFLT legend_width = 0, legend_height = 0;
  pls.legend(&legend_width, &legend_height, PL_LEGEND_BACKGROUND | PL_LEGEND_BOUNDING_BOX,
             PL_POSITION_RIGHT | PL_POSITION_OUTSIDE, 0.02, 0.0, 0.06, background, ink, 1, 0, 0, n, opts.data(), 0.8,
             text_scale, 2.0, 0.0, text_colours.data(), labels.data(), nullptr, nullptr, nullptr, nullptr,
             colours.data(), styles.data(), widths.data(), colours.data(), scales.data(), numbers.data(),
             glyphs.data());
}

}  // namespace

bool write_plot(const std::string& prefix, const std::vector<NodePlot>& panels, double confidence, std::string& why) {
  // Each node's panel, then beside it the heat map of its dynamic Allan deviation when it has one.
  std::vector<std::pair<const NodePlot*, bool>> order;  // (node, heat map?)
  for (const NodePlot& p : panels) {
    order.emplace_back(&p, false);
    if (p.dynamic) order.emplace_back(&p, true);
  }
  Palette colours;
  for (const auto& rgb : palette) colours.push_back({rgb[0], rgb[1], rgb[2]});
  return write_figure(prefix, order.size(), colours, 1500, 900,
                      [&](plstream& pls, std::size_t k) {
                        pls.schr(0, text_scale);
                        if (order[k].second)
                          draw_heat_map(pls, *order[k].first->dynamic);
                        else
                          draw_panel(pls, *order[k].first, confidence);
                      },
                      why);
}

}  // namespace gyrochar::decoding
