#pragma once
// The heat map of a dynamic Allan deviation (docs/dynamic.md): averaging time tau on a log axis
// against the time of the window, the deviation as colour (log scale, a perceptually uniform
// colour map, its bar beside). gyrochar-decode draws the board's windows live beside each node's
// curve; gyrochar-analyze --dynamic draws a file's, one panel per statistic.
#include <string>
#include <vector>

#include "figure.hpp"

namespace gyrochar {

struct HeatMap {
  std::string title;          // e.g. "node 0x10, session 0: ADEV per 600 s window"
  std::string value_name;     // what the colour is: "ADEV", "MDEV", ...
  std::string unit;           // its unit, e.g. "deg/h"
  std::vector<double> tau_s;  // the rows, increasing, > 0
  struct Column {
    double start_s = 0.0, end_s = 0.0;  // the cell's extent in time (s since the start of the run)
    std::vector<double> value;          // one per row; NaN or <= 0: no value (left blank)
  };
  std::vector<Column> columns;  // in time order
};

/// White background (index 0), black ink (1): colour map 0 of a heat map figure.
Palette heat_map_palette();

/// Draws `map` in the next subpage of `pls` (pls.adv(0) first), whose colour map 0 starts with
/// heat_map_palette()'s colours; sets colour map 1. A map without any value says so in its frame.
/// O(rows x columns) PLplot calls.
void draw_heat_map(plstream& pls, const HeatMap& map);

/// Writes `prefix`.svg and `prefix`.png with one panel per map (at least one), replacing the files
/// atomically (figure.hpp). False with `why` when a file cannot be written. Allocates.
bool write_heat_maps(const std::string& prefix, const std::vector<HeatMap>& maps, std::string& why);

}  // namespace gyrochar
