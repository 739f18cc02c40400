#include "analysis.hpp"

#include <fmt/format.h>

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

#include "gyrochar/characterizer.hpp"
#include "total_analysis.hpp"

namespace gyrochar {

namespace {

// Why estimate `e` is not a finite number, for an error message. The variance is the sum of the
// squared differences over tau0^2 (phase data) or over 1 (frequency data), TDEV's times tau^2 / 3.
std::string non_finite_reason(const Estimate& e, const TauSums& sums, double tau0_s) {
  const std::string where = fmt::format("{} at tau = {:g} s (m = {})", name(e.stat), e.tau_s, e.m);
  for (const double v : sums.variance)
    if (!std::isfinite(v))
      return where + ": the squared differences of the values overflow a double (largest 1.8e308): the values "
                     "are too large; scale them";
  if (!std::isnormal(tau0_s * tau0_s) || !std::isnormal(e.tau_s * e.tau_s))
    return where + fmt::format(": tau0^2 = ({:g} s)^2 is outside the range of a double: tau0 is too {}", tau0_s,
                               tau0_s < 1 ? "small" : "large");
  return where + fmt::format(": the squared differences divided by tau0^2 = ({:g} s)^2 overflow a double", tau0_s);
}

}  // namespace

const char* name(DataType t) {
  switch (t) {
    case DataType::phase: return "phase";
    case DataType::freq: return "freq";
    case DataType::counts: return "counts";
  }
  return "?";
}

std::optional<DevStat> parse_dev_stat(const std::string& text) {
  for (const auto& list : {all_dev_stats, total_dev_stats})
    for (const DevStat s : list)
      if (text == name(s)) return s;
  return std::nullopt;
}

std::uint32_t resolve_stride_factor(std::uint32_t requested, std::uint64_t m_max) {
  if (requested != 0) return requested;
  return static_cast<std::uint32_t>(std::bit_ceil(std::clamp<std::uint64_t>(m_max, 2, full_stride_cap)));
}

std::uint32_t full_stride_factor(std::uint64_t n_phase) {
  if (n_phase == 0) return full_stride_cap;
  return static_cast<std::uint32_t>(std::bit_ceil(std::clamp<std::uint64_t>(n_phase / 4, 2, std::uint64_t{1} << 24)));
}

std::uint64_t history_bytes(DataType type, std::uint32_t stride_factor, std::uint64_t m_max) {
  const std::size_t entry = type == DataType::counts ? sizeof(CountArith::Entry) : sizeof(FloatArith::Entry);
  return std::uint64_t{history_entries(stride_factor, m_max)} * entry;
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

std::vector<std::uint64_t> theo_taus(const std::string& rule, const std::vector<std::uint64_t>& m_list,
                                     std::uint64_t n_phase) {
  const std::uint64_t last = n_phase == 0 ? std::uint64_t{1} << 40 : n_phase - 1;
  std::vector<std::uint64_t> m;
  if (rule == "all") {
    for (std::uint64_t v = 10; v <= last; v += 2) m.push_back(v);
    return m;
  }
  for (const std::uint64_t v : m_list)
    if (v >= 10 && v % 2 == 0 && v <= last) m.push_back(v);
  if (rule == "octave")
    for (std::uint64_t v = m.empty() ? 16 : 2 * m.back(); v <= last; v *= 2) m.push_back(v);
  if (rule == "decade")
    for (std::uint64_t decade = 10; decade <= last; decade *= 10)
      for (const std::uint64_t step : {1, 2, 4})
        if (decade * step <= last && (m.empty() || decade * step > m.back())) m.push_back(decade * step);
  return m;
}

namespace {

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
  virtual void add(std::span<const double> values) = 0;
  virtual Analysis result(const AnalysisOptions& o) const = 0;
  virtual PhaseRecord record(const AnalysisOptions& o) const = 0;
};

// The characterizer of one arithmetic over heap storage, and its read-out into rows.
template <class Arith>
class Engine final : public EngineBase {
  using Entry = typename Arith::Entry;

 public:
  Engine(DataType type, std::uint32_t stride_factor, const std::vector<std::uint64_t>& m_list, bool keep_record)
      : type_(type), keep_record_(keep_record), history_(history_entries(stride_factor, m_list.back())),
        states_(m_list.size()), characterizer_(history_, states_) {
    if (!history_.data()) throw std::bad_alloc();
    if (characterizer_.configure({stride_factor, 0}, m_list) != ConfigureStatus::ok)
      throw std::invalid_argument("the taus do not fit the stride factor");
  }

  void add(std::span<const double> values) override {
    if constexpr (Arith::exact) {
      // Counts go to the block API as 32-bit integers, checked first.
      if (counts_.size() < values.size()) counts_.resize(values.size());
      std::size_t n = 0;
      for (; n < values.size(); ++n) {
        const double v = values[n];
        if (!(std::fabs(v) < 2147483648.0) || v != std::trunc(v)) break;
        counts_[n] = static_cast<std::int32_t>(v);
      }
      characterizer_.add_increments(std::span<const std::int32_t>(counts_.data(), n));
      if (characterizer_.phase_overflowed()) throw std::range_error("the accumulated count passed 2^63 pulses");
      if (n < values.size()) throw BadValue(n, "a count must be an integer of magnitude below 2^31");
      for (const double v : values) keep(v);
    } else {
      for (std::size_t i = 0; i < values.size(); ++i) {
        const double v = values[i];
        if (!std::isfinite(v)) throw BadValue(i, "not a finite number");
        if (type_ == DataType::phase)
          characterizer_.add_phase_point(v);
        else
          characterizer_.add_increment(v);  // frequency: phase in units of y tau0
        keep(v);
      }
    }
  }

  Analysis result(const AnalysisOptions& o) const override {
    Analysis a;
    a.n_values = type_ == DataType::phase ? characterizer_.phase_points() : characterizer_.increments();
    a.n_phase = characterizer_.phase_points();
    a.stride_factor = characterizer_.stride_factor();
    const std::size_t taus = characterizer_.tau_count();
    std::vector<TauSums> sums(taus);
    take_sums(characterizer_, sums);
    std::vector<NoiseId> noise2(taus), noise3(taus);
    // The identification and the EDF need the same covariance sums of each tau's Allan and
    // modified Allan grids: computed once (two grids a tau, the table half full at most).
    std::vector<PairSumCache::Entry> entries(4 * taus + 16);
    PairSumCache cache(entries);
    const bool frequency_input = type_ == DataType::freq;
    if (o.alpha) {
      std::fill(noise2.begin(), noise2.end(), given_noise(*o.alpha));
      std::fill(noise3.begin(), noise3.end(), given_noise(*o.alpha));
    } else {
      identify_noise(sums, a.n_phase, 2, frequency_input, noise2, &cache);
      identify_noise(sums, a.n_phase, 3, frequency_input, noise3, &cache);
    }
    const EstimateOptions options{o.tau0_s, type_ == DataType::freq ? o.tau0_s : 1.0, o.edf};
    auto rows_of = [&](DevStat stat, std::vector<AnalysisRow>& out) {
      for (std::size_t i = 0; i < taus; ++i) {
        const NoiseId& id = stat_of(stat) == Stat::hvar ? noise3[i] : noise2[i];
        const Estimate e = estimate(sums[i], a.n_phase, stat, id, options, &cache);
        if (e.n == 0) continue;
        if (!std::isfinite(e.deviation)) throw std::range_error(non_finite_reason(e, sums[i], o.tau0_s));
        AnalysisRow row;
        row.stat = stat;
        row.m = e.m;
        row.tau_s = e.tau_s;
        row.n = e.n;
        row.dev = e.deviation;
        if (e.noise.identified()) row.alpha = e.noise.alpha;
        row.noise = e.noise;
        row.edf_alpha = e.edf_alpha;
        row.stride = e.stride;
        row.edf = e.edf;
        row.skew_dof = o.edf == EdfModel::exact ? e.skew_dof : 0.0;  // Greenhall's: Stable32's plain intervals
        if (e.edf > 0) row.ci = confidence_interval(row.dev, row.edf, o.confidence, row.skew_dof);
        out.push_back(row);
      }
    };
    std::vector<AnalysisRow> allan;  // what the total family leans on (total_analysis.hpp)
    if (std::any_of(o.stats.begin(), o.stats.end(), [](DevStat s) { return is_total(s); }))
      for (const DevStat s : {DevStat::oadev, DevStat::mdev, DevStat::ohdev}) rows_of(s, allan);
    for (const DevStat stat : o.stats) {
      if (!is_total(stat)) {
        rows_of(stat, a.rows);
        continue;
      }
      const auto total = total_rows(stat, record_, options.unit, o, allan);
      a.rows.insert(a.rows.end(), total.begin(), total.end());
    }
    return a;
  }

  PhaseRecord record(const AnalysisOptions& o) const override {
    return {record_, type_ == DataType::freq ? o.tau0_s : 1.0};
  }

 private:
  // The record for the total family, in the characterizer's phase representation: phase relative
  // to the first point (the statistics ignore a constant), or the running sum of the increments.
  void keep(double value) {
    if (!keep_record_) return;
    if (type_ == DataType::phase) {
      if (record_.empty()) first_ = value;
      record_.push_back(value - first_);
    } else {
      if (record_.empty()) record_.push_back(0.0);
      record_.push_back(record_.back() + value);
    }
  }

  DataType type_;
  bool keep_record_;
  double first_ = 0.0;
  std::vector<double> record_;
  ZeroedArray<Entry> history_;
  std::vector<typename Characterizer<Arith>::TauState> states_;
  Characterizer<Arith> characterizer_;
  std::vector<std::int32_t> counts_;  // a block of counts on its way to the block API
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
  for (std::size_t i = 1; i < o.theo_m_list.size(); ++i)
    if (o.theo_m_list[i] <= o.theo_m_list[i - 1]) throw std::invalid_argument("Theo1 averaging factors must increase");
  impl_->options = o;
  const bool keep_record = o.keep_record || std::any_of(o.stats.begin(), o.stats.end(), [](DevStat s) { return is_total(s); });
  if (o.type == DataType::counts)
    impl_->engine = std::make_unique<Engine<CountArith>>(o.type, s, o.m_list, keep_record);
  else
    impl_->engine = std::make_unique<Engine<FloatArith>>(o.type, s, o.m_list, keep_record);
}

Analyzer::~Analyzer() = default;

void Analyzer::add(std::span<const double> values) { impl_->engine->add(values); }

Analysis Analyzer::result() const { return impl_->engine->result(impl_->options); }

PhaseRecord Analyzer::record() const { return impl_->engine->record(impl_->options); }

}  // namespace gyrochar
