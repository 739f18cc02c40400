#pragma once
// What the log-log panels of gyrochar-decode's plot and gyrochar-analyze's --plot share: the
// palette, text sizes and glyphs, the frame with its grid, the points with their confidence
// intervals as error bars, lines, and the legend outside the frame on the right. Drawn with PLplot
// through figure.hpp.
#include <cstddef>
#include <string>
#include <vector>

#include "confidence.hpp"
#include "figure.hpp"

namespace gyrochar {

/// Colour map 0 of the deviation panels (deviation_palette()); index 0 is the background.
enum PlotColour : int {
  background_colour,
  ink_colour,  // axes, text, read-off points
  adev_colour,
  mdev_colour,
  q_colour,
  n_colour,
  b_colour,
  k_colour,
  r_colour,
  sum_colour,  // the fitted model's sum
  grid_colour,
  truth_colour,     // the simulated (true) model
  markov_colour,    // Gauss-Markov terms
  sinusoid_colour,  // sinusoids, the PSD's peaks
  filter_colour,    // the sensor's own filter
  psd_colour,
  band_colour,  // the PSD's confidence band
};
/// The colours of PlotColour, in order.
Palette deviation_palette();
/// The colour of IEEE-952 term k (Q, N, B, K, R).
PlotColour term_colour(std::size_t k);

// Character heights relative to PLplot's default, and the glyphs (UTF-8, drawn by cairo).
inline constexpr double plot_text_scale = 0.55, plot_glyph_scale = 0.4, plot_label_scale = 0.45;
inline constexpr const char* adev_glyph = "●";
inline constexpr const char* mdev_glyph = "■";
inline constexpr const char* read_off_glyph = "◆";
inline constexpr const char* peak_glyph = "▼";

/// A deviation at a tau (any unit) with its interval (invalid: no error bar).
struct DevPoint {
  double tau_s = 0.0, dev = 0.0;
  Interval ci;
};

/// The viewport that leaves the right side to the legend, the window on log10 x and log10 y (y
/// linear when log_y is false), the grid, the axes and the labels. `title` above the frame.
void draw_log_frame(plstream& pls, double log_x_lo, double log_x_hi, double log_y_lo, double log_y_hi,
                    const std::string& x_label, const std::string& y_label, const std::string& title, bool log_y = true);
/// The points with a positive deviation as `glyph`, their intervals as error bars. O(points).
void draw_points(plstream& pls, const std::vector<DevPoint>& points, int colour, const char* glyph);
/// A line through (x, y) with y > 0, on log axes; style 1 solid, 2 short dashes, 3 long dashes.
void draw_log_line(plstream& pls, const std::vector<double>& x, const std::vector<double>& y, int colour, int style,
                   double width);
/// A marker with its label beside it (left of it near the right edge of the frame).
void draw_labelled_marker(plstream& pls, double x, double y, const char* glyph, const std::string& label, int colour,
                          double log_x_lo, double log_x_hi);

/// The legend's entries in drawing order; draw() puts it outside the frame, on the right.
class PlotLegend {
 public:
  void symbol(const std::string& text, int colour, const char* glyph);
  void line(const std::string& text, int colour, int style);
  void note(const std::string& text);  // text without a symbol
  void draw(plstream& pls) const;

 private:
  struct Entry {
    std::string text;
    int option, colour, style;
    const char* glyph;
  };
  std::vector<Entry> entries_;
};

}  // namespace gyrochar
