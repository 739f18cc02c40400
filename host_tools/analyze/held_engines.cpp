// The engines of the offline analysis over a held record (analysis_engine.hpp): the batch
// kernels of counts and of phase or frequency, their taus summed on every core.
#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <exception>
#include <thread>

#include "analysis_engine.hpp"
#include "held_memory.hpp"
#include "threads.hpp"
#include "gyrochar/batch.hpp"
#include "gyrochar/characterizer.hpp"
#include "gyrochar/float_batch.hpp"

namespace gyrochar {

namespace {

// The sums of taus 0 .. taus - 1, `block` consecutive ones at a time by sum_block(first, out)
// into out = sums[first .. first + block) (shorter at the end; independent: each thread takes the
// next block left until none is), on o.threads threads (0: one per core), telling o.on_progress.
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
      if (tell && o.on_progress && summed < taus) o.on_progress("summing", summed, taus);
    }
  };
  const unsigned threads = static_cast<unsigned>(std::min<std::size_t>(thread_count(o.threads), blocks));
  std::vector<std::thread> helpers;
  for (unsigned k = 1; k < threads; ++k) helpers.emplace_back(sum_taus, false);
  std::exception_ptr stopped;  // on_progress threw (the caller stops the work): the helpers end first
  try {
    sum_taus(true);
  } catch (...) {
    stopped = std::current_exception();
    next = blocks;
  }
  for (std::thread& t : helpers) t.join();
  if (stopped) std::rethrow_exception(stopped);
  if (o.on_progress) o.on_progress("summing", taus, taus);
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
    prefault_.start(narrow_.data(), narrow_.capacity() * sizeof(std::int32_t));
  }

  void add(std::span<const double> values) override {
    const std::size_t held = wide_.empty() ? narrow_.size() : wide_.size();
    if (held + values.size() > (wide_.empty() ? narrow_.capacity() : wide_.capacity()))
      prefault_.stop();  // past the bound reserved (a gzip member's size is a hint): the buffer moves
    std::size_t i = counts_ == 0 && !values.empty() ? 1 : 0;  // the first count sets the line
    if (i == 1) add_one(values[0], 0);
    if (wide_.empty()) i = add_narrow(values, i);
    for (; i < values.size(); ++i) add_one(values[i], i);
    prefault_.written(wide_.empty() ? narrow_.size() * sizeof(std::int32_t) : wide_.size() * sizeof(std::int64_t));
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
    read_out(a, sums, DataType::counts, o, record());
    return a;
  }

  PhaseRecord record(const AnalysisOptions&) const override { return {record(), 1.0}; }
  HeldCounts held_counts() const override { return {true, narrow_, wide_, slope_}; }

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
    if (!(std::fabs(v) < 2147483648.0) || v != std::trunc(v))
      throw BadValue(i, "a count must be an integer of magnitude below 2^31");
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
        prefault_.stop();  // before narrow_ goes
        wide_.reserve(narrow_.capacity());
        wide_.assign(narrow_.begin(), narrow_.end());
        Held<std::int32_t>().swap(narrow_);
        prefault_.start(wide_.data(), wide_.capacity() * sizeof(std::int64_t));
      }
      wide_.push_back(r);
    }
  }

  std::uint32_t stride_factor_;
  std::vector<std::uint64_t> m_list_;
  // The record the total family reads (keep_record): the residuals, no copy (total.hpp: the
  // statistics do not see the line).
  PhaseSpan record() const {
    if (!keep_record_ || counts_ == 0) return {};
    return wide_.empty() ? PhaseSpan(narrow_) : PhaseSpan(wide_);
  }

  bool keep_record_;
  std::uint64_t counts_ = 0;
  std::int64_t x_ = 0;                                     // the phase reached, in pulses
  std::int64_t slope_ = 0;                                 // the first count: the line the residuals are taken from
  std::uint64_t residual_ = 0;                             // x - slope * points, modulo 2^64
  std::int32_t lowest_ = INT32_MAX, highest_ = INT32_MIN;  // the counts' range: it bounds the terms
  Held<std::int32_t> narrow_;                              // the residuals while they fit in int32, x_0 first
  Held<std::int64_t> wide_;                                // all of them from the first that does not
  Prefault prefault_;  // the residuals' pages faulted in ahead of the read pass (after them: goes first)
};

// Phase or frequency with the record held: the points as the characterizer stages them (relative
// to the line through the first two phase points, or to the first frequency value), 8 bytes a
// point, every tau summed over them by phase_batch_taus() (float_batch.hpp), four side by side:
// the characterizer's AVAR and HVAR sums to the last bit, MVAR within its stated rounding bound.
// With prefix sums (dense tau lists) also their double-double prefix sums (24 bytes a point in
// all), every tau summed by float_batch_taus(), 64 consecutive ones at a time from the cache.
class FloatBatchEngine final : public EngineBase {
 public:
  FloatBatchEngine(DataType type, std::uint32_t stride_factor, const std::vector<std::uint64_t>& m_list, bool keep_record,
                   std::uint64_t values_hint, bool prefix_sums)
      : type_(type), stride_factor_(stride_factor), m_list_(m_list), record_(type, keep_record), prefix_sums_(prefix_sums) {
    x_.reserve(values_hint + 1);
    record_.reserve(values_hint);
    if (prefix_sums_)
      for (Held<double>* v : {&p_hi_, &p_lo_}) v->reserve(values_hint + 1);
  }

  void add(std::span<const double> values) override {
    std::size_t i = 0;
    if (type_ == DataType::freq && increments_ > 0 && !prefix_sums_) i = add_frequency(values);
    for (; i < values.size(); ++i) {
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
    const unsigned kinds = sums_needed(o);  // the others' terms are not formed
    const std::vector<TauSums> sums = sum_every_tau(m_list_.size(), prefix_sums_ ? float_batch_group : phase_batch_lanes, o,
                                                    [&](std::size_t first, std::span<TauSums> out) {
                                                      const std::span<const std::uint64_t> m(m_list_.data() + first,
                                                                                             out.size());
                                                      std::vector<std::uint64_t> stride(out.size());
                                                      for (std::size_t j = 0; j < out.size(); ++j)
                                                        stride[j] = stride_of(m[j], stride_factor_);
                                                      std::vector<TauResult<double>> r(out.size());
                                                      std::vector<NoiseIdAccumulator> noise(out.size());
                                                      if (prefix_sums_) float_batch_taus(held, m, stride, r, noise);
                                                      else phase_batch_taus(x_, m, stride, r, noise, kinds);
                                                      for (std::size_t j = 0; j < out.size(); ++j)
                                                        out[j] = tau_sums(r[j], noise[j]);
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

  // Frequency values after the first, without prefix sums, in one tight loop (the running phase in
  // a register, the points written in place): what add() stages one by one, the same bits. Stops
  // at the first value that is not finite (add() refuses it); returns where it stopped.
  std::size_t add_frequency(std::span<const double> values) {
    const std::size_t base = x_.size();
    x_.resize(base + values.size());
    double* out = x_.data() + base;
    double x = out[-1];
    std::size_t i = 0;
    for (; i < values.size() && std::isfinite(values[i]); ++i) out[i] = x = x + (values[i] - first_increment_);
    x_.resize(base + i);
    increments_ += i;
    for (std::size_t k = 0; k < i; ++k) record_.keep(values[k]);
    return i;
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

std::unique_ptr<EngineBase> make_count_batch_engine(std::uint32_t stride_factor, const std::vector<std::uint64_t>& m_list,
                                                    bool keep_record, std::uint64_t values_hint) {
  return std::make_unique<CountBatchEngine>(stride_factor, m_list, keep_record, values_hint);
}

std::unique_ptr<EngineBase> make_float_batch_engine(DataType type, std::uint32_t stride_factor,
                                                    const std::vector<std::uint64_t>& m_list, bool keep_record,
                                                    std::uint64_t values_hint, bool prefix_sums) {
  return std::make_unique<FloatBatchEngine>(type, stride_factor, m_list, keep_record, values_hint, prefix_sums);
}

}  // namespace gyrochar
