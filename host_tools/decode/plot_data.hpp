#pragma once
// The series of gyrochar-decode's ADEV/MDEV plot, in display units, with the IEEE-952 model lines
// and the heat map of the node's window curves (plot.hpp draws them with PLplot; this part needs no
// plotting library).
#include <optional>
#include <string>
#include <vector>

#include "deviation_plot.hpp"
#include "heat_map.hpp"
#include "rows.hpp"

namespace gyrochar::decoding {

using PlotPoint = DevPoint;  // tau, deviation, interval (invalid: no error bar)
struct PlotLine {
  std::optional<protocol::Ieee952Term> term;  // the term drawn; empty: the model's sum or a Markov term
  bool markov = false;                        // a Markov term of the model (protocol version 4)
  std::string label;                          // e.g. "N 0.00212 deg/sqrt(h) (±13%)" (UTF-8)
  std::vector<double> tau_s, dev;             // log-spaced over the plot's tau range
};
struct ReadOffPoint {
  double tau_s = 0.0, dev = 0.0;
  std::string label;  // e.g. "N at 1 s"
};
struct NodePlot {
  std::string title;                  // "node 0x10, session 0"
  std::string rate_name;              // unit of every deviation
  std::vector<PlotPoint> adev, mdev;  // valid values with a known tau
  std::vector<PlotLine> terms;        // resolved IEEE-952 terms, resolved Markov terms (version 4),
                                      // then the fitted model ("sum")
  std::optional<PlotLine> truth;      // the true model (simulation), drawn dashed beside the fit
  std::vector<std::string> notes;     // legend lines without a symbol: the fit rejected, short taus
                                      // left out (quantization not white), no fit
  std::vector<ReadOffPoint> read_offs;
  double tau_min_s = 0.0, tau_max_s = 0.0;  // the tau axis: the points' range widened by 2 on each
                                            // side (0, 0 when there are no points)
  std::optional<HeatMap> dynamic;           // the window curves' ADEV (protocol version 3): a node
                                            // with window taus has one, empty until a window comes
};

/// The plot of one node. Each resolved IEEE-952 term is drawn as the ADEV of its own AVAR term
/// (design brief section 3): Q sqrt(3)/tau, N/sqrt(tau), sqrt(2 ln2/pi) B, K sqrt(tau/3),
/// R tau/sqrt(2), and read off where the term equals its parameter: Q at tau = sqrt(3) s, N at 1 s,
/// K at 3 s, R at sqrt(2) s, and B as the floor 0.664 B at the minimum of the model's sum within
/// the points' taus. The sum is the fitted model: every fitted term, resolved or not, and Q at
/// pulse weight / sqrt(12) where the node held it there (quantization not white). A fit the node
/// rejected, or could not make, draws no model line and says so in `notes`. With `truth` (SI), its
/// model is drawn too (`truth`, the same closed form). From protocol version 4 the sum is the exact
/// sampled AVAR of the whole model (core's fitted_variance(): Markov terms, the sensor's filter,
/// sinusoids) when it has such terms, each resolved Markov term gets its own line, and while the
/// fit's model pages are pending or lost no model is drawn (a note says so). Lines span the tau axis; read-off points
/// outside it are left out. A node with window taus also gets the heat map of its windows' ADEV
/// (`dynamic`: one column per window, placed at its samples times tau0). O(taus + line points +
/// windows x window taus); allocates.
NodePlot plot_data(const NodeView& node, const DisplayRate& rate, ConfidenceIntervals& intervals,
                   const TrueTerms* truth = nullptr);

}  // namespace gyrochar::decoding
