// gyrochar._native: the analyzer's engine for Python (pybind11; std::invalid_argument and
// std::range_error come out as ValueError). The values come in through the
// buffer protocol without a copy (float64 or int64, contiguous or strided: strided and int64 values
// are converted a block at a time), the work runs without the GIL, and the rows go out as numpy
// arrays. The package's Python half (gyrochar/__init__.py) checks and normalizes the arguments.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "analysis.hpp"
#include "analysis_report.hpp"
#include "gyrochar/crc32.hpp"
#include "input_units.hpp"
#include "plan.hpp"
#include "units.hpp"

namespace py = pybind11;
using namespace gyrochar;

namespace {

// Values of a buffer, read as doubles a block at a time: a contiguous float64 buffer is handed
// over as is; int64 and strided buffers are converted into one block of 2^14.
class Values {
 public:
  explicit Values(const py::buffer& b) : info_(b.request()) {
    if (info_.ndim != 1)
      throw py::value_error(fmt::format("values must be one-dimensional, not {}-dimensional", info_.ndim));
    const std::string& f = info_.format;
    is_double_ = f == py::format_descriptor<double>::format();
    is_int64_ = info_.itemsize == 8 && (f == "q" || f == "l" || f == "<q" || f == "<l" || f == "=q" || f == "=l");
    if (!is_double_ && !is_int64_)
      throw py::type_error(
          fmt::format("values must be float64 or int64 (buffer format '{}'): convert them with "
                      "numpy.asarray(values, dtype=float)",
                      f));
    stride_ = info_.strides.empty() ? info_.itemsize : info_.strides[0];
  }
  std::size_t size() const { return static_cast<std::size_t>(info_.shape[0]); }
  /// Values [begin, begin + n) as a span valid until the next call (n <= block).
  std::span<const double> block(std::size_t begin, std::size_t n) {
    const auto* base = static_cast<const char*>(info_.ptr);
    if (is_double_ && stride_ == sizeof(double)) return {reinterpret_cast<const double*>(base) + begin, n};
    buffer_.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      const char* p = base + static_cast<std::ptrdiff_t>(begin + i) * stride_;
      if (is_double_) {
        std::memcpy(&buffer_[i], p, sizeof(double));
      } else {
        std::int64_t v = 0;
        std::memcpy(&v, p, sizeof v);
        buffer_[i] = static_cast<double>(v);
        if (static_cast<std::int64_t>(buffer_[i]) != v)
          throw BadValue(i, fmt::format("{} is not exact as a double (beyond 2^53)", v));
      }
    }
    return buffer_;
  }

 private:
  py::buffer_info info_;
  bool is_double_ = false, is_int64_ = false;
  py::ssize_t stride_ = 8;
  std::vector<double> buffer_;
};

DataType data_type(const std::string& t) {
  if (t == "phase") return DataType::phase;
  if (t == "freq") return DataType::freq;
  if (t == "counts") return DataType::counts;
  throw py::value_error("type must be 'phase', 'freq' or 'counts', not '" + t + "'");
}

// What the values are and the unit the deviations come out in: the analyzer's own resolution of
// --unit, --pulse-weight and --rate-unit (input_units.hpp), its refusals as ValueError naming the
// argument ("pulse_weight: unknown angle unit 'parsec' ...").
ReportUnits report_units(const UnitOptions& options) {
  try {
    return resolve_units(options);
  } catch (const UnitError& e) {
    std::string argument = e.option().substr(2);  // "--pulse-weight" -> "pulse_weight"
    std::replace(argument.begin(), argument.end(), '-', '_');
    if (argument == "pulse_unit") argument = "pulse_weight";  // one argument in Python: (1.5, 'arcsec')
    throw py::value_error(argument + ": " + e.what());
  }
}

template <typename T>
py::array_t<T> array_of(const std::vector<T>& v) {
  py::array_t<T> a(static_cast<py::ssize_t>(v.size()));
  std::copy(v.begin(), v.end(), a.mutable_data());
  return a;
}

// The rows of one statistic as numpy arrays, in the output unit (gyrochar-analyze's JSON: dev and
// the interval times units.factor(), NaN where the JSON has null).
py::dict stat_arrays(const std::vector<AnalysisRow>& rows, DevStat stat, const ReportUnits& u) {
  const double k = u.factor();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> tau, dev, lo, hi, alpha, edf;
  std::vector<std::uint64_t> m, n, stride;
  py::list noise;
  for (const AnalysisRow& r : rows) {
    if (r.stat != stat) continue;
    tau.push_back(r.tau_s);
    m.push_back(r.m);
    n.push_back(r.n);
    dev.push_back(r.dev * k);
    lo.push_back(r.ci.valid ? r.ci.low * k : nan);
    hi.push_back(r.ci.valid ? r.ci.high * k : nan);
    alpha.push_back(r.alpha ? static_cast<double>(*r.alpha) : nan);
    edf.push_back(r.edf > 0 ? r.edf : nan);
    stride.push_back(r.stride);
    noise.append(r.noise.identified() ? py::object(py::str(name(r.noise.method))) : py::object(py::none()));
  }
  py::dict d;
  d["tau"] = array_of(tau);
  d["m"] = array_of(m);
  d["n"] = array_of(n);
  d["dev"] = array_of(dev);
  d["ci_low"] = array_of(lo);
  d["ci_high"] = array_of(hi);
  d["alpha"] = array_of(alpha);
  d["edf"] = array_of(edf);
  d["stride"] = array_of(stride);
  d["noise_id"] = py::array(noise);
  d["unit"] = u.unit(stat);
  return d;
}

// What a run is asked for: the options, the units, the statistics shown, whether to fit.
struct Setup {
  AnalysisOptions o;
  ReportUnits units;
  std::vector<DevStat> shown;
  bool fit = false;
  std::vector<std::uint64_t> not_formed;  // decade taus the stride factor cannot form (plan.hpp)
};

// unit, pulse_weight, pulse_unit, rate_unit: the program's --unit, --pulse-weight, --pulse-unit and
// --rate-unit (empty: not given).
Setup make_setup(double tau0, const std::string& type_text, const std::string& unit, const std::string& pulse_weight,
                 const std::string& pulse_unit, const std::string& rate_unit, const std::vector<std::string>& stat_names,
                 std::uint32_t stride_factor, std::uint32_t total_stride_factor, double confidence, std::optional<int> alpha,
                 bool fit, unsigned threads, bool identify_noise) {
  Setup s;
  AnalysisOptions& o = s.o;
  o.type = data_type(type_text);
  o.tau0_s = tau0;
  o.confidence = confidence;
  o.alpha = alpha;
  o.stride_factor = stride_factor;
  o.total_stride_factor = total_stride_factor;
  o.threads = threads;
  o.identify_noise = identify_noise;
  o.stats.clear();
  for (const std::string& name : stat_names) {
    const auto st = parse_dev_stat(name);
    if (!st) throw py::value_error("unknown statistic '" + name + "'");
    o.stats.push_back(*st);
  }
  s.shown = o.stats;
  s.fit = fit;
  if (fit)  // the fit uses both curves, as gyrochar-analyze --fit
    for (const DevStat st : {DevStat::oadev, DevStat::mdev})
      if (std::find(o.stats.begin(), o.stats.end(), st) == o.stats.end()) o.stats.push_back(st);
  UnitOptions units;
  units.type = o.type;
  units.unit = unit;
  units.pulse_weight = pulse_weight;
  units.pulse_unit_given = !pulse_unit.empty();
  if (units.pulse_unit_given) units.pulse_unit = pulse_unit;
  units.rate_unit_given = !rate_unit.empty();
  if (units.rate_unit_given) units.rate_unit = rate_unit;
  s.units = report_units(units);
  // What a checkpoint must be restored under besides the taus and the stride factor, which the core
  // checks itself: what the values are.
  const std::string fingerprint = fmt::format("type={} tau0={:.17g} input={}", type_text, tau0, s.units.input);
  o.checkpoint_tag = crc32(std::as_bytes(std::span(fingerprint.data(), fingerprint.size())));
  return s;
}

// Thrown by the engine's progress callback when Python has a KeyboardInterrupt pending (its error
// indicator set by PyErr_CheckSignals).
struct Interrupted {};

// The taus and the stride factor (plan.hpp) over at most n_phase phase points (0: unknown), and the
// analyzer for them.
std::unique_ptr<Analyzer> planned_analyzer(Setup& s, const std::string& taus, const std::vector<std::uint64_t>& listed,
                                           std::uint64_t n_phase) {
  AnalysisOptions& o = s.o;
  const TauPlan plan = plan_taus(o, taus, listed, n_phase, memory_budget());
  if (o.m_list.empty()) throw py::value_error(fmt::format("{} phase points are too few for any tau", n_phase / 2));
  s.not_formed = plan.not_formed;  // refused once the data reaches them (results()), as the program does
  if (!plan.held && history_bytes(o.type, o.stride_factor, o.m_list.back()) > memory_budget())
    throw py::value_error(
        fmt::format("stride factor {} with taus up to {} needs more memory than this process may use "
                    "({}): give a smaller stride factor or fewer taus",
                    o.stride_factor, o.m_list.back(), memory_budget_reason()));
  // The sums of a held record (taus "all", counts of a known length) and the total family's taus
  // may take minutes: between blocks of taus a pending KeyboardInterrupt stops them (results()).
  o.on_progress = [](const char*, std::size_t, std::size_t) {
    py::gil_scoped_acquire gil;
    if (PyErr_CheckSignals() != 0) throw Interrupted{};
  };
  try {
    return std::make_unique<Analyzer>(o);
  } catch (const std::invalid_argument& e) {
    throw py::value_error(e.what());
  }
}

// Adds the values in blocks of 2^20 without the GIL; between them a pending KeyboardInterrupt stops
// the call. `added`: values added so far, counted on (up to a refused value, which is not added).
void feed(Analyzer& analyzer, Values& values, std::uint64_t& added) {
  constexpr std::size_t chunk = 1 << 20, block = 1 << 14;
  std::size_t done = 0;
  while (done < values.size()) {
    const std::size_t end = std::min(values.size(), done + chunk);
    {
      py::gil_scoped_release release;
      for (std::size_t i = done; i < end; i += block) {
        const std::size_t n = std::min(block, end - i);
        try {
          analyzer.add(values.block(i, n));
        } catch (const BadValue& e) {
          added += e.index();
          throw std::invalid_argument(fmt::format("values[{}]: {}", added, e.what()));
        } catch (const std::range_error& e) {
          throw std::invalid_argument(fmt::format("values[{}:{}]: {}", added, added + n, e.what()));
        }
        added += n;
      }
    }
    if (PyErr_CheckSignals() != 0) throw py::error_already_set();
    done = end;
  }
}

// The results so far as a dict (see gyrochar/__init__.py), computed (and fitted) without the GIL.
py::dict results(const Analyzer& analyzer, const Setup& s) {
  const ReportUnits& units = s.units;
  Analysis a;
  std::vector<CurveFit> fits;
  bool interrupted = false;
  {
    py::gil_scoped_release release;
    try {
      a = analyzer.result();
    } catch (const std::range_error& e) {
      throw std::invalid_argument(e.what());
    } catch (const Interrupted&) {
      interrupted = true;
    }
    if (s.fit && !interrupted)
      fits = fit_curves(a, units, s.o.tau0_s, s.o.type == DataType::counts ? units.phase_unit_si / std::sqrt(12.0) : 0.0,
                        LongTau::oadev, analyzer.record());
  }
  if (interrupted) throw py::error_already_set();  // the KeyboardInterrupt PyErr_CheckSignals raised
  for (const std::uint64_t m : s.not_formed)
    if (m <= a.n_phase / 2)
      throw py::value_error(
          fmt::format("averaging factor {} cannot be formed with stride factor {}: above S it must "
                      "be a multiple of its stride (m/S rounded up to a power of two)",
                      m, a.stride_factor));
  const auto shown = [&](const AnalysisRow& r) {
    return std::find(s.shown.begin(), s.shown.end(), r.stat) != s.shown.end();
  };
  if (std::none_of(a.rows.begin(), a.rows.end(), shown))
    throw py::value_error(fmt::format("{} values are too few for any of the taus asked", a.n_values));
  for (const AnalysisRow& r : a.rows)  // the output unit must not take a value out of range
    if (shown(r) && (!std::isfinite(r.dev * units.factor()) ||
                     (r.dev != 0 && !(std::fabs(r.dev * units.factor()) >= 2.2250738585072014e-308))))
      throw py::value_error(
          fmt::format("{} at tau = {:g} s (m = {}): {:g} times the unit factor {:g} ({}) leaves a "
                      "double's range",
                      name(r.stat), r.tau_s, r.m, r.dev, units.factor(), units.unit(r.stat)));
  py::dict out;
  out["n_values"] = a.n_values;
  out["n_phase"] = a.n_phase;
  out["stride_factor"] = a.stride_factor;
  out["units_input"] = units.input;
  py::dict stats;
  for (const DevStat st : s.shown) stats[name(st)] = stat_arrays(a.rows, st, units);
  out["stats"] = stats;
  if (s.fit) {
    // The fit's part of gyrochar-analyze's JSON report, as text for json.loads.
    const Report report{a,        s.o.type,    s.o.tau0_s,   s.o.confidence, units, std::move(fits), std::nullopt,
                        "values", DataRange{}, std::nullopt, std::nullopt};
    out["fit_json"] = to_json(report)["fit"].dump();
  }
  return out;
}

// gyrochar-analyze on values in memory: the same plan (plan.hpp), engine (analysis.hpp) and fit
// (analysis_report.hpp). taus: "octave", "decade", "all", or "list" with `listed`. stride_factor
// and total_stride_factor 0: full and exact.
py::dict analyze(const py::buffer& buffer, Setup s, const std::string& taus, const std::vector<std::uint64_t>& listed) {
  Values values(buffer);
  if (values.size() == 0) throw py::value_error("no values");
  const std::uint64_t n_values = values.size();
  const std::uint64_t n_phase = s.o.type == DataType::phase ? n_values : n_values + 1;
  // The length is known: "all" plans on it; the other rules plan, as gyrochar-analyze on a file,
  // on an upper bound (twice it), so that "full" overlaps every tau up to N/2.
  s.o.values_hint = n_values;
  const std::unique_ptr<Analyzer> analyzer = planned_analyzer(s, taus, listed, taus == "all" ? n_phase : 2 * n_phase);
  std::uint64_t added = 0;
  feed(*analyzer, values, added);
  return results(*analyzer, s);
}

// The streaming characterizer: gyrochar-analyze on standard input (length unknown: taus up to
// 2^39 or the list, stride factor "full" = 2^16), fed any number of blocks of any size.
class Stream {
 public:
  Stream(Setup s, const std::string& taus, const std::vector<std::uint64_t>& listed)
      : setup_(std::move(s)), analyzer_(planned_analyzer(setup_, taus, listed, 0)) {}
  void add(const py::buffer& buffer) {
    Values values(buffer);
    feed(*analyzer_, values, added_);
  }
  py::dict estimates() const { return results(*analyzer_, setup_); }
  std::uint64_t values() const { return added_; }
  /// The core characterizer's checkpoint (the board's format), as bytes.
  py::bytes checkpoint() const {
    const std::vector<std::byte> bytes = analyzer_->checkpoint();
    return {reinterpret_cast<const char*>(bytes.data()), bytes.size()};
  }
  /// Restores checkpoint() bytes of a characterizer with the same arguments; refused ones raise
  /// ValueError with the core's reason and change nothing.
  void restore(const py::bytes& checkpoint) {
    const std::string_view text = checkpoint;
    if (const std::string why = analyzer_->restore(std::as_bytes(std::span(text.data(), text.size()))); !why.empty())
      throw py::value_error("checkpoint refused: " + why);
    added_ = analyzer_->result().n_values;
  }

 private:
  Setup setup_;
  std::unique_ptr<Analyzer> analyzer_;
  std::uint64_t added_ = 0;
};

}  // namespace

PYBIND11_MODULE(_native, m) {
  m.doc() = "gyrochar's engine (the analyzer's C++ code); use the gyrochar package, not this module";
  py::class_<Setup>(m, "Setup");
  m.def("setup", &make_setup, py::arg("tau0"), py::arg("type"), py::arg("unit"), py::arg("pulse_weight"),
        py::arg("pulse_unit"), py::arg("rate_unit"), py::arg("stats"), py::arg("stride_factor"),
        py::arg("total_stride_factor"), py::arg("confidence"), py::arg("alpha"), py::arg("fit"), py::arg("threads"),
        py::arg("identify_noise") = true);
  m.def("analyze", &analyze, py::arg("values"), py::arg("setup"), py::arg("taus"), py::arg("listed"));
  py::class_<Stream>(m, "Characterizer")
      .def(py::init<Setup, const std::string&, const std::vector<std::uint64_t>&>(), py::arg("setup"), py::arg("taus"),
           py::arg("listed"))
      .def("add", &Stream::add, py::arg("values"))
      .def("estimates", &Stream::estimates)
      .def_property_readonly("values", &Stream::values)
      .def("checkpoint", &Stream::checkpoint)
      .def("restore", &Stream::restore, py::arg("checkpoint"));
}
