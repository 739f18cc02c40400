#pragma once
// Figures drawn with PLplot's cairo drivers (Debian plplot-driver-cairo): PREFIX.svg and
// PREFIX.png holding panels in a near-square grid, each file drawn to PREFIX.*.part and renamed,
// so that a viewer never sees a half-written figure. gyrochar-decode's plot and the heat maps of
// the dynamic Allan deviation (heat_map.hpp) are drawn through it.
#include <array>
#include <cstddef>
#include <functional>
#include <string>
#include <vector>

class plstream;

namespace gyrochar {

/// Colour map 0 of a figure, RGB 0..255: index 0 is the background, 1 the ink (axes, text).
using Palette = std::vector<std::array<int, 3>>;

/// Empty when PLplot has the svgcairo and pngcairo devices; otherwise why not. Call before
/// plotting: PLplot ends the process on a missing device instead of returning an error.
std::string plot_devices_missing();

/// Draws a panel that has nothing to show yet: its frame, `message` in the middle, `title` above.
void draw_empty_panel(plstream& pls, const std::string& title, const char* message);

/// Writes `prefix`.svg and `prefix`.png: `panels` (at least one) panels of panel_width x
/// panel_height pixels, panel k drawn by draw_panel(pls, k), which starts its panel with
/// pls.adv(0). Replaces the files atomically. Returns false and sets `why` when a file cannot be
/// written. Allocates; the cost is the panels'.
bool write_figure(const std::string& prefix, std::size_t panels, const Palette& palette, int panel_width, int panel_height,
                  const std::function<void(plstream&, std::size_t)>& draw_panel, std::string& why);

}  // namespace gyrochar
