#include "analysis.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdlib>
#include <new>
#include <span>
#include <stdexcept>
#include <string>
#include <type_traits>

#include "gyrochar/edf.hpp"
#include "gyrochar/noise_id.hpp"
#include "gyrochar/pyramid.hpp"

namespace gyrochar {

const char* name(DataType t) {
  switch (t) {
    case DataType::phase: return "phase";
    case DataType::freq: return "freq";
    case DataType::counts: return "counts";
  }
  return "?";
}

const char* name(DevStat s) {
  switch (s) {
    case DevStat::adev: return "adev";
    case DevStat::oadev: return "oadev";
    case DevStat::mdev: return "mdev";
    case DevStat::tdev: return "tdev";
    case DevStat::hdev: return "hdev";
    case DevStat::ohdev: return "ohdev";
  }
  return "?";
}

std::optional<DevStat> parse_dev_stat(const std::string& text) {
  for (const DevStat s : {DevStat::adev, DevStat::oadev, DevStat::mdev, DevStat::tdev, DevStat::hdev, DevStat::ohdev})
    if (text == name(s)) return s;
  return std::nullopt;
}

std::uint32_t resolve_stride_factor(std::uint32_t requested, std::uint64_t m_max) {
  if (requested != 0) return requested;
  return static_cast<std::uint32_t>(std::bit_ceil(std::clamp<std::uint64_t>(m_max, 2, full_stride_cap)));
}

bool tau_representable(std::uint64_t m, std::uint32_t stride_factor) {
  if (m == 0) return false;
  std::uint64_t stride = 1;
  while (m > stride * stride_factor) stride *= 2;
  return m % stride == 0;
}

std::vector<std::uint64_t> octave_taus(std::uint64_t n_phase) {
  const std::uint64_t limit = n_phase == 0 ? std::uint64_t{1} << 39 : n_phase / 2;
  std::vector<std::uint64_t> m;
  for (std::uint64_t v = 1; v <= limit; v *= 2) m.push_back(v);
  return m;
}

std::vector<std::uint64_t> decade_taus(std::uint64_t n_phase) {
  std::vector<std::uint64_t> m;
  for (std::uint64_t decade = 1; decade <= n_phase / 2; decade *= 10)
    for (const std::uint64_t step : {1, 2, 4})
      if (decade * step <= n_phase / 2) m.push_back(decade * step);
  return m;
}

std::vector<std::uint64_t> all_taus(std::uint64_t n_phase, std::uint32_t stride_factor) {
  std::vector<std::uint64_t> m;
  for (std::uint64_t v = 1, stride = 1; v <= n_phase / 2; v += stride) {
    if (v > stride * stride_factor) stride *= 2;  // v = S 2^L + 2^(L-1) here: next multiple of 2^L
    if (v % stride != 0) v += stride - v % stride;
    if (v <= n_phase / 2) m.push_back(v);
  }
  return m;
}

namespace {

// Phase relative to the line through the first two points, x'_k = (x_k - x_0) - k (x_1 - x_0).
// Second and higher differences are unchanged, and x' stays about as small as the noise, which
// keeps the pyramid's prefix sums small. x_k - x_0 is formed exactly (as hi + lo) and the line is
// taken off by one fused multiply-add, so x' carries about one rounding of its own (small) size.
class ReferenceLine {
 public:
  double relative(double x) {
    const std::uint64_t k = k_++;
    if (k == 0) x0_ = x;
    const double hi = x - x0_;
    const double b = hi - x;
    const double lo = (x - (hi - b)) - (x0_ + b);
    if (k == 1) slope_ = hi;
    return std::fma(-static_cast<double>(k), slope_, hi) + lo;
  }

 private:
  std::uint64_t k_ = 0;
  double x0_ = 0.0;
  double slope_ = 0.0;
};

// Zero-filled storage from calloc, whose pages the system maps on first write: the pyramid's
// history rings for long taus cost memory only once the data reaches them (a short input with
// the 2^16 stride factor and taus up to 2^39 stays small). The entries are aggregates of numbers,
// for which all-zero bytes are the zero value.
struct FreeDeleter {
  void operator()(void* p) const { std::free(p); }
};
template <class T>
class ZeroedArray {
  static_assert(std::is_trivially_copyable_v<T>);

 public:
  explicit ZeroedArray(std::size_t n) : data_(static_cast<T*>(std::calloc(n, sizeof(T)))), size_(data_ ? n : 0) {}
  T* data() const { return data_.get(); }
  operator std::span<T>() const { return {data_.get(), size_}; }

 private:
  std::unique_ptr<T[], FreeDeleter> data_;
  std::size_t size_;
};

struct EngineBase {
  virtual ~EngineBase() = default;
  virtual void add(double value) = 0;
  virtual Analysis result(const AnalysisOptions& o) const = 0;
};

// Everything that depends on the arithmetic: the pyramid (overlapping statistics), Stable32's
// non-overlapped ADEV/HDEV and the decimated series for noise identification.
template <class Arith>
class Engine final : public EngineBase {
  using Entry = typename Arith::Entry;
  using X = decltype(Entry{}.x);
  using Sum = typename Arith::Sum;

 public:
  Engine(DataType type, std::uint32_t stride_factor, const std::vector<std::uint64_t>& m_list)
      : type_(type), m_list_(m_list), history_(history_entries(stride_factor, m_list.back())),
        states_(m_list.size()), pyramid_(history_, states_), decimated_(m_list.size()) {
    if (!history_.data()) throw std::bad_alloc();
    if (pyramid_.configure({stride_factor, false}, m_list_) != PyramidStatus::ok)
      throw std::invalid_argument("the taus do not fit the stride factor");
  }

  void add(double value) override {
    if constexpr (Arith::exact) {
      if (!(std::fabs(value) < 2147483648.0) || value != std::trunc(value))
        throw std::invalid_argument("a count must be an integer of magnitude below 2^31");
      const auto count = static_cast<std::int32_t>(value);
      if (values_ == 0) point(0);
      if (__builtin_add_overflow(x_, std::int64_t{count}, &x_))
        throw std::range_error("the accumulated count passed 2^63 pulses");
      pyramid_.add_increment(count);
      point(x_);
    } else {
      if (!std::isfinite(value)) throw std::invalid_argument("not a finite number");
      if (type_ == DataType::phase) {
        const double x = line_.relative(value);
        pyramid_.add_phase_point(x);
        point(x);
      } else {  // frequency, integrated relative to the first value: phase in units of y tau0
        if (values_ == 0) {
          y0_ = value;
          point(0.0);
        }
        const double dy = value - y0_;
        x_ += dy;
        pyramid_.add_increment(dy);
        point(x_);
      }
    }
    ++values_;
  }

  Analysis result(const AnalysisOptions& o) const override {
    Analysis a;
    a.n_values = values_;
    a.n_phase = pyramid_.phase_points();
    a.stride_factor = pyramid_.stride_factor();
    for (const DevStat stat : o.stats)
      for (std::size_t i = 0; i < m_list_.size(); ++i)
        if (const auto row = make_row(o, stat, i)) a.rows.push_back(*row);
    return a;
  }

 private:
  // Non-overlapped terms (j = 0, m, 2m, ...) and the decimated series x[k m] for noise ID.
  struct Decimated {
    std::uint64_t countdown = 0;  // phase points until the next multiple of m
    std::array<X, 3> back{};      // x at e - m, e - 2m, e - 3m
    int have = 0;                 // entries of `back` filled
    Sum sum_avar{}, sum_hvar{};
    std::uint64_t n_avar = 0, n_hvar = 0;
    NoiseIdAccumulator noise;
  };

  void point(X x) {
    for (std::size_t i = 0; i < decimated_.size(); ++i) {
      Decimated& d = decimated_[i];
      if (d.countdown-- != 0) continue;
      d.countdown = m_list_[i] - 1;
      X a{}, h{};
      if (d.have >= 2 && Arith::x_term2(x, d.back[0], d.back[1], a)) {
        Arith::accumulate(d.sum_avar, a);
        ++d.n_avar;
      }
      if (d.have >= 3 && Arith::x_terms(x, d.back[0], d.back[1], d.back[2], a, h)) {
        Arith::accumulate(d.sum_hvar, h);
        ++d.n_hvar;
      }
      d.back = {x, d.back[0], d.back[1]};
      if (d.have < 3) ++d.have;
      d.noise.add(static_cast<double>(x));
    }
  }

  std::optional<AnalysisRow> make_row(const AnalysisOptions& o, DevStat stat, std::size_t i) const {
    const auto r = pyramid_.result(i);
    const Decimated& dec = decimated_[i];
    const double unit = type_ == DataType::freq ? o.tau0_s : 1.0;  // phase unit per x step
    AnalysisRow row;
    row.stat = stat;
    row.m = m_list_[i];
    row.tau_s = static_cast<double>(row.m) * o.tau0_s;
    row.stride = pyramid_.stride(i);
    double var = 0.0;
    EdfStat edf_stat = EdfStat::avar;
    switch (stat) {
      case DevStat::adev:  // the AVAR formula over the non-overlapped terms
        row.n = dec.n_avar;
        row.stride = row.m;
        if (row.n) var = Arith::to_double(dec.sum_avar) * unit * unit / (2.0 * static_cast<double>(row.n) * row.tau_s * row.tau_s);
        break;
      case DevStat::oadev:
        row.n = r.n[0];
        var = variance(r, Stat::avar, o.tau0_s, unit);
        break;
      case DevStat::mdev:
      case DevStat::tdev:
        row.n = r.n[1];
        var = variance(r, Stat::mvar, o.tau0_s, unit);
        edf_stat = EdfStat::mvar;
        break;
      case DevStat::hdev:  // the HVAR formula over the non-overlapped terms
        row.n = dec.n_hvar;
        row.stride = row.m;
        if (row.n) var = Arith::to_double(dec.sum_hvar) * unit * unit / (6.0 * static_cast<double>(row.n) * row.tau_s * row.tau_s);
        edf_stat = EdfStat::hvar;
        break;
      case DevStat::ohdev:
        row.n = r.n[2];
        var = variance(r, Stat::hvar, o.tau0_s, unit);
        edf_stat = EdfStat::hvar;
        break;
    }
    if (row.n == 0) return std::nullopt;
    row.dev = stat == DevStat::tdev ? std::sqrt(tvar_from_mvar(var, row.tau_s)) : std::sqrt(var);
    row.alpha = o.alpha;
    if (!row.alpha) {
      NoiseIdInput in;
      in.m = row.m;
      in.dmax = edf_stat == EdfStat::hvar ? 3 : 2;
      in.frequency_data = type_ == DataType::freq;
      in.tau0_s = o.tau0_s;
      in.avar = variance(r, Stat::avar, o.tau0_s);
      in.mvar = variance(r, Stat::mvar, o.tau0_s);
      const NoiseId id = identify_noise(dec.noise, in);
      if (id.method != NoiseIdMethod::none) row.alpha = id.alpha;
    }
    if (row.alpha) {
      row.edf = edf_for(edf_stat, *row.alpha, row.m, row.stride, pyramid_.phase_points());
      row.ci = confidence_interval(row.dev, row.edf, o.confidence);
    }
    return row;
  }

  DataType type_;
  std::vector<std::uint64_t> m_list_;
  ZeroedArray<Entry> history_;
  std::vector<typename Pyramid<Arith>::TauState> states_;
  Pyramid<Arith> pyramid_;
  std::vector<Decimated> decimated_;
  std::uint64_t values_ = 0;
  X x_{};             // running phase (counts, frequency)
  double y0_ = 0.0;   // first frequency value
  ReferenceLine line_;
};

}  // namespace

struct Analyzer::Impl {
  AnalysisOptions options;
  std::unique_ptr<EngineBase> engine;
};

Analyzer::Analyzer(const AnalysisOptions& options) : impl_(std::make_unique<Impl>()) {
  const AnalysisOptions& o = options;
  if (!(o.tau0_s > 0) || !std::isfinite(o.tau0_s)) throw std::invalid_argument("tau0 must be a positive number of seconds");
  if (o.m_list.empty()) throw std::invalid_argument("no taus to compute");
  if (o.stats.empty()) throw std::invalid_argument("no statistics asked for");
  if (!(o.confidence > 0 && o.confidence < 1)) throw std::invalid_argument("the confidence must be between 0 and 1");
  for (std::size_t i = 0; i < o.m_list.size(); ++i)
    if (o.m_list[i] == 0 || (i > 0 && o.m_list[i] <= o.m_list[i - 1]))
      throw std::invalid_argument("averaging factors must be positive and strictly increasing");
  if (o.stride_factor != 0 && (o.stride_factor < 2 || !std::has_single_bit(o.stride_factor) || o.stride_factor > (1u << 24)))
    throw std::invalid_argument("the stride factor must be a power of two from 2 to 2^24");
  const std::uint32_t s = resolve_stride_factor(o.stride_factor, o.m_list.back());
  for (const std::uint64_t m : o.m_list)
    if (!tau_representable(m, s))
      throw std::invalid_argument("averaging factor " + std::to_string(m) + " cannot be formed with stride factor " +
                                  std::to_string(s) + ": above S it must be a multiple of its stride (m/S rounded up to a power of two)");
  impl_->options = o;
  if (o.type == DataType::counts)
    impl_->engine = std::make_unique<Engine<CountArith>>(o.type, s, o.m_list);
  else
    impl_->engine = std::make_unique<Engine<FloatArith>>(o.type, s, o.m_list);
}

Analyzer::~Analyzer() = default;

void Analyzer::add(double value) { impl_->engine->add(value); }

Analysis Analyzer::result() const { return impl_->engine->result(impl_->options); }

}  // namespace gyrochar
