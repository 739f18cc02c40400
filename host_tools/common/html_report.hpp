#pragma once
// The pieces of the self-contained HTML reports of gyrochar-analyze and gyrochar-decode
// (--report FILE.html): one file with inline CSS (print-friendly, @media print) and inline SVG
// log-log plots drawn here, no script and no external reference, so that it opens with no network
// and prints to PDF from any browser. Every number a table shows carries its exact value (shortest
// round trip, as the CSV writes it) in a data-value attribute, for machines and tests.
#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include "confidence.hpp"
#include "limits.hpp"

namespace gyrochar::html {

/// `text` with &, <, >, " and ' escaped, bytes below 0x20 (but tab and newline) as U+FFFD. O(n).
std::string escape(std::string_view text);

/// The software's name and version, e.g. "gyrochar 0.1.0". A static string.
const char* software_version();
/// The time now, "2026-11-28 06:02:09 UTC", for a report's provenance. O(1).
std::string utc_now();

/// A table cell: text for people, and (numbers) the exact value.
struct Cell {
  std::string text;
  std::string value;  // data-value attribute; empty: none
  std::string css;    // class attribute; empty: none
};
/// A number cell: text with 4 significant digits, data-value the shortest round trip; an empty
/// cell for NaN. O(1).
Cell number(double v);
/// A verdict cell, coloured by its class (pass, fail, undecided).
Cell verdict(Verdict v);

/// Points with confidence intervals (drawn as error bars) and lines, on log-log axes.
struct PlotPoint {
  double x = 0, y = 0;
  Interval ci;
};
struct PlotSeries {
  std::string name, colour;  // colour: a CSS colour, e.g. "#1f5fbf"
  bool square = false;       // squares, else circles
  std::vector<PlotPoint> points;
};
struct PlotLine {
  std::string name, colour;
  bool dashed = false;
  std::vector<double> x, y;
};
struct LogPlot {
  std::string title, x_label, y_label;
  std::vector<PlotSeries> series;
  std::vector<PlotLine> lines;
  /// Acceptance limits, drawn dashed in red with their label: at a tau (a short bar there) or, with
  /// tau 0, across the plot.
  struct LimitMark {
    double tau = 0, value = 0;
    std::string label;
  };
  std::vector<LimitMark> limits;
};
/// The plot as an <svg> element (no namespace URI: HTML5 inline SVG), with a decade grid and the
/// legend on the right; points and lines with a value <= 0 are left out. A plot with nothing to
/// draw shows "no data". O(points + line points).
std::string svg_log_plot(const LogPlot& plot);

/// The page under construction: sections of headings, paragraphs, key/value lists, tables, plots.
class Document {
 public:
  explicit Document(std::string title);
  void heading(std::string_view text, int level = 2, std::string_view id = {});
  void paragraph(std::string_view text, std::string_view css = {});
  /// A two-column list of facts (provenance): name, value.
  void facts(const std::vector<std::pair<std::string, std::string>>& rows, std::string_view id = {});
  /// A table with an id (for machines), a caption, a header row and cells.
  void table(std::string_view id, std::string_view caption, const std::vector<std::string>& header,
             const std::vector<std::vector<Cell>>& rows);
  /// Markup made elsewhere (svg_log_plot()); the caller escapes what it holds.
  void raw(std::string_view markup);
  /// The whole page. O(size).
  std::string finish() const;

 private:
  std::string title_, body_;
};

/// The acceptance verdicts under a heading of `level`: the overall verdict, the decision rule and
/// a table (id `id`), every value in the limit's own unit.
void verdict_section(Document& doc, const std::vector<Limit>& limits, const std::vector<Decision>& decisions,
                     const std::string& id = "verdicts", int level = 2);

/// Writes `text` to `path` through `path`.part and a rename (a reader never sees half a report).
/// False with `why` on failure. O(size).
bool write_file_atomically(const std::string& path, std::string_view text, std::string& why);

}  // namespace gyrochar::html
