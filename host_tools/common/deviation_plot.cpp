#include "deviation_plot.hpp"

#include <plplot/plstream.h>

#include <array>
#include <cmath>

namespace gyrochar {

Palette deviation_palette() {
  return {
      {255, 255, 255},  // background: white
      {0, 0, 0},        // ink: black
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
      {188, 189, 34},   // Markov: olive
      {0, 128, 128},    // sinusoid: teal
      {127, 127, 200},  // filter: lavender
      {31, 119, 180},   // PSD: blue
      {174, 199, 232},  // PSD band: light blue
  };
}

PlotColour term_colour(std::size_t k) {
  static constexpr std::array<PlotColour, 5> colours{q_colour, n_colour, b_colour, k_colour, r_colour};
  return colours[k];
}

void draw_log_frame(plstream& pls, double log_x_lo, double log_x_hi, double log_y_lo, double log_y_hi,
                    const std::string& x_label, const std::string& y_label, const std::string& title, bool log_y) {
  pls.vpor(0.08, 0.60, 0.10, 0.92);  // the legend, outside on the right, gets the rest
  pls.wind(log_x_lo, log_x_hi, log_y_lo, log_y_hi);
  pls.col0(grid_colour);
  pls.width(0.5);
  pls.box("ghl", 0, 0, log_y ? "ghl" : "g", 0, 0);
  pls.col0(ink_colour);
  pls.width(1.0);
  pls.box("bcnlst", 0, 0, log_y ? "bcnlstv" : "bcnstv", 0, 0);
  pls.lab(x_label.c_str(), y_label.c_str(), title.c_str());
}

void draw_points(plstream& pls, const std::vector<DevPoint>& points, int colour, const char* glyph) {
  std::vector<PLFLT> x, y, ex, low, high;
  for (const DevPoint& p : points) {
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
  pls.schr(0, plot_glyph_scale);
  pls.string(static_cast<PLINT>(x.size()), x.data(), y.data(), glyph);
  pls.schr(0, plot_text_scale);
}

void draw_log_line(plstream& pls, const std::vector<double>& x, const std::vector<double>& y, int colour, int style,
                   double width) {
  std::vector<PLFLT> lx, ly;
  for (std::size_t k = 0; k < x.size() && k < y.size(); ++k) {
    if (!(y[k] > 0) || !(x[k] > 0)) continue;
    lx.push_back(std::log10(x[k]));
    ly.push_back(std::log10(y[k]));
  }
  pls.col0(colour);
  pls.lsty(style);
  pls.width(width);
  pls.line(static_cast<PLINT>(lx.size()), lx.data(), ly.data());
  pls.lsty(1);
}

void draw_labelled_marker(plstream& pls, double x, double y, const char* glyph, const std::string& label, int colour,
                          double log_x_lo, double log_x_hi) {
  pls.col0(colour);
  pls.schr(0, plot_glyph_scale);
  pls.string(1, &x, &y, glyph);
  pls.schr(0, plot_label_scale);
  const bool right = x < log_x_hi - 0.2 * (log_x_hi - log_x_lo);  // beside the marker, inside the frame
  pls.ptex(x + (right ? 0.015 : -0.015) * (log_x_hi - log_x_lo), y, 1, 0, right ? 0.0 : 1.0, label.c_str());
  pls.schr(0, plot_text_scale);
}

void PlotLegend::symbol(const std::string& text, int colour, const char* glyph) {
  entries_.push_back({text, PL_LEGEND_SYMBOL, colour, 1, glyph});
}
void PlotLegend::line(const std::string& text, int colour, int style) {
  entries_.push_back({text, PL_LEGEND_LINE, colour, style, ""});
}
void PlotLegend::note(const std::string& text) { entries_.push_back({text, PL_LEGEND_NONE, ink_colour, 1, ""}); }

void PlotLegend::draw(plstream& pls) const {
  const auto n = static_cast<PLINT>(entries_.size());
  std::vector<const char*> labels, glyphs;
  std::vector<PLINT> opts, colours, styles;
  for (const Entry& e : entries_) {
    labels.push_back(e.text.c_str());
    glyphs.push_back(e.glyph);
    opts.push_back(e.option);
    colours.push_back(e.colour);
    styles.push_back(e.style);
  }
  const std::vector<PLFLT> widths(entries_.size(), 1.5), scales(entries_.size(), 0.6 * plot_glyph_scale / plot_text_scale);
  const std::vector<PLINT> numbers(entries_.size(), 1), text_colours(entries_.size(), ink_colour);
  PLFLT legend_width = 0, legend_height = 0;
  pls.legend(&legend_width, &legend_height, PL_LEGEND_BACKGROUND | PL_LEGEND_BOUNDING_BOX,
             PL_POSITION_RIGHT | PL_POSITION_OUTSIDE, 0.02, 0.0, 0.06, background_colour, ink_colour, 1, 0, 0, n,
             opts.data(), 0.8, plot_text_scale, 2.0, 0.0, text_colours.data(), labels.data(), nullptr, nullptr, nullptr,
             nullptr, colours.data(), styles.data(), widths.data(), colours.data(), scales.data(), numbers.data(),
             glyphs.data());
}

}  // namespace gyrochar
