#pragma once
// The ADEV/MDEV plot of gyrochar-decode, drawn with PLplot's cairo drivers (Debian
// plplot-driver-cairo): one log-log panel per node with both deviations and their confidence
// intervals as error bars, each resolved IEEE-952 term as its own line, the model's sum, the
// read-off points, the simulated model where known (dashed), and in the legend what the node's fit
// says: rejected (no model drawn), short taus left out (plot_data.hpp); beside it, for a node
// with window curves, the heat map of its dynamic Allan deviation (heat_map.hpp).
#include <string>
#include <vector>

#include "figure.hpp"
#include "plot_data.hpp"

namespace gyrochar::decoding {

using gyrochar::plot_devices_missing;

/// Writes `prefix`.svg and `prefix`.png, one panel per element of `panels` (at least one) and one
/// more for each heat map, replacing the files atomically (drawn to `prefix`.*.part, then renamed). `confidence` is the level of
/// the error bars, for the caption. Returns false and sets `why` when a file cannot be written.
/// Allocates; O(points) per panel.
bool write_plot(const std::string& prefix, const std::vector<NodePlot>& panels, double confidence, std::string& why);

}  // namespace gyrochar::decoding
