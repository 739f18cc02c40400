#include "limits.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <fstream>
#include <iterator>
#include <optional>

#include "confidence.hpp"
#include "units.hpp"

namespace gyrochar {
namespace {

constexpr std::size_t max_limits_bytes = 65536;

std::string_view trim(std::string_view s) {
  const auto blank = [](char c) { return c == ' ' || c == '\t' || c == '\r'; };
  while (!s.empty() && blank(s.front())) s.remove_prefix(1);
  while (!s.empty() && blank(s.back())) s.remove_suffix(1);
  return s;
}

// A positive finite number at the start of `s`; `s` keeps what follows it.
std::optional<double> leading_number(std::string_view& s) {
  double v = 0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc() || end == s.data() || !(v > 0) || !std::isfinite(v)) return std::nullopt;
  s.remove_prefix(static_cast<std::size_t>(end - s.data()));
  return v;
}

// The size in SI of `unit` for IEEE-952 term k: its gyro unit, its SI unit; Q any angle unit, B
// any rate unit.
std::optional<double> term_unit_si(std::size_t k, std::string_view unit) {
  static constexpr std::array<const char*, 5> si{"rad", "rad/s^0.5", "rad/s", "rad/s^1.5", "rad/s^2"};
  if (unit == units::ieee952[k].name) return units::ieee952[k].si;
  if (unit == si[k]) return 1.0;
  if (k == 0) return angle_unit_rad(unit);
  if (k == 2)
    if (const auto r = rate_unit(unit)) return r->rad_per_s;
  return std::nullopt;
}

std::string term_units_text(std::size_t k) {
  static constexpr std::array<const char*, 5> si{"rad", "rad/s^0.5", "rad/s", "rad/s^1.5", "rad/s^2"};
  std::string t = fmt::format("{} or {}", units::ieee952[k].name, si[k]);
  if (k == 0) t = "an angle unit (arcsec, deg, rad, mrad, urad)";
  if (k == 2) t = "a rate unit (deg/h, deg/s, rad/s)";
  return t;
}

[[noreturn]] void line_error(std::size_t line, const std::string& why) {
  throw LimitsError(fmt::format("line {}: {}", line, why));
}

// "(100 s)" after adev or mdev: the tau in s; `s` keeps what follows the ')'.
double parse_tau(std::string_view& s, std::size_t line, std::string_view stat) {
  s = trim(s);
  if (s.empty() || s.front() != '(') line_error(line, fmt::format("{} needs its tau: {}(100 s)", stat, stat));
  const auto close = s.find(')');
  if (close == std::string_view::npos) line_error(line, fmt::format("{}(: no closing ')'", stat));
  std::string_view inside = trim(s.substr(1, close - 1));
  s.remove_prefix(close + 1);
  const auto tau = leading_number(inside);
  if (!tau) line_error(line, fmt::format("the tau of {} is not a positive number of seconds", stat));
  inside = trim(inside);
  double scale = 0;
  if (inside.empty() || inside == "s") scale = 1;
  else if (inside == "min") scale = 60;
  else if (inside == "h") scale = 3600;
  else line_error(line, fmt::format("the tau's unit '{}' is not s, min or h", inside));
  return *tau * scale;
}

Limit parse_line(std::string_view text, std::size_t line) {
  Limit l;
  l.line = line;
  l.text = std::string(text);
  std::string_view s = text;
  // The quantity.
  const auto name_end = std::min(s.find_first_of(" \t(<>="), s.size());
  const std::string_view q = s.substr(0, name_end);
  s.remove_prefix(name_end);
  if (q == "adev" || q == "mdev") {
    l.kind = q == "adev" ? Limit::Kind::adev : Limit::Kind::mdev;
    l.tau_s = parse_tau(s, line, q);
  } else {
    const auto k = std::find_if(units::ieee952.begin(), units::ieee952.end(),
                                [&](const units::Ieee952Unit& u) { return q == u.letter; });
    if (k == units::ieee952.end())
      line_error(line, fmt::format("'{}' is not a limited quantity: Q, N, B, K, R, adev(TAU), mdev(TAU)", q));
    l.kind = Limit::Kind::term;
    l.term = static_cast<std::size_t>(k - units::ieee952.begin());
  }
  // The operator.
  s = trim(s);
  if (s.substr(0, 2) != "<=") {
    const std::string_view op = s.substr(0, std::min(s.find_first_of(" \t0123456789."), s.size()));
    line_error(line, op.empty() ? std::string("no operator: write QUANTITY <= VALUE UNIT")
                                : fmt::format("operator '{}': only upper limits, '<=', are supported", op));
  }
  s = trim(s.substr(2));
  // The value and its unit.
  const auto value = leading_number(s);
  if (!value) line_error(line, "the limit is not a positive finite number");
  l.unit = std::string(trim(s));
  if (l.unit.empty()) line_error(line, "the limit has no unit");
  std::optional<double> unit_si;
  if (l.kind == Limit::Kind::term) {
    unit_si = term_unit_si(l.term, l.unit);
    if (!unit_si)
      line_error(line, fmt::format("'{}' is not a unit of {}: {}", l.unit, units::ieee952[l.term].letter,
                                   term_units_text(l.term)));
  } else if (const auto r = rate_unit(l.unit)) {
    unit_si = r->rad_per_s;
  } else {
    line_error(line, fmt::format("'{}' is not a rate unit (deg/h, deg/s, rad/s)", l.unit));
  }
  l.unit_si = *unit_si;
  l.value_si = *value * l.unit_si;
  if (!std::isnormal(l.value_si)) line_error(line, "the limit leaves a double's range in SI units");
  return l;
}

}  // namespace

std::string Limit::quantity() const {
  if (kind == Kind::term) return units::ieee952[term].letter;
  return fmt::format("{}({:g} s)", kind == Kind::adev ? "adev" : "mdev", tau_s);
}

std::vector<Limit> parse_limits(std::string_view text) {
  std::vector<Limit> limits;
  std::size_t line = 0;
  while (!text.empty()) {
    ++line;
    const auto nl = std::min(text.find('\n'), text.size());
    std::string_view raw = text.substr(0, nl);
    text.remove_prefix(std::min(nl + 1, text.size()));
    for (const char c : raw)
      if ((static_cast<unsigned char>(c) < 0x20 && c != '\t' && c != '\r') || c == 0x7f)
        line_error(line, fmt::format("control byte \\x{:02x}", static_cast<unsigned char>(c)));
    const std::string_view content = trim(raw.substr(0, std::min(raw.find('#'), raw.size())));
    if (content.empty()) continue;
    Limit l = parse_line(content, line);
    for (const Limit& other : limits)
      if (other.kind == l.kind && other.term == l.term && other.tau_s == l.tau_s)
        line_error(line, fmt::format("{} is limited twice (line {} too)", l.quantity(), other.line));
    limits.push_back(std::move(l));
  }
  if (limits.empty()) throw LimitsError("no limit in the file (only comments and blank lines)");
  return limits;
}

std::vector<Limit> read_limits_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw LimitsError("cannot be read");
  std::string text;
  text.resize(max_limits_bytes + 1);
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  if (in.bad()) throw LimitsError("cannot be read");
  text.resize(static_cast<std::size_t>(in.gcount()));
  if (text.size() > max_limits_bytes) throw LimitsError(fmt::format("longer than {} bytes", max_limits_bytes));
  return parse_limits(text);
}

const char* name(Verdict v) {
  switch (v) {
    case Verdict::pass: return "pass";
    case Verdict::fail: return "fail";
    case Verdict::undecided: return "undecided";
  }
  return "undecided";
}

LimitEstimate normal_estimate(double value, double standard_uncertainty, double run_s) {
  LimitEstimate e;
  e.usable = std::isfinite(value) && std::isfinite(standard_uncertainty) && standard_uncertainty >= 0;
  if (!e.usable) e.why = "no finite estimate";
  e.value = value;
  e.low = std::max(0.0, value - decision_z * standard_uncertainty);
  e.high = value + decision_z * standard_uncertainty;
  e.run_s = run_s;
  return e;
}

LimitEstimate deviation_estimate(double dev, double edf, double skew_dof, double run_s) {
  const Interval ci = confidence_interval(dev, edf, decision_confidence, skew_dof);
  if (!ci.valid || !std::isfinite(dev)) return no_estimate("no EDF at this tau");
  LimitEstimate e;
  e.usable = true;
  e.value = dev;
  e.low = ci.low;
  e.high = ci.high;
  e.run_s = run_s;
  return e;
}

LimitEstimate no_estimate(std::string why) {
  LimitEstimate e;
  e.why = std::move(why);
  return e;
}

Decision decide(const Limit& limit, const LimitEstimate& estimate) {
  Decision d;
  d.estimate = estimate;
  if (!estimate.usable) {
    d.reason = estimate.why;
    return d;
  }
  const double x = estimate.value, lim = limit.value_si;
  if (estimate.high <= lim) {
    d.verdict = Verdict::pass;
    d.reason = "upper bound within the limit";
  } else if (estimate.low > lim) {
    d.verdict = Verdict::fail;
    d.reason = "lower bound beyond the limit";
  } else {
    // The bound on the limit's side must move to it: its distance shrinks as sqrt(T / T_decide).
    const double gap = std::abs(x - lim);
    const double bound = x <= lim ? estimate.high - x : x - estimate.low;
    d.decide_at_s = gap > 0 ? estimate.run_s * (bound / gap) * (bound / gap) : std::numeric_limits<double>::infinity();
    d.reason = "interval spans the limit";
  }
  return d;
}

Verdict overall(const std::vector<Decision>& decisions) {
  Verdict v = Verdict::pass;
  for (const Decision& d : decisions) {
    if (d.verdict == Verdict::fail) return Verdict::fail;
    if (d.verdict == Verdict::undecided) v = Verdict::undecided;
  }
  return v;
}

std::string format_run_length(double seconds) {
  if (std::isnan(seconds)) return "";
  if (std::isinf(seconds)) return "never at this estimate";
  if (seconds >= 2 * 86400) return fmt::format("{:.3g} d", seconds / 86400);
  if (seconds >= 2 * 3600) return fmt::format("{:.3g} h", seconds / 3600);
  if (seconds >= 120) return fmt::format("{:.3g} min", seconds / 60);
  return fmt::format("{:.3g} s", seconds);
}

}  // namespace gyrochar
