#include "plot.hpp"

#include <fmt/format.h>
#include <plplot/plstream.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>

#include "deviation_plot.hpp"
#include "figure.hpp"
#include "heat_map.hpp"

namespace gyrochar::decoding {
namespace {

struct Range {
  double lo = INFINITY, hi = -INFINITY;
  void add(double v) {
    if (v > 0 && std::isfinite(v)) lo = std::min(lo, v), hi = std::max(hi, v);
  }
};

void draw_panel(plstream& pls, const NodePlot& p, double confidence) {
  pls.adv(0);
  pls.col0(ink_colour);
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
  draw_log_frame(pls, x_lo, x_hi, y_lo, y_hi, "averaging time #gt [s]",
                 fmt::format("ADEV, MDEV [{}], error bars: {:.1f}% confidence", p.rate_name, 100.0 * confidence), p.title);

  PlotLegend legend;  // entries in drawing order
  legend.symbol("ADEV (overlapping)", adev_colour, adev_glyph);
  legend.symbol("MDEV", mdev_colour, mdev_glyph);
  const auto draw_line = [&](const PlotLine& line, int colour, int style, double width) {
    draw_log_line(pls, line.tau_s, line.dev, colour, style, width);
    legend.line(line.label, colour, style);
  };
  for (const PlotLine& line : p.terms) {
    const bool sum = !line.term && !line.markov;
    const PlotColour colour = sum           ? sum_colour
                              : line.markov ? markov_colour
                                            : term_colour(static_cast<std::size_t>(*line.term));
    draw_line(line, colour, sum ? 1 : 2, sum ? 2.0 : 1.5);
  }
  if (p.truth) draw_line(*p.truth, truth_colour, 3, 2.0);  // long dashes: told apart from the terms'
  draw_points(pls, p.adev, adev_colour, adev_glyph);
  draw_points(pls, p.mdev, mdev_colour, mdev_glyph);
  if (!p.read_offs.empty()) {
    for (const ReadOffPoint& r : p.read_offs)
      draw_labelled_marker(pls, std::log10(r.tau_s), std::log10(r.dev), read_off_glyph, r.label, ink_colour, x_lo, x_hi);
    legend.symbol("read-off points", ink_colour, read_off_glyph);
  }
  for (const std::string& note : p.notes) legend.note(note);  // text only: what the fit says
  legend.draw(pls);
}

}  // namespace

bool write_plot(const std::string& prefix, const std::vector<NodePlot>& panels, double confidence, std::string& why) {
  // Each node's panel, then beside it the heat map of its dynamic Allan deviation when it has one.
  std::vector<std::pair<const NodePlot*, bool>> order;  // (node, heat map?)
  for (const NodePlot& p : panels) {
    order.emplace_back(&p, false);
    if (p.dynamic) order.emplace_back(&p, true);
  }
  return write_figure(
      prefix, order.size(), deviation_palette(), 1500, 900,
      [&](plstream& pls, std::size_t k) {
        pls.schr(0, plot_text_scale);
        if (order[k].second) draw_heat_map(pls, *order[k].first->dynamic);
        else draw_panel(pls, *order[k].first, confidence);
      },
      why);
}

}  // namespace gyrochar::decoding
