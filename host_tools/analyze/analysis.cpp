#include "analysis.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cfloat>
#include <cmath>
#include <cstdlib>
#include <exception>
#include <map>
#include <new>
#include <span>
#include <stdexcept>
#include <string>
#include <thread>
#include <type_traits>

#include "gyrochar/batch.hpp"
#include "edf_table.hpp"
#include "gyrochar/characterizer.hpp"
#include "gyrochar/float_batch.hpp"
#include "total_analysis.hpp"
#include "analysis_engine.hpp"

namespace gyrochar {

namespace {

// "oadev at tau = 1 s (m = 1)": the start of an estimate's error message.
std::string where_of(const Estimate& e) { return fmt::format("{} at tau = {:g} s (m = {})", name(e.stat), e.tau_s, e.m); }

// Whether tau0^2 or tau^2 leaves the normal range of a double, and so it says.
bool tau0_out_of_range(const Estimate& e, double tau0_s, std::string& why) {
  if (std::isnormal(tau0_s * tau0_s) && std::isnormal(e.tau_s * e.tau_s)) return false;
  why = where_of(e) + fmt::format(": tau0^2 = ({:g} s)^2 is outside the range of a double: tau0 is too {}", tau0_s,
                                  tau0_s < 1 ? "small" : "large");
  return true;
}

// Why estimate `e` is not a finite number, for an error message. The variance is the sum of the
// squared differences over tau0^2 (phase data) or over 1 (frequency data), TDEV's times tau^2 / 3.
std::string non_finite_reason(const Estimate& e, const TauSums& sums, double tau0_s) {
  const std::string where = where_of(e);
  for (const double v : sums.variance)
    if (!std::isfinite(v))
      return where +
             ": the squared differences of the values overflow a double (largest 1.8e308): the values "
             "are too large; scale them";
  if (std::string why; tau0_out_of_range(e, tau0_s, why)) return why;
  return where + fmt::format(": the squared differences divided by tau0^2 = ({:g} s)^2 overflow a double", tau0_s);
}

// The other end: why the finite estimate `e` lost its value to underflow (a deviation of 0 or of
// a few bits that the data do not have), or "" when it did not. Its tau is not finite; the sums'
// variance (at tau0 = 1) is positive but below the smallest normal double (the squares of the
// differences underflowed); or the division by tau0^2 takes a positive variance there.
std::string underflow_reason(const Estimate& e, const TauSums& sums, double tau0_s) {
  const std::string where = where_of(e);
  if (!std::isfinite(e.tau_s))
    return where + fmt::format(": tau = m tau0 = {} x {:g} s is not a finite number: tau0 is too large", e.m, tau0_s);
  const double v = sums.variance[static_cast<std::size_t>(sum_kind(e.stat))];
  if (v > 0 && v < DBL_MIN)
    return where +
           ": the squared differences of the values underflow a double (smallest normal 2.2e-308): the "
           "values are too small; scale them";
  if (!(v > 0) || e.variance >= DBL_MIN) return {};
  if (std::string why; tau0_out_of_range(e, tau0_s, why)) return why;
  return where + fmt::format(
                     ": the squared differences divided by tau0^2 = ({:g} s)^2 underflow a double (smallest "
                     "normal 2.2e-308): the values are too small for this tau0; scale them",
                     tau0_s);
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
  for (const DevStatInfo& s : dev_stats)
    if (text == s.name) return s.stat;
  return std::nullopt;
}

std::string dev_stat_names(const char* separator) {
  std::string names;
  for (const DevStatInfo& s : dev_stats) names += (names.empty() ? "" : separator) + std::string(s.name);
  return names;
}

bool valid_stride_factor(std::uint32_t s, bool held) {
  return s >= 2 && std::has_single_bit(s) && s <= (held ? held_stride_cap : 1u << 24);
}

std::uint32_t resolve_stride_factor(std::uint32_t requested, std::uint64_t m_max) {
  if (requested != 0) return requested;
  return static_cast<std::uint32_t>(std::bit_ceil(std::clamp<std::uint64_t>(m_max, 2, full_stride_cap)));
}

std::uint32_t full_stride_factor(std::uint64_t n_phase, bool held) {
  if (n_phase == 0) return full_stride_cap;
  const std::uint64_t cap = held ? held_stride_cap : 1u << 24;
  return static_cast<std::uint32_t>(std::bit_ceil(std::clamp<std::uint64_t>(n_phase / 4, 2, cap)));
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

constexpr std::uint64_t dense_from = 64;

// A dense tau list (at least every other m from 64 on, fully overlapped: --taus all) takes the
// exact EDF of an overlapping statistic from an interpolating table (edf_table.hpp) from m = 64 on:
// the exact one of every m would cost O(N) covariance sums a tau. Null otherwise.
std::unique_ptr<EdfTable> dense_edf_table(DevStat stat, const std::vector<TauSums>& sums, std::uint64_t n_phase,
                                          EdfModel model, PairSumCache& cache) {
  constexpr std::uint64_t m_min = dense_from;
  const SumKind k = sum_kind(stat);
  if (model != EdfModel::exact || (k != SumKind::avar && k != SumKind::mvar && k != SumKind::hvar)) return nullptr;
  std::uint64_t m_max = 0, dense = 0;
  for (const TauSums& t : sums) {
    if (t.m < m_min || t.stride != 1 || unbroken_grid(stat_of(stat), t.m, 1, n_phase).n == 0) continue;
    m_max = t.m;
    ++dense;
  }
  if (m_max == 0 || 2 * dense < m_max - m_min + 1) return nullptr;
  return std::make_unique<EdfTable>(stat, n_phase, m_min, m_max, cache);
}

}  // namespace

namespace {

bool any_total(const AnalysisOptions& o) {
  return std::any_of(o.stats.begin(), o.stats.end(), [](DevStat s) { return is_total(s); });
}

// Whether the read-out identifies the noise of a curve: Hadamard's (dmax 3) for hdev and ohdev,
// Allan's for the others; both for the total family (it leans on all three statistics' rows).
bool identifies(const AnalysisOptions& o, bool hadamard) {
  if (any_total(o)) return true;
  if (o.alpha || !o.identify_noise) return false;
  return std::any_of(o.stats.begin(), o.stats.end(), [&](DevStat s) { return (stat_of(s) == Stat::hvar) == hadamard; });
}

}  // namespace

unsigned sums_needed(const AnalysisOptions& o) {
  if (any_total(o)) return all_sums | noise_sums;
  unsigned kinds = 0;
  for (const DevStat s : o.stats) kinds |= sum_bit(sum_kind(s));
  if (identifies(o, false) || identifies(o, true)) kinds |= sum_bit(SumKind::avar) | sum_bit(SumKind::mvar) | noise_sums;
  return kinds;
}

// The read-out every engine shares: the noise identification of every tau (Allan and Hadamard
// curves, each where a statistic asked for needs it), then each statistic's rows with their EDF and
// interval, and the total family from the record. `a` has its counts filled in; the rows are
// appended.
void read_out(Analysis& a, const std::vector<TauSums>& sums, DataType type, const AnalysisOptions& o, PhaseSpan record) {
  const std::size_t taus = sums.size();
  std::vector<NoiseId> noise2(taus), noise3(taus);
  // The identification and the EDF need the same covariance sums of each tau's Allan and
  // modified Allan grids: computed once (two grids a tau, the table half full at most).
  // (A dense list's taus take theirs from DenseNoiseSums below, not from the table: its size
  // stays that of a few thousand taus.)
  std::vector<PairSumCache::Entry> entries(4 * std::min<std::size_t>(taus, 4096) + 16);
  PairSumCache cache(entries);
  const bool frequency_input = type == DataType::freq;
  // Dense taus: the EDF from tables, and the identification's pair sums put in the cache, both
  // exact at anchors and interpolated between them (edf_table.hpp).
  std::map<DevStat, std::unique_ptr<EdfTable>> tables;
  std::unique_ptr<DenseNoiseSums> dense_sums;
  const bool identify_allan = identifies(o, false), identify_hadamard = identifies(o, true);
  for (const DevStat stat : o.stats)
    for (const DevStat s :
         is_total(stat) ? std::vector<DevStat>{DevStat::oadev, DevStat::mdev, DevStat::ohdev} : std::vector{stat})
      if (!tables.contains(s))
        tables[s] = o.alpha || identifies(o, stat_of(s) == Stat::hvar) ? dense_edf_table(s, sums, a.n_phase, o.edf, cache)
                                                                       : nullptr;  // no EDF without a noise
  if (!o.alpha && std::any_of(tables.begin(), tables.end(), [](const auto& t) { return t.second != nullptr; })) {
    std::vector<std::uint64_t> m_list;
    for (const TauSums& t : sums)
      if (t.stride == 1) m_list.push_back(t.m);
    dense_sums = std::make_unique<DenseNoiseSums>(m_list, a.n_phase, dense_from, cache);
    cache.attach(dense_sums.get());
  }
  if (o.alpha) {
    std::fill(noise2.begin(), noise2.end(), given_noise(*o.alpha));
    std::fill(noise3.begin(), noise3.end(), given_noise(*o.alpha));
  } else {
    if (identify_allan) identify_noise(sums, a.n_phase, 2, frequency_input, noise2, &cache);
    if (identify_hadamard) identify_noise(sums, a.n_phase, 3, frequency_input, noise3, &cache);
  }
  const EstimateOptions options{o.tau0_s, type == DataType::freq ? o.tau0_s : 1.0, o.edf};
  auto rows_of = [&](DevStat stat, std::vector<AnalysisRow>& out) {
    const EdfTable* table = tables[stat].get();
    for (std::size_t i = 0; i < taus; ++i) {
      const NoiseId& id = stat_of(stat) == Stat::hvar ? noise3[i] : noise2[i];
      const bool interpolated = table && table->covers(sums[i].m) && sums[i].stride == 1;
      const Estimate e = interpolated ? table->estimate(sums[i], a.n_phase, id, options)
                                      : estimate(sums[i], a.n_phase, stat, id, options, &cache);
      if (e.n == 0) continue;
      if (!std::isfinite(e.deviation)) throw std::range_error(non_finite_reason(e, sums[i], o.tau0_s));
      if (const std::string why = underflow_reason(e, sums[i], o.tau0_s); !why.empty()) throw std::range_error(why);
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
  if (any_total(o))
    for (const DevStat s : {DevStat::oadev, DevStat::mdev, DevStat::ohdev}) rows_of(s, allan);
  LagSumRecord lag_sums;  // one preparation shared by Theo1, TheoH, MTOTDEV and TTOTDEV
  for (const DevStat stat : o.stats) {
    if (!is_total(stat)) {
      rows_of(stat, a.rows);
      continue;
    }
    // Counts' sums are exact integer sums of the held record's own terms (CountArith, batch.hpp).
    const std::span<const TauSums> exact = type == DataType::counts ? std::span<const TauSums>(sums)
                                                                    : std::span<const TauSums>();
    const auto total = total_rows(stat, record, options.unit, o, allan, exact, lag_sums);
    a.rows.insert(a.rows.end(), total.begin(), total.end());
  }
  a.theoh_bias = lag_sums.theoh_bias;
}

namespace {

// A refused checkpoint in words (the core's RestoreStatus).
std::string restore_reason(RestoreStatus s, const char* field) {
  switch (s) {
    case RestoreStatus::ok: return "";
    case RestoreStatus::truncated: return "truncated: fewer bytes than the checkpoint needs";
    case RestoreStatus::not_a_checkpoint: return "not a gyrochar checkpoint (wrong magic number)";
    case RestoreStatus::wrong_version: return "written by another checkpoint format version";
    case RestoreStatus::corrupted: return "CRC mismatch (corrupted)";
    case RestoreStatus::config_mismatch:
      return "written under another configuration (data type, tau0, units, stride factor or taus)";
    case RestoreStatus::other_identity: return "written for another instrument";
    case RestoreStatus::invalid_state: return std::string("invalid state: ") + field;
  }
  return "refused";
}

// The characterizer of one arithmetic over heap storage, and its read-out into rows.
template <class Arith>
class Engine final : public EngineBase {
  using Entry = typename Arith::Entry;

 public:
  Engine(DataType type, std::uint32_t stride_factor, const std::vector<std::uint64_t>& m_list, bool keep_record,
         std::uint32_t tag)
      : type_(type),
        record_(type, keep_record),
        history_(history_entries(stride_factor, m_list.back())),
        states_(m_list.size()),
        characterizer_(history_, states_) {
    if (!history_.data()) throw std::bad_alloc();
    if (characterizer_.configure({stride_factor, tag}, m_list) != ConfigureStatus::ok)
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
      for (const double v : values) record_.keep(v);
    } else {
      for (std::size_t i = 0; i < values.size(); ++i) {
        const double v = values[i];
        if (!std::isfinite(v)) throw BadValue(i, "not a finite number");
        if (type_ == DataType::phase) characterizer_.add_phase_point(v);
        else characterizer_.add_increment(v);  // frequency: phase in units of y tau0
        record_.keep(v);
      }
    }
  }

  Analysis result(const AnalysisOptions& o) const override {
    Analysis a;
    a.n_values = type_ == DataType::phase ? characterizer_.phase_points() : characterizer_.increments();
    a.n_phase = characterizer_.phase_points();
    a.stride_factor = characterizer_.stride_factor();
    std::vector<TauSums> sums(characterizer_.tau_count());
    take_sums(characterizer_, sums);
    read_out(a, sums, type_, o, record_.points);
    return a;
  }

  PhaseRecord record(const AnalysisOptions& o) const override {
    return {record_.points, type_ == DataType::freq ? o.tau0_s : 1.0};
  }

  std::vector<std::byte> checkpoint() const override {
    if (record_.on) return EngineBase::checkpoint();
    std::vector<std::byte> bytes(characterizer_.checkpoint_size());
    bytes.resize(characterizer_.save(bytes));
    return bytes;
  }

  std::string restore(std::span<const std::byte> bytes) override {
    if (record_.on) return EngineBase::restore(bytes);
    return restore_reason(characterizer_.restore(bytes), characterizer_.restore_field());
  }

 private:
  DataType type_;
  KeptRecord record_;
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
  const bool held = o.type == DataType::counts ? o.hold_counts : o.hold_phase;
  if (o.stride_factor != 0 && !valid_stride_factor(o.stride_factor, held))
    throw std::invalid_argument(held ? "the stride factor must be a power of two from 2 to 2^31"
                                     : "the stride factor must be a power of two from 2 to 2^24");
  const std::uint32_t s = resolve_stride_factor(o.stride_factor, o.m_list.back());
  for (const std::uint64_t m : o.m_list)
    if (!tau_representable(m, s))
      throw std::invalid_argument("averaging factor " + std::to_string(m) + " cannot be formed with stride factor " +
                                  std::to_string(s) +
                                  ": above S it must be a multiple of its stride (m/S rounded up to a power of two)");
  for (std::size_t i = 1; i < o.theo_m_list.size(); ++i)
    if (o.theo_m_list[i] <= o.theo_m_list[i - 1]) throw std::invalid_argument("Theo1 averaging factors must increase");
  impl_->options = o;
  const bool keep_record = o.keep_record ||
                           std::any_of(o.stats.begin(), o.stats.end(), [](DevStat s) { return is_total(s); });
  if (held && o.type == DataType::counts) impl_->engine = make_count_batch_engine(s, o.m_list, keep_record, o.values_hint);
  else if (held)
    impl_->engine = make_float_batch_engine(o.type, s, o.m_list, keep_record, o.values_hint, o.hold_prefix_sums);
  else if (o.type == DataType::counts)
    impl_->engine = std::make_unique<Engine<CountArith>>(o.type, s, o.m_list, keep_record, o.checkpoint_tag);
  else impl_->engine = std::make_unique<Engine<FloatArith>>(o.type, s, o.m_list, keep_record, o.checkpoint_tag);
}

Analyzer::~Analyzer() = default;

void Analyzer::add(std::span<const double> values) { impl_->engine->add(values); }

Analysis Analyzer::result() const { return impl_->engine->result(impl_->options); }

PhaseRecord Analyzer::record() const { return impl_->engine->record(impl_->options); }

HeldCounts Analyzer::held_counts() const { return impl_->engine->held_counts(); }

std::vector<std::byte> Analyzer::checkpoint() const { return impl_->engine->checkpoint(); }

std::string Analyzer::restore(std::span<const std::byte> bytes) { return impl_->engine->restore(bytes); }

}  // namespace gyrochar
