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

#include <sys/mman.h>

#include "gyrochar/batch.hpp"
#include "edf_table.hpp"
#include "gyrochar/characterizer.hpp"
#include "gyrochar/float_batch.hpp"
#include "total_analysis.hpp"

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
      return where + ": the squared differences of the values overflow a double (largest 1.8e308): the values "
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
    return where + ": the squared differences of the values underflow a double (smallest normal 2.2e-308): the "
                   "values are too small; scale them";
  if (!(v > 0) || e.variance >= DBL_MIN) return {};
  if (std::string why; tau0_out_of_range(e, tau0_s, why)) return why;
  return where + fmt::format(": the squared differences divided by tau0^2 = ({:g} s)^2 underflow a double (smallest "
                             "normal 2.2e-308): the values are too small for this tau0; scale them", tau0_s);
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

// The read-out every engine shares: the noise identification of every tau (Allan and Hadamard
// curves), then each statistic's rows with their EDF and interval, and the total family from the
// record. `a` has its counts filled in; the rows are appended.
void read_out(Analysis& a, const std::vector<TauSums>& sums, DataType type, const AnalysisOptions& o,
              std::span<const double> record) {
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
  for (const DevStat stat : o.stats)
    for (const DevStat s : is_total(stat) ? std::vector<DevStat>{DevStat::oadev, DevStat::mdev, DevStat::ohdev} : std::vector{stat})
      if (!tables.contains(s)) tables[s] = dense_edf_table(s, sums, a.n_phase, o.edf, cache);
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
    identify_noise(sums, a.n_phase, 2, frequency_input, noise2, &cache);
    identify_noise(sums, a.n_phase, 3, frequency_input, noise3, &cache);
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
  if (std::any_of(o.stats.begin(), o.stats.end(), [](DevStat s) { return is_total(s); }))
    for (const DevStat s : {DevStat::oadev, DevStat::mdev, DevStat::ohdev}) rows_of(s, allan);
  for (const DevStat stat : o.stats) {
    if (!is_total(stat)) {
      rows_of(stat, a.rows);
      continue;
    }
    const auto total = total_rows(stat, record, options.unit, o, allan);
    a.rows.insert(a.rows.end(), total.begin(), total.end());
  }
}

struct EngineBase {
  virtual ~EngineBase() = default;
  virtual void add(std::span<const double> values) = 0;
  virtual Analysis result(const AnalysisOptions& o) const = 0;
  virtual PhaseRecord record(const AnalysisOptions& o) const = 0;
  virtual std::vector<std::byte> checkpoint() const { throw std::invalid_argument(no_checkpoint); }
  virtual std::string restore(std::span<const std::byte>) { throw std::invalid_argument(no_checkpoint); }
  static constexpr const char* no_checkpoint =
      "a checkpoint holds the characterizer's state, not a held record: not with the total family or a "
      "record of known length held in memory";
};

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

// The record for the total family, in the characterizer's phase representation: phase relative
// to the first point (the statistics ignore a constant), or the running sum of the increments.
struct KeptRecord {
  KeptRecord(DataType data_type, bool keep_it) : type(data_type), on(keep_it) {}
  void keep(double value) {
    if (!on) return;
    if (type == DataType::phase) {
      if (points.empty()) first = value;
      points.push_back(value - first);
    } else {
      if (points.empty()) points.push_back(0.0);
      points.push_back(points.back() + value);
    }
  }
  DataType type;
  bool on;
  double first = 0.0;
  std::vector<double> points;
};

// The characterizer of one arithmetic over heap storage, and its read-out into rows.
template <class Arith>
class Engine final : public EngineBase {
  using Entry = typename Arith::Entry;

 public:
  Engine(DataType type, std::uint32_t stride_factor, const std::vector<std::uint64_t>& m_list, bool keep_record,
         std::uint32_t tag)
      : type_(type), record_(type, keep_record), history_(history_entries(stride_factor, m_list.back())),
        states_(m_list.size()), characterizer_(history_, states_) {
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
        if (type_ == DataType::phase)
          characterizer_.add_phase_point(v);
        else
          characterizer_.add_increment(v);  // frequency: phase in units of y tau0
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

// Storage for a held record: from 4 MiB on, in transparent huge pages (2 MiB pages fault 512
// times less often than 4 KiB ones: at 10^7 counts the faults cost as much as reading the file);
// the system's default for them is to be asked (madvise). Elements are left uninitialized by
// resize(): every one is written before it is read.
template <class T>
struct HeldAllocator {
  static_assert(std::is_trivially_copyable_v<T>);
  using value_type = T;
  static constexpr std::size_t huge_page = std::size_t{1} << 21;
  HeldAllocator() = default;
  template <class U>
  HeldAllocator(const HeldAllocator<U>&) {}
  T* allocate(std::size_t n) {
    if (n > SIZE_MAX / sizeof(T) - huge_page) throw std::bad_alloc();
    const std::size_t bytes = n * sizeof(T);
    if (bytes < 2 * huge_page) return std::allocator<T>().allocate(n);
    void* p = std::aligned_alloc(huge_page, (bytes + huge_page - 1) / huge_page * huge_page);
    if (!p) throw std::bad_alloc();
    madvise(p, bytes, MADV_HUGEPAGE);  // a hint: without it, 4 KiB pages
    return static_cast<T*>(p);
  }
  void deallocate(T* p, std::size_t n) {
    if (n * sizeof(T) < 2 * huge_page) {
      std::allocator<T>().deallocate(p, n);
    } else {
      std::free(p);
    }
  }
  template <class U>
  void construct(U* p) {
    ::new (static_cast<void*>(p)) U;
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
  template <class U>
  bool operator==(const HeldAllocator<U>&) const {
    return true;
  }
};
template <class T>
using Held = std::vector<T, HeldAllocator<T>>;

// The sums of taus 0 .. taus - 1, `block` consecutive ones at a time by sum_block(first, out)
// into out = sums[first .. first + block) (shorter at the end; independent: each thread takes the
// next block left until none is), on o.threads threads (0: one per core), telling o.on_summed.
template <class SumBlock>
std::vector<TauSums> sum_every_tau(std::size_t taus, std::size_t block, const AnalysisOptions& o, SumBlock sum_block) {
  std::vector<TauSums> sums(taus);
  std::atomic<std::size_t> next{0}, done{0};
  const std::size_t blocks = (taus + block - 1) / block;
  const auto sum_taus = [&](bool tell) {
    for (std::size_t b = next++; b < blocks; b = next++) {
      const std::size_t first = b * block, count = std::min(block, taus - first);
      sum_block(first, std::span<TauSums>(sums.data() + first, count));
      const std::size_t summed = done += count;
      if (tell && o.on_summed && summed < taus) o.on_summed(summed, taus);
    }
  };
  const unsigned threads = std::min<std::size_t>(o.threads > 0 ? o.threads : std::max(1u, std::thread::hardware_concurrency()), blocks);
  std::vector<std::thread> helpers;
  for (unsigned k = 1; k < threads; ++k) helpers.emplace_back(sum_taus, false);
  std::exception_ptr stopped;  // on_summed threw (the caller stops the work): the helpers end first
  try {
    sum_taus(true);
  } catch (...) {
    stopped = std::current_exception();
    next = blocks;
  }
  for (std::thread& t : helpers) t.join();
  if (stopped) std::rethrow_exception(stopped);
  if (o.on_summed) o.on_summed(taus, taus);
  return sums;
}

// Counts with the record held: every tau summed over it by the batch kernel (core/batch.hpp), the
// same sums to the last bit as the characterizer's, O(N) per tau. The phase is held as residuals
// from the line of the first count, 4 bytes a point while they fit in int32 (a gyro's phase strays
// little from its mean rate), 8 bytes from the first that does not.
class CountBatchEngine final : public EngineBase {
 public:
  CountBatchEngine(std::uint32_t stride_factor, const std::vector<std::uint64_t>& m_list, bool keep_record,
                   std::uint64_t values_hint)
      : stride_factor_(stride_factor), m_list_(m_list), keep_record_(keep_record) {
    narrow_.reserve(values_hint + 1);
    narrow_.push_back(0);  // x_0 = 0
  }

  void add(std::span<const double> values) override {
    std::size_t i = counts_ == 0 && !values.empty() ? 1 : 0;  // the first count sets the line
    if (i == 1) add_one(values[0], 0);
    if (wide_.empty()) i = add_narrow(values, i);
    for (; i < values.size(); ++i) add_one(values[i], i);
    if (keep_record_)  // as the characterizer's engine keeps it
      for (const double v : values) {
        if (record_.empty()) record_.push_back(0.0);
        record_.push_back(record_.back() + v);
      }
  }

  Analysis result(const AnalysisOptions& o) const override {
    Analysis a;
    a.n_values = counts_;
    a.n_phase = counts_ == 0 ? 0 : counts_ + 1;
    a.stride_factor = stride_factor_;
    const std::size_t taus = m_list_.size();
    const std::uint64_t spread = counts_ == 0 ? 0 : static_cast<std::uint64_t>(std::int64_t{highest_} - lowest_);
    const std::vector<TauSums> sums = sum_every_tau(taus, 1, o, [&](std::size_t i, std::span<TauSums> out) {
      BatchTau tau(m_list_[i], stride_of(m_list_[i], stride_factor_));
      if (counts_ > 0 && wide_.empty()) tau.add_segment(PhaseSegment<std::int32_t>{narrow_, 0, slope_, 0, spread});
      if (counts_ > 0 && !wide_.empty()) tau.add_segment(PhaseSegment<std::int64_t>{wide_, 0, slope_, 0, spread});
      out[0] = tau_sums(tau.result(), tau.noise());
    });
    read_out(a, sums, DataType::counts, o, record_);
    return a;
  }

  PhaseRecord record(const AnalysisOptions&) const override { return {record_, 1.0}; }

 private:
  // The common case in one tight loop: counts whose residuals stay within int32, from values[i]
  // on; stops at the first value that is not such a count (add_one() takes it: an error or the
  // switch to int64 residuals). Returns where it stopped. The phase cannot pass 2^63 within a
  // block of fewer than 2^31 counts from below 2^62: checked once.
  std::size_t add_narrow(std::span<const double> values, std::size_t i) {
    if (values.size() - i >= (std::size_t{1} << 31) || x_ >= (std::int64_t{1} << 62) || x_ <= -(std::int64_t{1} << 62))
      return i;
    const std::size_t base = narrow_.size();
    narrow_.resize(base + values.size() - i);
    std::int32_t* out = narrow_.data() + base - i;
    std::int32_t lowest = lowest_, highest = highest_;
    std::uint64_t residual = residual_;
    std::int64_t sum = 0;
    const std::size_t start = i;
    for (; i < values.size(); ++i) {
      const double v = values[i];
      if (!(std::fabs(v) < 2147483648.0) || v != std::trunc(v)) break;
      const auto c = static_cast<std::int32_t>(v);
      const std::uint64_t next = residual + static_cast<std::uint64_t>(std::int64_t{c} - slope_);
      const auto r = static_cast<std::int64_t>(next);
      if (r < INT32_MIN || r > INT32_MAX) break;
      residual = next;
      out[i] = static_cast<std::int32_t>(r);
      sum += c;
      lowest = std::min(lowest, c);
      highest = std::max(highest, c);
    }
    narrow_.resize(base + (i - start));
    x_ += sum;
    counts_ += i - start;
    lowest_ = lowest;
    highest_ = highest;
    residual_ = residual;
    return i;
  }

  // One value, every case: checked, the line set by the first, int64 residuals from the first
  // that leaves int32. values[i] names it in an error.
  void add_one(double v, std::size_t i) {
    if (!(std::fabs(v) < 2147483648.0) || v != std::trunc(v)) throw BadValue(i, "a count must be an integer of magnitude below 2^31");
    const auto c = static_cast<std::int32_t>(v);
    if (counts_ == 0) slope_ = c;
    if (__builtin_add_overflow(x_, std::int64_t{c}, &x_)) throw std::range_error("the accumulated count passed 2^63 pulses");
    ++counts_;
    lowest_ = std::min(lowest_, c);
    highest_ = std::max(highest_, c);
    residual_ += static_cast<std::uint64_t>(std::int64_t{c} - slope_);  // modulo 2^64, as the kernel reads it
    const auto r = static_cast<std::int64_t>(residual_);
    if (wide_.empty() && r >= INT32_MIN && r <= INT32_MAX) {
      narrow_.push_back(static_cast<std::int32_t>(r));
    } else {
      if (wide_.empty()) {
        wide_.reserve(narrow_.capacity());
        wide_.assign(narrow_.begin(), narrow_.end());
        Held<std::int32_t>().swap(narrow_);
      }
      wide_.push_back(r);
    }
  }

  std::uint32_t stride_factor_;
  std::vector<std::uint64_t> m_list_;
  bool keep_record_;
  std::uint64_t counts_ = 0;
  std::int64_t x_ = 0;            // the phase reached, in pulses
  std::int64_t slope_ = 0;        // the first count: the line the residuals are taken from
  std::uint64_t residual_ = 0;    // x - slope * points, modulo 2^64
  std::int32_t lowest_ = INT32_MAX, highest_ = INT32_MIN;  // the counts' range: it bounds the terms
  Held<std::int32_t> narrow_;  // the residuals while they fit in int32, x_0 first
  Held<std::int64_t> wide_;    // all of them from the first that does not
  std::vector<double> record_;        // the phase for the total family (keep_record)
};

// Phase or frequency with the record held: the points as the characterizer stages them (relative
// to the line through the first two phase points, or to the first frequency value), 8 bytes a
// point, every tau summed over them by phase_batch_taus() (float_batch.hpp), four side by side:
// the characterizer's AVAR and HVAR sums to the last bit, MVAR within its stated rounding bound.
// With prefix sums (dense tau lists) also their double-double prefix sums (24 bytes a point in
// all), every tau summed by float_batch_taus(), 64 consecutive ones at a time from the cache.
class FloatBatchEngine final : public EngineBase {
 public:
  FloatBatchEngine(DataType type, std::uint32_t stride_factor, const std::vector<std::uint64_t>& m_list,
                   bool keep_record, std::uint64_t values_hint, bool prefix_sums)
      : type_(type), stride_factor_(stride_factor), m_list_(m_list), record_(type, keep_record),
        prefix_sums_(prefix_sums) {
    x_.reserve(values_hint + 1);
    if (prefix_sums_)
      for (Held<double>* v : {&p_hi_, &p_lo_}) v->reserve(values_hint + 1);
  }

  void add(std::span<const double> values) override {
    for (std::size_t i = 0; i < values.size(); ++i) {
      const double v = values[i];
      if (!std::isfinite(v)) throw BadValue(i, "not a finite number");
      if (type_ == DataType::phase) {
        stage(line_residual(v, x_.size(), line_x0_, line_slope_));
      } else {  // as the characterizer's add_increment(): x_0 = 0, then the sum of y - y_1
        if (increments_++ == 0) {
          first_increment_ = v;
          stage(0.0);
        }
        stage(x_.back() + (v - first_increment_));
      }
      record_.keep(v);
    }
  }

  Analysis result(const AnalysisOptions& o) const override {
    Analysis a;
    a.n_phase = x_.size();
    a.n_values = type_ == DataType::phase ? a.n_phase : increments_;
    a.stride_factor = stride_factor_;
    const FloatRecord held{x_, p_hi_, p_lo_};
    const std::vector<TauSums> sums = sum_every_tau(m_list_.size(), prefix_sums_ ? float_batch_group : phase_batch_lanes, o,
                                                    [&](std::size_t first, std::span<TauSums> out) {
      const std::span<const std::uint64_t> m(m_list_.data() + first, out.size());
      std::vector<std::uint64_t> stride(out.size());
      for (std::size_t j = 0; j < out.size(); ++j) stride[j] = stride_of(m[j], stride_factor_);
      std::vector<TauResult<double>> r(out.size());
      std::vector<NoiseIdAccumulator> noise(out.size());
      if (prefix_sums_)
        float_batch_taus(held, m, stride, r, noise);
      else
        phase_batch_taus(x_, m, stride, r, noise);
      for (std::size_t j = 0; j < out.size(); ++j) out[j] = tau_sums(r[j], noise[j]);
    });
    read_out(a, sums, type_, o, record_.points);
    return a;
  }

  PhaseRecord record(const AnalysisOptions& o) const override {
    return {record_.points, type_ == DataType::freq ? o.tau0_s : 1.0};
  }

 private:
  void stage(double x) {
    x_.push_back(x);
    if (!prefix_sums_) return;
    prefix_ = FloatArith::add_prefix(prefix_, x);
    p_hi_.push_back(prefix_.hi);
    p_lo_.push_back(prefix_.lo);
  }

  DataType type_;
  std::uint32_t stride_factor_;
  std::vector<std::uint64_t> m_list_;
  KeptRecord record_;
  bool prefix_sums_;
  Held<double> x_, p_hi_, p_lo_;  // the staged points; with prefix sums P_{e+1} = x_0 + ... + x_e
  FloatArith::Prefix prefix_;
  double line_x0_ = 0, line_slope_ = 0, first_increment_ = 0;
  std::uint64_t increments_ = 0;
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
  if (o.type == DataType::counts && o.hold_counts)
    impl_->engine = std::make_unique<CountBatchEngine>(s, o.m_list, keep_record, o.values_hint);
  else if (o.type != DataType::counts && o.hold_phase)
    impl_->engine = std::make_unique<FloatBatchEngine>(o.type, s, o.m_list, keep_record, o.values_hint,
                                                       o.hold_prefix_sums);
  else if (o.type == DataType::counts)
    impl_->engine = std::make_unique<Engine<CountArith>>(o.type, s, o.m_list, keep_record, o.checkpoint_tag);
  else
    impl_->engine = std::make_unique<Engine<FloatArith>>(o.type, s, o.m_list, keep_record, o.checkpoint_tag);
}

Analyzer::~Analyzer() = default;

void Analyzer::add(std::span<const double> values) { impl_->engine->add(values); }

Analysis Analyzer::result() const { return impl_->engine->result(impl_->options); }

PhaseRecord Analyzer::record() const { return impl_->engine->record(impl_->options); }

std::vector<std::byte> Analyzer::checkpoint() const { return impl_->engine->checkpoint(); }

std::string Analyzer::restore(std::span<const std::byte> bytes) { return impl_->engine->restore(bytes); }

}  // namespace gyrochar
