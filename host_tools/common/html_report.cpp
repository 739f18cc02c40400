#include "html_report.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <limits>

#ifndef GYROCHAR_VERSION
#define GYROCHAR_VERSION "unknown"
#endif

namespace gyrochar::html {
namespace {

// Inline style: screen and print (A4/Letter, black on white, tables not split across pages).
constexpr const char* style = R"(
body { font-family: "DejaVu Sans", Arial, sans-serif; font-size: 13px; color: #111; background: #fff;
       max-width: 1100px; margin: 1em auto; padding: 0 1em; }
h1 { font-size: 20px; border-bottom: 2px solid #333; padding-bottom: 4px; }
h2 { font-size: 16px; margin-top: 1.4em; border-bottom: 1px solid #999; }
h3 { font-size: 14px; }
table { border-collapse: collapse; margin: 0.5em 0 1em 0; }
caption { text-align: left; font-weight: bold; padding: 2px 0; }
th, td { border: 1px solid #bbb; padding: 2px 6px; text-align: right; font-variant-numeric: tabular-nums; }
th { background: #eee; }
td.text, th.text { text-align: left; }
dl.facts { display: grid; grid-template-columns: max-content auto; gap: 2px 14px; }
dl.facts dt { font-weight: bold; }
dl.facts dd { margin: 0; }
td.pass { background: #d8f0d8; color: #0a5a0a; font-weight: bold; }
td.fail { background: #f6d3d3; color: #8a0b0b; font-weight: bold; }
td.undecided { background: #fbf0c8; color: #6a5200; font-weight: bold; }
p.overall { font-size: 15px; font-weight: bold; }
p.note { color: #444; }
svg.plot { border: 1px solid #ccc; margin: 0.3em 0.6em 0.6em 0; background: #fff; }
.plots { display: flex; flex-wrap: wrap; }
@media print {
  body { max-width: none; margin: 0; font-size: 10pt; }
  h2 { page-break-after: avoid; break-after: avoid; }
  table, svg.plot, dl.facts { page-break-inside: avoid; break-inside: avoid; }
  td.pass, td.fail, td.undecided, th { -webkit-print-color-adjust: exact; print-color-adjust: exact; }
  svg.plot { border: none; }
}
)";

std::string attr(std::string_view name, std::string_view value) {
  return value.empty() ? std::string() : fmt::format(" {}=\"{}\"", name, escape(value));
}

// The decade exponents that enclose [lo, hi] (both > 0).
std::pair<int, int> decades(double lo, double hi) {
  int a = static_cast<int>(std::floor(std::log10(lo)));
  int b = static_cast<int>(std::ceil(std::log10(hi)));
  if (b <= a) b = a + 1;
  return {a, b};
}

}  // namespace

std::string escape(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&#39;"; break;
      default:
        if (static_cast<unsigned char>(c) < 0x20 && c != '\n' && c != '\t') out += "\xef\xbf\xbd";
        else out += c;
    }
  }
  return out;
}

const char* software_version() { return "gyrochar " GYROCHAR_VERSION; }

std::string utc_now() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%d %H:%M:%S UTC", &tm);
  return buf;
}

Cell number(double v) {
  if (std::isnan(v)) return {};
  if (std::isinf(v)) return {v > 0 ? "inf" : "-inf", v > 0 ? "inf" : "-inf", {}};
  return {fmt::format("{:.4g}", v), fmt::format("{}", v), {}};
}

Cell verdict(Verdict v) { return {name(v), name(v), name(v)}; }

std::string svg_log_plot(const LogPlot& plot) {
  constexpr double width = 720, height = 400, left = 72, right = 250, top = 30, bottom = 48;
  const double pw = width - left - right, ph = height - top - bottom;
  double x_lo = std::numeric_limits<double>::infinity(), x_hi = 0, y_lo = x_lo, y_hi = 0;
  const auto take = [&](double x, double y) {
    if (!(x > 0 && y > 0 && std::isfinite(x) && std::isfinite(y))) return;
    x_lo = std::min(x_lo, x), x_hi = std::max(x_hi, x), y_lo = std::min(y_lo, y), y_hi = std::max(y_hi, y);
  };
  for (const PlotSeries& s : plot.series)
    for (const PlotPoint& p : s.points) {
      take(p.x, p.y);
      if (p.ci.valid && p.y > 0) take(p.x, p.ci.low), take(p.x, p.ci.high);
    }
  std::string out =
      fmt::format(R"(<svg class="plot" width="{}" height="{}" viewBox="0 0 {} {}" role="img" aria-label="{}">)", width,
                  height, width, height, escape(plot.title));
  out += fmt::format(R"(<text x="{}" y="18" font-size="14" font-weight="bold">{}</text>)", left, escape(plot.title));
  if (!(x_hi > 0)) {
    out += fmt::format(R"(<rect x="{}" y="{}" width="{}" height="{}" fill="none" stroke="#333"/>)", left, top, pw, ph);
    out += fmt::format(R"(<text x="{}" y="{}" text-anchor="middle">no data</text></svg>)", left + pw / 2, top + ph / 2);
    return out;
  }
  // Lines widen the window a little (the model beyond the points is clipped), limits too.
  for (const LogPlot::LimitMark& l : plot.limits) take(l.tau > 0 ? l.tau : x_lo, l.value);
  // Plain names, not structured bindings: lambdas below capture them (clang before 16 refuses that).
  const auto x_decades = decades(x_lo, x_hi), y_decades = decades(y_lo, y_hi);
  const int xa = x_decades.first, xb = x_decades.second, ya = y_decades.first, yb = y_decades.second;
  const auto px = [&](double x) { return left + (std::log10(x) - xa) / (xb - xa) * pw; };
  const auto py = [&](double y) { return top + ph - (std::log10(y) - ya) / (yb - ya) * ph; };
  const auto inside = [&](double x, double y) {
    return x > 0 && y > 0 && std::log10(x) >= xa - 1e-9 && std::log10(x) <= xb + 1e-9 && std::log10(y) >= ya - 1e-9 &&
           std::log10(y) <= yb + 1e-9;
  };
  // Grid and decade labels.
  for (int e = xa; e <= xb; ++e) {
    const double x = left + static_cast<double>(e - xa) / (xb - xa) * pw;
    out += fmt::format(R"(<line x1="{:.1f}" y1="{}" x2="{:.1f}" y2="{}" stroke="#ddd"/>)", x, top, x, top + ph);
    out += fmt::format(
        R"(<text x="{:.1f}" y="{}" text-anchor="middle" font-size="11">10<tspan dy="-5" font-size="8">{}</tspan></text>)", x,
        top + ph + 15, e);
  }
  for (int e = ya; e <= yb; ++e) {
    const double y = top + ph - static_cast<double>(e - ya) / (yb - ya) * ph;
    out += fmt::format(R"(<line x1="{}" y1="{:.1f}" x2="{}" y2="{:.1f}" stroke="#ddd"/>)", left, y, left + pw, y);
    out += fmt::format(
        R"(<text x="{}" y="{:.1f}" text-anchor="end" font-size="11">10<tspan dy="-5" font-size="8">{}</tspan></text>)",
        left - 6, y + 4, e);
  }
  out += fmt::format(R"(<rect x="{}" y="{}" width="{}" height="{}" fill="none" stroke="#333"/>)", left, top, pw, ph);
  out += fmt::format(R"(<text x="{}" y="{}" text-anchor="middle" font-size="12">{}</text>)", left + pw / 2, height - 10,
                     escape(plot.x_label));
  out += fmt::format(R"~(<text x="14" y="{}" text-anchor="middle" font-size="12" transform="rotate(-90 14 {})">{}</text>)~",
                     top + ph / 2, top + ph / 2, escape(plot.y_label));
  // Lines (clipped to the window), limits, then the points with their error bars.
  std::string legend;
  double ly = top + 8;
  const auto legend_entry = [&](const std::string& colour, const std::string& name, const char* mark) {
    legend += fmt::format(R"~(<g transform="translate({},{:.0f})">{}<text x="22" y="4" font-size="11">{}</text></g>)~",
                          left + pw + 10, ly, fmt::format(fmt::runtime(mark), colour), escape(name));
    ly += 16;
  };
  for (const PlotLine& l : plot.lines) {
    std::string pts;
    for (std::size_t i = 0; i < l.x.size() && i < l.y.size(); ++i)
      if (inside(l.x[i], l.y[i])) pts += fmt::format("{:.1f},{:.1f} ", px(l.x[i]), py(l.y[i]));
    if (pts.empty()) continue;
    out += fmt::format(R"(<polyline points="{}" fill="none" stroke="{}" stroke-width="1.5"{}/>)", pts, escape(l.colour),
                       l.dashed ? R"( stroke-dasharray="5,3")" : "");
    legend_entry(escape(l.colour), l.name,
                 l.dashed ? R"(<line x1="0" y1="0" x2="16" y2="0" stroke="{}" stroke-width="1.5" stroke-dasharray="5,3"/>)"
                          : R"(<line x1="0" y1="0" x2="16" y2="0" stroke="{}" stroke-width="1.5"/>)");
  }
  for (const LogPlot::LimitMark& l : plot.limits) {
    if (!inside(l.tau > 0 ? l.tau : std::pow(10.0, xa), l.value)) continue;
    const double x1 = l.tau > 0 ? std::max(left, px(l.tau) - 18) : left,
                 x2 = l.tau > 0 ? std::min(left + pw, px(l.tau) + 18) : left + pw;
    out += fmt::format(
        R"(<line x1="{:.1f}" y1="{:.1f}" x2="{:.1f}" y2="{:.1f}" stroke="#c00000" stroke-width="2" stroke-dasharray="6,3"/>)",
        x1, py(l.value), x2, py(l.value));
    legend_entry("#c00000", l.label,
                 R"(<line x1="0" y1="0" x2="16" y2="0" stroke="{}" stroke-width="2" stroke-dasharray="6,3"/>)");
  }
  for (const PlotSeries& s : plot.series) {
    const std::string c = escape(s.colour);
    for (const PlotPoint& p : s.points) {
      if (!inside(p.x, p.y)) continue;
      if (p.ci.valid && p.ci.low > 0)
        out += fmt::format(R"(<line x1="{0:.1f}" y1="{1:.1f}" x2="{0:.1f}" y2="{2:.1f}" stroke="{3}"/>)", px(p.x),
                           py(std::min(p.ci.high, std::pow(10.0, yb))), py(std::max(p.ci.low, std::pow(10.0, ya))), c);
      out += s.square ? fmt::format(R"(<rect x="{:.1f}" y="{:.1f}" width="6" height="6" fill="{}"/>)", px(p.x) - 3,
                                    py(p.y) - 3, c)
                      : fmt::format(R"(<circle cx="{:.1f}" cy="{:.1f}" r="3" fill="{}"/>)", px(p.x), py(p.y), c);
    }
    legend_entry(c, s.name,
                 s.square ? R"(<rect x="5" y="-3" width="6" height="6" fill="{}"/>)"
                          : R"(<circle cx="8" cy="0" r="3" fill="{}"/>)");
  }
  return out + legend + "</svg>";
}

Document::Document(std::string title) : title_(std::move(title)) {}

void Document::heading(std::string_view text, int level, std::string_view id) {
  body_ += fmt::format("<h{}{}>{}</h{}>\n", level, attr("id", id), escape(text), level);
}

void Document::paragraph(std::string_view text, std::string_view css) {
  body_ += fmt::format("<p{}>{}</p>\n", attr("class", css), escape(text));
}

void Document::facts(const std::vector<std::pair<std::string, std::string>>& rows, std::string_view id) {
  body_ += fmt::format("<dl class=\"facts\"{}>\n", attr("id", id));
  for (const auto& [k, v] : rows) body_ += fmt::format("<dt>{}</dt><dd>{}</dd>\n", escape(k), escape(v));
  body_ += "</dl>\n";
}

void Document::table(std::string_view id, std::string_view caption, const std::vector<std::string>& header,
                     const std::vector<std::vector<Cell>>& rows) {
  body_ += fmt::format("<table{}>", attr("id", id));
  if (!caption.empty()) body_ += fmt::format("<caption>{}</caption>", escape(caption));
  body_ += "\n<thead><tr>";
  for (const std::string& h : header) body_ += fmt::format("<th>{}</th>", escape(h));
  body_ += "</tr></thead>\n<tbody>\n";
  for (const auto& row : rows) {
    body_ += "<tr>";
    for (const Cell& c : row)
      body_ += fmt::format("<td{}{}>{}</td>", attr("class", c.css), attr("data-value", c.value), escape(c.text));
    body_ += "</tr>\n";
  }
  body_ += "</tbody></table>\n";
}

void Document::raw(std::string_view markup) { body_ += markup; }

std::string Document::finish() const {
  return fmt::format(
      "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>{}</title>\n"
      "<style>{}</style>\n</head>\n<body>\n<h1>{}</h1>\n{}<p class=\"note\">Made by {}.</p>\n"
      "</body>\n</html>\n",
      escape(title_), style, escape(title_), body_, software_version());
}

void verdict_section(Document& doc, const std::vector<Limit>& limits, const std::vector<Decision>& decisions,
                     const std::string& id, int level) {
  doc.heading("Acceptance verdicts", level, id + "-heading");
  doc.paragraph(fmt::format("Overall: {}", name(overall(decisions))), "overall");
  doc.paragraph(
      "Decision rule: each bound is a one-sided 97.5 % confidence bound (the two-sided 95 % interval of "
      "the deviation's EDF, or of the fitted term, value -+ 1.96 standard uncertainties). Pass when the "
      "upper bound is within the limit, fail when the lower bound is beyond it, undecided otherwise or "
      "when the term is not resolved by an accepted fit. 'Decides at' is the run length at which the "
      "interval is expected to clear the limit if the estimate stays where it is (the interval narrows "
      "as 1/sqrt(EDF), EDF in proportion to the run length).",
      "note");
  std::vector<std::vector<Cell>> rows;
  for (std::size_t i = 0; i < limits.size() && i < decisions.size(); ++i) {
    const Limit& l = limits[i];
    const Decision& d = decisions[i];
    const auto in_unit = [&](double v) { return d.estimate.usable ? number(v / l.unit_si) : Cell{}; };
    Cell when = Cell{format_run_length(d.decide_at_s),
                     std::isnan(d.decide_at_s) ? "" : fmt::format("{}", d.decide_at_s),
                     {}};
    rows.push_back({{l.quantity(), l.quantity(), "text"},
                    number(l.value_si / l.unit_si),
                    {l.unit, {}, "text"},
                    in_unit(d.estimate.value),
                    in_unit(d.estimate.low),
                    in_unit(d.estimate.high),
                    verdict(d.verdict),
                    when,
                    {d.reason, {}, "text"}});
  }
  doc.table(id, "",
            {"quantity", "limit", "unit", "estimate", "lower 97.5 %", "upper 97.5 %", "verdict", "decides at", "why"}, rows);
}

bool write_file_atomically(const std::string& path, std::string_view text, std::string& why) {
  const std::string part = path + ".part";
  std::FILE* f = std::fopen(part.c_str(), "wb");
  if (f == nullptr) {
    why = fmt::format("{}: {}", part, std::strerror(errno));
    return false;
  }
  const bool written = std::fwrite(text.data(), 1, text.size(), f) == text.size();
  const int saved = errno;
  if (std::fclose(f) != 0 || !written) {
    why = fmt::format("{}: write failed: {}", part, std::strerror(written ? errno : saved));
    std::remove(part.c_str());
    return false;
  }
  if (std::rename(part.c_str(), path.c_str()) != 0) {
    why = fmt::format("{}: {}", path, std::strerror(errno));
    std::remove(part.c_str());
    return false;
  }
  return true;
}

}  // namespace gyrochar::html
