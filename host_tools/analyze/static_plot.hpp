#pragma once
// gyrochar-analyze --plot PREFIX for a whole record (not --dynamic): PREFIX.svg and PREFIX.png in
// the look of gyrochar-decode's plot (common/deviation_plot.hpp). Panels:
//   ADEV   the OADEV points with their confidence intervals (error bars); with an accepted
//          IEEE-952 fit, each term of the chosen model as its own line (Q, N with the sensor's
//          filter where the model has one, B, K, R, each Markov term, each sinusoid) and the
//          model's total, from the fit's exact expectations (fitted_variance()); the read-off
//          lines of slope -1/2 and +1/2 and the read-off points (N at 1 s, the floor, K at 3 s).
//   MDEV   the same for the modified Allan deviation.
//   PSD    the rate's Welch PSD with its confidence band, the local background of the sinusoid
//          search and the peaks found, and the white level 2 N^2 of the fitted N.
//   fit residuals  (with a fit) each point the fit used, (estimate - model) / its standard
//          deviation, against tau.
// A rejected fit draws no model and says so in the legend.
#include <string>

#include "analysis_report.hpp"

namespace gyrochar {

/// Writes `prefix`.svg and `prefix`.png for `report` (its fits, read-off and spectrum) and the
/// OADEV and MDEV rows in `curves` (engine units, as Analysis::rows; dense taus are thinned to
/// 100 a decade), replacing the files atomically (figure.hpp). False with `why` when a file cannot
/// be written. Allocates; O(rows + PSD bins + 600 model points per line).
bool write_static_plot(const std::string& prefix, const Report& report, const std::vector<AnalysisRow>& curves,
                       std::string& why);

}  // namespace gyrochar
