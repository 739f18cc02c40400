#include "sim_truth.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <system_error>
#include <utility>

namespace gyrochar {

namespace {

constexpr std::string_view truth_prefix = "# gyrochar-sim truth:";
constexpr std::uint64_t truth_format = 1, segmented_format = 2;
constexpr std::size_t max_segments = 1000;

// The parameters on the truth line, in the order written. One table for writer and parser.
struct NumberKey {
  std::string_view key;
  double SimOptions::*field;
};
constexpr std::array<NumberKey, 12> number_keys{{
    {"duration_s", &SimOptions::duration_s},
    {"tau0_s", &SimOptions::tau0_s},
    {"pulse_arcsec", &SimOptions::pulse_arcsec},
    {"rate_deg_per_h", &SimOptions::rate_deg_per_h},
    {"white_angle_arcsec", &SimOptions::white_angle_arcsec},
    {"arw_deg_per_sqrt_h", &SimOptions::arw_deg_per_sqrt_h},
    {"rrw_deg_per_h_sqrt_h", &SimOptions::rrw_deg_per_h_sqrt_h},
    {"bias_deg_per_h", &SimOptions::bias_deg_per_h},
    {"bias_time_s", &SimOptions::bias_time_s},
    {"ramp_deg_per_h2", &SimOptions::ramp_deg_per_h2},
    {"dither_arcsec", &SimOptions::dither_arcsec},
    {"dither_hz", &SimOptions::dither_hz},
}};

// The truth in the units of the IEEE-952 fit, and each unit in SI.
struct TruthKey {
  std::string_view key;
  double Ieee952Truth::*field;
  double unit;
};
constexpr std::array<TruthKey, 5> truth_keys{{
    {"Q_arcsec", &Ieee952Truth::q_rad, units::arcsec},
    {"N_deg_per_sqrt_h", &Ieee952Truth::n_rad_sqrt_s, units::deg_per_sqrt_h},
    {"B_deg_per_h", &Ieee952Truth::b_rad_s, units::deg_per_h},
    {"K_deg_per_h_sqrt_h", &Ieee952Truth::k_rad_s_sqrt_s, units::deg_per_h_sqrt_h},
    {"R_deg_per_h2", &Ieee952Truth::r_rad_s2, units::deg_per_h_per_h},
}};

// What a segment may change: its key on the truth line, its --segment name, the option it sets.
struct SegmentKey {
  std::string_view key, option;
  std::optional<double> SimSegment::*field;
  double SimOptions::*target;
};
constexpr std::array<SegmentKey, 4> segment_keys{{
    {"rate_deg_per_h", "rate", &SimSegment::rate_deg_per_h, &SimOptions::rate_deg_per_h},
    {"white_angle_arcsec", "white-angle", &SimSegment::white_angle_arcsec, &SimOptions::white_angle_arcsec},
    {"arw_deg_per_sqrt_h", "arw", &SimSegment::arw_deg_per_sqrt_h, &SimOptions::arw_deg_per_sqrt_h},
    {"rrw_deg_per_h_sqrt_h", "rrw", &SimSegment::rrw_deg_per_h_sqrt_h, &SimOptions::rrw_deg_per_h_sqrt_h},
}};

// A run's Gauss-Markov or sinusoidal terms on the truth line: the count key, then for term i the
// keys <head><i>_<field> of its two numbers. One table per kind for writer and parser.
template <class Term>
struct TermKeys {
  std::string_view head, count;
  std::array<std::pair<std::string_view, double Term::*>, 2> fields;
  std::vector<Term> SimOptions::*list;
};
constexpr TermKeys<SimMarkov> markov_keys{"markov",
                                          "markov_terms",
                                          {{{"sigma_deg_per_h", &SimMarkov::sigma_deg_per_h}, {"tc_s", &SimMarkov::tc_s}}},
                                          &SimOptions::markov};
constexpr TermKeys<SimSinusoid> sinusoid_keys{"sinusoid",
                                              "sinusoid_terms",
                                              {{{"amplitude_deg_per_h", &SimSinusoid::amplitude_deg_per_h},
                                                {"frequency_hz", &SimSinusoid::frequency_hz}}},
                                              &SimOptions::sinusoids};

void append_number(std::string& out, double v) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);  // shortest text that reads back exactly
  out.append(buf, r.ptr);
}

void append_integer(std::string& out, std::uint64_t v) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  out.append(buf, r.ptr);
}

bool read_number(std::string_view text, double& v) {
  const auto r = std::from_chars(text.data(), text.data() + text.size(), v);
  return r.ec == std::errc() && r.ptr == text.data() + text.size() && std::isfinite(v);
}

bool read_integer(std::string_view text, std::uint64_t& v) {
  const auto r = std::from_chars(text.data(), text.data() + text.size(), v);
  return r.ec == std::errc() && r.ptr == text.data() + text.size();
}

bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; }

}  // namespace

std::optional<ParameterProblem> check_parameters(const SimOptions& o) {
  if (!(o.tau0_s > 0) || !std::isfinite(o.tau0_s)) return ParameterProblem{"--tau0", "must be positive"};
  if (!(o.duration_s >= o.tau0_s)) return ParameterProblem{"--duration", "must be at least tau0"};
  if (!(o.duration_s / o.tau0_s <= 1e12)) return ParameterProblem{"--duration", "more than 10^12 samples of tau0"};
  if (!std::isfinite(o.rate_deg_per_h) || std::fabs(o.rate_deg_per_h) > 1e9)
    return ParameterProblem{"--rate", "must be a finite rate in deg/h"};
  if (!(o.pulse_arcsec > 0) || !std::isfinite(o.pulse_arcsec)) return ParameterProblem{"--pulse-weight", "must be positive"};
  for (double v : {o.white_angle_arcsec, o.arw_deg_per_sqrt_h, o.rrw_deg_per_h_sqrt_h, o.ramp_deg_per_h2, o.bias_deg_per_h,
                   o.dither_arcsec, o.dither_hz})
    if (!(v >= 0) || !std::isfinite(v)) return ParameterProblem{"noise parameters", "must be finite and >= 0"};
  if (o.bias_deg_per_h > 0 && !(o.bias_time_s > o.tau0_s && o.bias_time_s <= 1e15 * o.tau0_s))
    return ParameterProblem{"--bias-time", "must exceed tau0 (and stay within 10^15 tau0) for bias instability"};
  if (o.markov.size() > max_rate_terms) return ParameterProblem{"--markov", "at most 4 Gauss-Markov terms"};
  for (const SimMarkov& m : o.markov) {
    if (!(m.sigma_deg_per_h > 0 && m.sigma_deg_per_h <= 1e9))
      return ParameterProblem{"--markov", "SIGMA must be positive and at most 10^9 deg/h"};
    if (!(m.tc_s > 0) || !std::isfinite(m.tc_s)) return ParameterProblem{"--markov", "TC must be positive and finite (s)"};
  }
  if (o.sinusoids.size() > max_rate_terms) return ParameterProblem{"--sinusoid", "at most 4 sinusoids"};
  for (const SimSinusoid& g : o.sinusoids) {
    if (!(g.amplitude_deg_per_h >= 0 && g.amplitude_deg_per_h <= 1e9))
      return ParameterProblem{"--sinusoid", "AMP must be between 0 and 10^9 deg/h"};
    if (!(g.frequency_hz > 0 && 2 * g.frequency_hz * o.tau0_s < 1)) {
      char why[160];
      std::snprintf(why, sizeof why, "FREQ must be above 0 and below the Nyquist frequency 1/(2 tau0) = %g Hz",
                    0.5 / o.tau0_s);
      return ParameterProblem{"--sinusoid", why};
    }
  }
  if (o.segments.size() > max_segments) return ParameterProblem{"--segment", "at most 1000 segments"};
  double previous_s = 0;
  for (std::size_t i = 0; i < o.segments.size(); ++i) {
    const SimSegment& g = o.segments[i];
    if (!(g.start_s >= o.tau0_s && g.start_s < o.duration_s && g.start_s > previous_s))
      return ParameterProblem{"--segment", "segments must start in increasing order, at tau0 or later, before the end"};
    previous_s = g.start_s;
    if (std::none_of(segment_keys.begin(), segment_keys.end(),
                     [&](const SegmentKey& k) { return (g.*k.field).has_value(); }))
      return ParameterProblem{"--segment", "a segment must change something"};
    if (const auto problem = check_parameters(segment_options(o, i + 1))) return ParameterProblem{"--segment", problem->why};
  }
  if (const PulseReach reach = worst_case_pulses(o); !(reach.total <= max_pulse_total)) {
    char why[400];
    std::snprintf(why, sizeof why,
                  "the counted angle could reach %.3g pulses over the run (%.3g from this option; random terms at "
                  "%g sigma), beyond the simulator's limit of 2^53 = %.4g pulses (counts exact): shorten --duration, "
                  "raise --pulse-weight or lower the rates and noise",
                  reach.total, reach.largest, range_sigmas, max_pulse_total);
    return ParameterProblem{reach.largest_what, why};
  }
  return std::nullopt;
}

PulseReach worst_case_pulses(const SimOptions& o) {
  const double t = std::round(o.duration_s / o.tau0_s) * o.tau0_s, s = range_sigmas;
  double rate = 0, q = 0, n = 0, k = 0;  // every segment's largest level, SI
  for (std::size_t i = 0; i <= o.segments.size(); ++i) {
    const GyroParameters p = gyro_parameters(segment_options(o, i));
    rate = std::max(rate, std::fabs(p.rate_rad_s));
    q = std::max(q, p.q_rad);
    n = std::max(n, p.n_rad_sqrt_s);
    k = std::max(k, p.k_rad_s_sqrt_s);
  }
  const GyroParameters p = gyro_parameters(o);
  double flicker_variance = 0;  // the octave processes of gyro_sim.cpp, B^2 ln 2 / pi each
  if (p.b_rad_s > 0)
    for (double f = flicker_top_corner / p.tau0_s;; f *= 0.5) {
      flicker_variance += p.b_rad_s * p.b_rad_s * std::log(2.0) / units::pi;
      if (f <= 1.0 / (2.0 * units::pi * p.bias_time_s)) break;
    }
  double markov = 0, sinusoids = 0;
  for (const MarkovRate& m : p.markov) markov += s * m.sigma_rad_s * t;
  for (const SinusoidRate& g : p.sinusoids) sinusoids += g.amplitude_rad_s / (units::pi * g.frequency_hz);
  const std::pair<const char*, double> terms[] = {
      {"--rate", rate * t},
      {"--ramp", p.r_rad_s2 * t * t / 2},
      {"--dither", p.dither_amplitude_rad},
      {"--white-angle", s * q},
      {"--arw", s * n * std::sqrt(t)},
      {"--rrw", s * k * t * std::sqrt(t / 3)},
      {"--bias-instability", s * std::sqrt(flicker_variance) * t},
      {"--markov", markov},
      {"--sinusoid", sinusoids},
  };
  PulseReach reach;
  for (const auto& [what, rad] : terms) {
    if (std::isnan(rad)) continue;  // 0 x inf: a term that is absent
    const double pulses = rad / p.pulse_weight_rad;
    reach.total += pulses;
    if (!(pulses <= reach.largest)) {  // NaN too
      reach.largest = pulses;
      reach.largest_what = what;
    }
  }
  if (reach.largest_what[0] == '\0') reach.largest_what = "--duration";
  return reach;
}

SimOptions segment_options(const SimOptions& o, std::size_t i) {
  SimOptions s = o;
  s.segments.clear();
  for (std::size_t j = 0; j < i && j < o.segments.size(); ++j)
    for (const SegmentKey& k : segment_keys)
      if (const auto& v = o.segments[j].*k.field) s.*k.target = *v;
  return s;
}

GyroParameters gyro_parameters(const SimOptions& o) {
  GyroParameters p;
  p.tau0_s = o.tau0_s;
  p.pulse_weight_rad = o.pulse_arcsec * units::arcsec;
  p.rate_rad_s = o.rate_deg_per_h * units::deg_per_h;
  p.q_rad = o.white_angle_arcsec * units::arcsec;
  p.n_rad_sqrt_s = o.arw_deg_per_sqrt_h * units::deg_per_sqrt_h;
  p.k_rad_s_sqrt_s = o.rrw_deg_per_h_sqrt_h * units::deg_per_h_sqrt_h;
  p.r_rad_s2 = o.ramp_deg_per_h2 * units::deg_per_h_per_h;
  p.b_rad_s = o.bias_deg_per_h * units::deg_per_h;
  p.bias_time_s = o.bias_time_s;
  p.dither_amplitude_rad = o.dither_arcsec * units::arcsec;
  p.dither_frequency_hz = o.dither_hz;
  p.seed = o.seed;
  for (const SimMarkov& m : o.markov) p.markov.push_back({m.sigma_deg_per_h * units::deg_per_h, m.tc_s});
  for (const SimSinusoid& g : o.sinusoids) p.sinusoids.push_back({g.amplitude_deg_per_h * units::deg_per_h, g.frequency_hz});
  return p;
}

bool quantization_expected_white(const SimOptions& o) {
  for (std::size_t i = 1; i <= o.segments.size(); ++i)
    if (!quantization_expected_white(segment_options(o, i))) return false;
  const double arw_arcsec = o.arw_deg_per_sqrt_h * units::deg_per_sqrt_h / units::arcsec;  // arcsec/sqrt(s)
  const double random_step_arcsec = std::sqrt(arw_arcsec * arw_arcsec * o.tau0_s +
                                              2.0 * o.white_angle_arcsec * o.white_angle_arcsec);
  // A dither of angle amplitude A moves the angle by up to 2 A |sin(pi f tau0)| per sample; so does a
  // sinusoidal rate, whose angle amplitude is A_rate / (2 pi f) (deg/h = arcsec/s).
  const auto dither_step_arcsec = [&o](double amplitude_arcsec, double f) {
    return 2.0 * amplitude_arcsec * std::fabs(std::sin(units::pi * f * o.tau0_s));
  };
  const double pulse = o.pulse_arcsec * (1 - 1e-12);  // a step of exactly one pulse, up to rounding
  for (const SimSinusoid& g : o.sinusoids)
    if (dither_step_arcsec(g.amplitude_deg_per_h / (2.0 * units::pi * g.frequency_hz), g.frequency_hz) >= pulse) return true;
  return random_step_arcsec >= pulse || dither_step_arcsec(o.dither_arcsec, o.dither_hz) >= pulse;
}

Ieee952Truth ieee952_truth(const SimOptions& o) {
  const GyroParameters p = gyro_parameters(o);
  Ieee952Truth t;
  t.q_rad = std::sqrt(p.q_rad * p.q_rad + p.pulse_weight_rad * p.pulse_weight_rad / 12.0);
  t.n_rad_sqrt_s = p.n_rad_sqrt_s;
  t.b_rad_s = p.b_rad_s;
  t.k_rad_s_sqrt_s = p.k_rad_s_sqrt_s;
  t.r_rad_s2 = p.r_rad_s2;
  t.quantization_white = quantization_expected_white(o);
  t.markov = p.markov;
  t.sinusoids = p.sinusoids;
  return t;
}

std::string format_sim_description_line(const SimOptions& o) {
  char buf[640];
  std::snprintf(buf, sizeof buf,
                "# gyrochar-sim counts: tau0 %g s, pulse weight %g arcsec, rate %g deg/h, white angle %g arcsec, "
                "ARW %g deg/sqrt(h), bias instability %g deg/h (band down to 1/(2 pi %g s)), RRW %g deg/h/sqrt(h), "
                "ramp %g deg/h/h, dither %g arcsec at %g Hz, seed %llu",
                o.tau0_s, o.pulse_arcsec, o.rate_deg_per_h, o.white_angle_arcsec, o.arw_deg_per_sqrt_h, o.bias_deg_per_h,
                o.bias_time_s, o.rrw_deg_per_h_sqrt_h, o.ramp_deg_per_h2, o.dither_arcsec, o.dither_hz,
                static_cast<unsigned long long>(o.seed));
  std::string out = buf;
  for (const SimMarkov& m : o.markov) {
    std::snprintf(buf, sizeof buf, ", Gauss-Markov rate %g deg/h over %g s", m.sigma_deg_per_h, m.tc_s);
    out += buf;
  }
  for (const SimSinusoid& g : o.sinusoids) {
    std::snprintf(buf, sizeof buf, ", sinusoidal rate %g deg/h at %g Hz", g.amplitude_deg_per_h, g.frequency_hz);
    out += buf;
  }
  for (const SimSegment& g : o.segments) {
    std::snprintf(buf, sizeof buf, "; from %g s:", g.start_s);
    out += buf;
    for (const SegmentKey& k : segment_keys) {
      if (!(g.*k.field)) continue;
      std::snprintf(buf, sizeof buf, " %.*s %g", static_cast<int>(k.option.size()), k.option.data(), *(g.*k.field));
      out += buf;
    }
  }
  return out;
}

namespace {

// " markov_terms=2 markov1_sigma_deg_per_h=... markov1_tc_s=... markov2_...", nothing without terms.
template <class Term>
void append_terms(std::string& out, const SimOptions& o, const TermKeys<Term>& keys) {
  const std::vector<Term>& list = o.*keys.list;
  if (list.empty()) return;
  out += ' ';
  out += keys.count;
  out += '=';
  append_integer(out, list.size());
  for (std::size_t i = 0; i < list.size(); ++i) {
    for (const auto& [name, field] : keys.fields) {
      out += ' ';
      out += keys.head;
      append_integer(out, i + 1);
      out += '_';
      out += name;
      out += '=';
      append_number(out, list[i].*field);
    }
  }
}

}  // namespace

std::string format_sim_truth_line(const SimOptions& o) {
  std::string out(truth_prefix);
  out += " format=";
  append_integer(out, o.segments.empty() ? truth_format : segmented_format);
  for (const NumberKey& k : number_keys) {
    out += ' ';
    out += k.key;
    out += '=';
    append_number(out, o.*k.field);
  }
  out += " seed=";
  append_integer(out, o.seed);
  const Ieee952Truth t = ieee952_truth(o);
  for (const TruthKey& k : truth_keys) {
    out += ' ';
    out += k.key;
    out += '=';
    append_number(out, t.*k.field / k.unit);
  }
  out += t.quantization_white ? " Q_white=yes" : " Q_white=no";
  append_terms(out, o, markov_keys);
  append_terms(out, o, sinusoid_keys);
  if (o.segments.empty()) return out;
  out += " segments=";
  append_integer(out, o.segments.size());
  for (std::size_t i = 0; i < o.segments.size(); ++i) {
    const std::string prefix = " segment" + std::to_string(i + 1) + "_";
    out += prefix + "start_s=";
    append_number(out, o.segments[i].start_s);
    for (const SegmentKey& k : segment_keys) {
      if (!(o.segments[i].*k.field)) continue;
      out += prefix;
      out += k.key;
      out += '=';
      append_number(out, *(o.segments[i].*k.field));
    }
  }
  return out;
}

namespace {

// An indexed key "<head><i>_<name>" (segment1_start_s, markov2_tc_s) with i >= 1; i and name, or
// nothing.
std::optional<std::pair<std::size_t, std::string_view>> indexed_key(std::string_view key, std::string_view head) {
  if (!key.starts_with(head)) return std::nullopt;
  key.remove_prefix(head.size());
  std::size_t i = 0;
  const auto r = std::from_chars(key.data(), key.data() + key.size(), i);
  if (r.ec != std::errc() || r.ptr == key.data() || i == 0 || r.ptr == key.data() + key.size() || *r.ptr != '_')
    return std::nullopt;
  return std::pair{i, key.substr(static_cast<std::size_t>(r.ptr - key.data()) + 1)};
}

// What TermReader::read made of a key.
enum class Read { other, ok, bad };

// Reads one kind of rate term (TermKeys) off the truth line, key by key, into the options' list.
template <class Term>
class TermReader {
 public:
  TermReader(const TermKeys<Term>& keys, SimOptions& o) : keys_(keys), list_(o.*keys.list) {}

  /// ok: the key was this kind's and is read; bad: it was, and is wrong; other: not this kind's
  /// (a field name it does not know, from a later format, is also other).
  Read read(std::string_view key, std::string_view value) {
    if (key == keys_.count) {
      if (count_ || !read_integer(value, count_.emplace()) || *count_ == 0 || *count_ > max_rate_terms) return Read::bad;
      return Read::ok;
    }
    const auto indexed = indexed_key(key, keys_.head);
    if (!indexed) return Read::other;
    const auto [i, name] = *indexed;
    for (std::size_t f = 0; f < keys_.fields.size(); ++f) {
      if (name != keys_.fields[f].first) continue;
      double v = 0;
      if (i > max_rate_terms || (seen_[i - 1] >> f & 1u) != 0 || !read_number(value, v)) return Read::bad;
      if (list_.size() < i) list_.resize(i);
      list_[i - 1].*keys_.fields[f].second = v;
      seen_[i - 1] |= 1u << f;
      return Read::ok;
    }
    return Read::other;
  }

  /// Every term up to the count has both its numbers, and there are no terms without a count.
  bool complete() const {
    if (list_.size() != count_.value_or(0)) return false;
    for (std::size_t i = 0; i < list_.size(); ++i)
      if (seen_[i] != (1u << keys_.fields.size()) - 1) return false;
    return true;
  }

 private:
  const TermKeys<Term>& keys_;
  std::vector<Term>& list_;
  std::optional<std::uint64_t> count_;
  std::array<unsigned, max_rate_terms> seen_{};  // bit f: field f read
};

}  // namespace

std::optional<SimTruth> parse_sim_truth_line(std::string_view line) {
  if (!line.starts_with(truth_prefix)) return std::nullopt;
  line.remove_prefix(truth_prefix.size());
  SimTruth r;
  // Bits of the keys seen: the numbers, then format, seed, the truths and Q_white.
  constexpr unsigned n_numbers = number_keys.size(), bit_format = n_numbers, bit_seed = n_numbers + 1,
                     bit_truth = n_numbers + 2, bit_white = bit_truth + truth_keys.size();
  constexpr std::uint32_t all = (std::uint32_t{1} << (bit_white + 1)) - 1;
  std::uint32_t seen = 0;
  auto first_time = [&seen](unsigned bit) {
    const bool fresh = (seen & (std::uint32_t{1} << bit)) == 0;
    seen |= std::uint32_t{1} << bit;
    return fresh;
  };
  std::uint64_t format = 0, segments = 0;
  bool has_segments = false;
  TermReader markov(markov_keys, r.options);
  TermReader sinusoids(sinusoid_keys, r.options);
  std::size_t at = 0;
  while (true) {
    while (at < line.size() && is_blank(line[at])) ++at;
    if (at == line.size()) break;
    std::size_t end = at;
    while (end < line.size() && !is_blank(line[end])) ++end;
    const std::string_view token = line.substr(at, end - at);
    at = end;
    const std::size_t eq = token.find('=');
    if (eq == std::string_view::npos || eq == 0) return std::nullopt;
    const std::string_view key = token.substr(0, eq), value = token.substr(eq + 1);
    bool known = false;
    for (unsigned i = 0; i < n_numbers && !known; ++i) {
      if (key != number_keys[i].key) continue;
      known = true;
      if (!first_time(i) || !read_number(value, r.options.*number_keys[i].field)) return std::nullopt;
    }
    for (unsigned i = 0; i < truth_keys.size() && !known; ++i) {
      if (key != truth_keys[i].key) continue;
      known = true;
      double v = 0;
      if (!first_time(bit_truth + i) || !read_number(value, v) || v < 0) return std::nullopt;
      r.truth.*truth_keys[i].field = v * truth_keys[i].unit;
    }
    if (known) continue;
    bool wrong = false;
    for (const auto got : {markov.read(key, value), sinusoids.read(key, value)}) {
      known = known || got != Read::other;
      wrong = wrong || got == Read::bad;
    }
    if (wrong) return std::nullopt;
    if (known) continue;
    if (const auto segment = indexed_key(key, "segment")) {  // format 2
      const auto [i, name] = *segment;
      if (i > max_segments) return std::nullopt;
      if (r.options.segments.size() < i) r.options.segments.resize(i);
      SimSegment& g = r.options.segments[i - 1];
      double v = 0;
      if (!read_number(value, v)) return std::nullopt;
      if (name == "start_s") {
        if (g.start_s != 0) return std::nullopt;
        g.start_s = v;
        continue;
      }
      bool named = false;
      for (const SegmentKey& k : segment_keys) {
        if (name != k.key) continue;
        if ((g.*k.field).has_value()) return std::nullopt;
        g.*k.field = v;
        named = true;
      }
      if (!named) return std::nullopt;
      continue;
    }
    if (key == "segments") {
      if (!read_integer(value, segments) || segments == 0 || segments > max_segments || has_segments) return std::nullopt;
      has_segments = true;
    } else if (key == "format") {
      if (!first_time(bit_format) || !read_integer(value, format)) return std::nullopt;
    } else if (key == "seed") {
      if (!first_time(bit_seed) || !read_integer(value, r.options.seed)) return std::nullopt;
    } else if (key == "Q_white") {
      if (!first_time(bit_white) || (value != "yes" && value != "no")) return std::nullopt;
      r.truth.quantization_white = value == "yes";
    }
    // Any other key belongs to a later format: ignored.
  }
  if (seen != all || format != (has_segments ? segmented_format : truth_format) || r.options.segments.size() != segments ||
      !markov.complete() || !sinusoids.complete() || check_parameters(r.options))
    return std::nullopt;
  const GyroParameters p = gyro_parameters(r.options);  // the terms' truth: as written, in SI
  r.truth.markov = p.markov;
  r.truth.sinusoids = p.sinusoids;
  return r;
}

std::optional<SimSegment> parse_segment_option(std::string_view text, std::string& why) {
  SimSegment g;
  const std::size_t colon = text.find(':');
  const auto number = [](std::string_view t, double& v) {
    const auto r = std::from_chars(t.data(), t.data() + t.size(), v);
    return r.ec == std::errc() && r.ptr == t.data() + t.size() && std::isfinite(v);
  };
  if (colon == std::string_view::npos || !number(text.substr(0, colon), g.start_s)) {
    why = std::string("'").append(text).append("' is not T:NAME=VALUE[,NAME=VALUE...] (T in seconds)");
    return std::nullopt;
  }
  std::string_view rest = text.substr(colon + 1);
  while (true) {
    const std::size_t comma = rest.find(',');
    const std::string_view item = rest.substr(0, comma);
    const std::size_t eq = item.find('=');
    const SegmentKey* key = nullptr;
    for (const SegmentKey& k : segment_keys)
      if (eq != std::string_view::npos && item.substr(0, eq) == k.option) key = &k;
    double v = 0;
    if (key == nullptr || !number(item.substr(eq + 1), v) || (g.*key->field).has_value()) {
      why = std::string("'").append(item).append("' is not rate=, white-angle=, arw= or rrw= with a number, each once");
      return std::nullopt;
    }
    g.*key->field = v;
    if (comma == std::string_view::npos) break;
    rest = rest.substr(comma + 1);
  }
  return g;
}

namespace {

// "A,B" with A and B finite numbers; `form` names them for the message ("SIGMA,TC (deg/h, s)").
std::optional<std::pair<double, double>> parse_pair(std::string_view text, const char* form, std::string& why) {
  const std::size_t comma = text.find(',');
  std::pair<double, double> v;
  if (comma != std::string_view::npos && read_number(text.substr(0, comma), v.first) &&
      read_number(text.substr(comma + 1), v.second))
    return v;
  why = std::string("'").append(text).append("' is not ").append(form);
  return std::nullopt;
}

}  // namespace

std::optional<SimMarkov> parse_markov_option(std::string_view text, std::string& why) {
  const auto v = parse_pair(text, "SIGMA,TC: two numbers, deg/h and s", why);
  if (!v) return std::nullopt;
  return SimMarkov{v->first, v->second};
}

std::optional<SimSinusoid> parse_sinusoid_option(std::string_view text, std::string& why) {
  const auto v = parse_pair(text, "AMP,FREQ: two numbers, deg/h and Hz", why);
  if (!v) return std::nullopt;
  return SimSinusoid{v->first, v->second};
}

SimRun::SimRun(const SimOptions& o)
    : options_(o), gyro_(gyro_parameters(o)), samples_(static_cast<std::uint64_t>(std::llround(o.duration_s / o.tau0_s))) {}

std::int64_t SimRun::next_count() {
  while (next_segment_ < options_.segments.size() &&
         k_ >= static_cast<std::uint64_t>(std::llround(options_.segments[next_segment_].start_s / options_.tau0_s)))
    gyro_.retune(gyro_parameters(segment_options(options_, ++next_segment_)));
  ++k_;
  return gyro_.next_count();
}

}  // namespace gyrochar
