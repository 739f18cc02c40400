#pragma once
// The offline analysis engine behind gyrochar-analyze: the core characterizer (the one the board
// runs) over heap storage sized for the file, read out by the core extractors (estimates.hpp): per
// tau the deviation, its number of terms, the identified noise and how it was chosen, the exact EDF
// of the estimator actually used, and the chi-squared interval.
//
// Memory depends on the tau list and the stride factor S, never on the number of values: the
// history holds at most 3S (1 + levels/2) points (levels: octaves of the largest tau above S; the
// pages of a level are touched only once the data reaches it), each tau a few hundred bytes.
//
// Units: deviations come out in "phase unit per second", where the phase unit is the unit of the
// values (phase data: the value's unit, e.g. s or deg; counts: one pulse; frequency data: the
// value's unit times s, so deviations are in the value's unit). TDEV is in the phase unit.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <functional>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "confidence.hpp"
#include "gyrochar/estimates.hpp"
#include "gyrochar/total.hpp"

namespace gyrochar {

enum class DataType {
  phase,   // phase (angle, time) samples x_k
  freq,    // frequency (rate) samples y_k, averages over tau0: N values give N + 1 phase points
  counts,  // integer pulse counts per tau0 (exact): N counts give N + 1 phase points
};
/// "phase", "freq", "counts". A static string, never null.
const char* name(DataType t);
/// The statistic called `text`, or nothing.
std::optional<DevStat> parse_dev_stat(const std::string& text);
/// Every statistic's name, in DevStat's order, joined by `separator` ("adev,oadev,...,theoh").
std::string dev_stat_names(const char* separator);

/// Largest stride factor "full" uses: with S = 2^16 the history takes a few MB whatever the run
/// length; taus above it are strided (terms every m/S points) and their EDF says so.
inline constexpr std::uint32_t full_stride_cap = 1u << 16;

/// Largest stride factor "full" resolves to when the record is held: the batch kernels keep no
/// history, so every tau up to N/4 stays fully overlapped at any length (2^31: the largest power
/// of two a std::uint32_t holds).
inline constexpr std::uint32_t held_stride_cap = 1u << 31;

/// True for a stride factor the core's characterizer accepts: a power of two from 2 to 2^24
/// (ConfigureStatus::bad_stride_factor otherwise); with `held` (the batch kernels over a held
/// record), up to held_stride_cap. O(1).
bool valid_stride_factor(std::uint32_t s, bool held = false);

/// The stride factor used for a request: `requested` (a power of two >= 2) as is; 0 means "full":
/// the smallest power of two >= m_max (so every tau is fully overlapped), at least 2 and at most
/// full_stride_cap. O(1).
std::uint32_t resolve_stride_factor(std::uint32_t requested, std::uint64_t m_max);

/// The stride factor of "full" for an input of at most n_phase phase points: the smallest power
/// of two >= n_phase / 4, so that every tau up to N/4 is fully overlapped (the history then holds
/// 3N/4 to 3N/2 points, of which the pages the data reaches are used), within [2, 2^24], or
/// within [2, held_stride_cap] when the record is `held` (no history); full_stride_cap when the
/// length is unknown (0). O(1).
std::uint32_t full_stride_factor(std::uint64_t n_phase, bool held = false);

/// Bytes of history the characterizer of `type` needs for stride factor S and taus up to m_max
/// (calloc'd: pages the data never reaches are not used). O(log m_max).
std::uint64_t history_bytes(DataType type, std::uint32_t stride_factor, std::uint64_t m_max);

/// True when the pyramid with stride factor S can form averaging factor m >= 1: m <= S, or m a
/// multiple of its stride 2^L, the smallest power of two with S 2^L >= m. O(1).
bool tau_representable(std::uint64_t m, std::uint32_t stride_factor);

/// Octave averaging factors 1, 2, 4, ... up to n_phase / 2 (up to 2^39 when n_phase is 0, unknown).
std::vector<std::uint64_t> octave_taus(std::uint64_t n_phase);
/// Decade averaging factors as Stable32: 1, 2, 4, 10, 20, 40, 100, ... up to n_phase / 2.
std::vector<std::uint64_t> decade_taus(std::uint64_t n_phase);
/// Averaging factors of Theo1 and TheoBR (tau = 0.75 m tau0) for a tau list of the Allan family:
/// its even factors from 10 on, continued by its own rule (octave: doubling; decade: 1, 2, 4 per
/// decade) up to n_phase - 1 (2^40 when n_phase is 0, unknown); "all": every even m from 10 to
/// n_phase - 1. O(list).
std::vector<std::uint64_t> theo_taus(const std::string& rule, const std::vector<std::uint64_t>& m_list,
                                     std::uint64_t n_phase);
/// Every averaging factor up to n_phase / 2 that stride factor S can form (every m when
/// n_phase / 2 <= S). The list has O(min(n_phase, S log n_phase)) entries.
std::vector<std::uint64_t> all_taus(std::uint64_t n_phase, std::uint32_t stride_factor);

struct AnalysisOptions {
  DataType type = DataType::phase;
  double tau0_s = 1.0;                                        // sample interval
  std::vector<std::uint64_t> m_list;                          // averaging factors, strictly increasing
  std::vector<DevStat> stats{DevStat::oadev, DevStat::mdev};  // rows come out in this order
  std::uint32_t stride_factor = 0;                            // S, a power of two >= 2; 0: full (resolve_stride_factor)
  double confidence = 0.682689492137086;
  std::optional<int> alpha;        // noise exponent for the EDF; empty: identified per tau
  EdfModel edf = EdfModel::exact;  // greenhall: Stable32's approximation (comparisons)
  // false: the deviations alone, no noise identification and so no EDF or interval (the Python
  // package's allantools functions, which return none); the total family identifies all the same
  // (its bias corrections need it).
  bool identify_noise = true;
  // The total and Theo family (total_analysis.hpp): asked for in `stats`, they make the analyzer
  // hold the record (8 bytes a phase point).
  std::vector<std::uint64_t> theo_m_list;  // averaging factors of Theo1 and TheoBR (even), increasing
  std::uint32_t total_stride_factor = 16;  // S of their decimated estimators; 0: always exact
  bool theo_decimated = false;             // Theo1/TheoBR rows by the decimated estimator (S above)
                                           // where the direct one is costly; false: exact, lag sums
  bool total_decimated = false;            // MTOTDEV/TTOTDEV/HTOTDEV rows by the exact-or-decimated
                                           // plan (S above) instead of the exact lag-sum estimator
  bool keep_record = false;                // hold the record without a total statistic (fits)
  // Counts only: hold the phase (4 bytes a point while it strays less than 2^31 pulses from the
  // line of the first count, else 8) and sum every tau over it by the batch kernel
  // (core/include/gyrochar/batch.hpp): the characterizer's sums to the last bit, O(N) per tau,
  // where the pyramid's history for a stride factor near N/4 would take 24 bytes a point or more.
  // values_hint: an upper bound on the values to reserve the record for (0: unknown).
  bool hold_counts = false;
  std::uint64_t values_hint = 0;
  // Phase and frequency only: hold the phase points as the characterizer stages them (8 bytes a
  // point) and sum the taus over them, four side by side (phase_batch_taus(),
  // core/include/gyrochar/float_batch.hpp): the characterizer's AVAR and HVAR sums to the last
  // bit, the MVAR terms as exact running sums of the rounded AVAR terms (within the roundings
  // those owe, u relative and a second-order bound), only the sums the read-out needs, O(N) per
  // tau where the characterizer visits every tau at every point.
  bool hold_phase = false;
  // With hold_phase, for dense tau lists (--taus all): hold the double-double prefix sums too (24
  // bytes a point) and sum 64 consecutive taus at a time from the cache (float_batch_taus(): the
  // characterizer's terms to the last bit, the overlapping sums in another order, within 2 n u
  // relative), two to three times faster there than four taus side by side.
  bool hold_prefix_sums = false;
  // Threads summing the held record's taus (each tau on one; they are independent); 0: one per
  // core the system offers.
  unsigned threads = 0;
  // The caller's configuration fingerprint, kept in checkpoints (Analyzer::checkpoint): a
  // checkpoint restores only under the same tag.
  std::uint32_t checkpoint_tag = 0;
  // Told, from the thread that calls result(), how far its long stages are: "summing", the held
  // record's taus (the sums of every tau, --taus all, take minutes at 10^6 values), then each
  // statistic of the total family by its name ("theoh bias ratio" for TheoBR's ratio), its taus
  // done of how many; each stage ends with done = total. May be empty. May throw to stop result()
  // (the Python module's KeyboardInterrupt): the exception comes out of it.
  std::function<void(const char* stage, std::size_t done, std::size_t total)> on_progress;
};

struct AnalysisRow {
  DevStat stat = DevStat::oadev;
  std::uint64_t m = 0;
  double tau_s = 0.0;        // m tau0 (Theo1, TheoBR: 0.75 m tau0)
  std::uint64_t n = 0;       // terms in the estimate (Stable32's "#")
  double dev = 0.0;          // deviation: phase unit per second (TDEV, TTOTDEV: phase unit)
  std::optional<int> alpha;  // identified (or given) noise exponent; empty: not identified
  NoiseId noise;             // the identification: plausible range and method
  int edf_alpha = 0;         // the alpha whose EDF was used (the smallest of the plausible)
  std::uint64_t stride = 1;  // terms every `stride` phase points (m for adev and hdev); total
                             // family: 1 exact, else the decimated estimator's block or stride
  double edf = 0.0;          // EDF of this estimator; 0: not available
  double skew_dof = 0.0;     // skewness of its distribution (confidence.hpp); 0: plain chi-squared
  Interval ci;               // same unit as dev
};

/// The phase record the analyzer holds for the total family: points in the engine's representation
/// (phase relative to the first point; for freq the running sum of the values less the first value,
/// a line less, which the total family does not see; for counts the running sum of the counts, or
/// where the batch engine holds them its residuals from the line of the first count, in int32 or
/// int64: a line less again) and the factor that makes them phase units (tau0 for frequency data,
/// else 1). Empty when not held.
struct PhaseRecord {
  PhaseSpan phase;
  double phase_scale = 1.0;
};

/// The counts as the analyzer holds them when it sums every tau over the held record (hold_counts):
/// the phase's residuals from the line of the first count, x_0 = 0 first, in int32 while every one
/// fits (`narrow`), else in int64 (`wide`, modulo 2^64). Count i = r[i+1] - r[i] + slope, exactly
/// (modulo 2^64). `held` false: this analyzer does not hold counts.
struct HeldCounts {
  bool held = false;
  std::span<const std::int32_t> narrow;
  std::span<const std::int64_t> wide;
  std::int64_t slope = 0;
};

/// TheoBR's bias ratio of the record (theo_bias_ratio, decimated with stride factor S) as TheoH's
/// rows computed it, for the fit's long-tau points to reuse: at 10^7 points its 64 decimated taus
/// cost about 4 s of CPU. ratio 0: none computed.
struct TheoBias {
  double ratio = 0.0;
  std::uint32_t stride_factor = 0;
};

struct Analysis {
  std::uint64_t n_values = 0;       // values read
  std::uint64_t n_phase = 0;        // phase points (values + 1 for freq and counts)
  std::uint32_t stride_factor = 0;  // S used
  std::vector<AnalysisRow> rows;    // by stat (in the order asked), then by m; no row when n = 0
  TheoBias theoh_bias;              // TheoH's bias ratio, when TheoH was asked for
};

/// A value Analyzer::add() refused: its index in the block, and why (what()).
class BadValue : public std::invalid_argument {
 public:
  BadValue(std::size_t index, const std::string& why) : std::invalid_argument(why), index_(index) {}
  std::size_t index() const { return index_; }

 private:
  std::size_t index_;
};

class Analyzer {
 public:
  /// Allocates the history and per-tau state (O(S log m_max + taus)). Throws std::invalid_argument
  /// with a reason for inconsistent options: tau0 <= 0, no taus, taus not increasing, a tau the
  /// stride factor cannot form, a stride factor that is not a power of two in [2, 2^24], a
  /// confidence outside (0, 1), no statistics.
  explicit Analyzer(const AnalysisOptions& options);
  ~Analyzer();
  Analyzer(const Analyzer&) = delete;
  Analyzer& operator=(const Analyzer&) = delete;

  /// The next values, in order: phases, frequencies, or pulse counts (integers below 2^31 in
  /// magnitude, given to the characterizer's block API). O(taus) amortized per value; allocates
  /// only a conversion buffer the size of the largest block. Throws BadValue for a value that is
  /// not finite or not a valid count (the values before it were added), std::range_error when
  /// the accumulated count passes 2^63 pulses (within the block).
  void add(std::span<const double> values);
  /// One value: add() of a block of one.
  void add(double value) { add(std::span<const double>(&value, 1)); }
  /// Results so far; may be called at any time. O(taus x stats) plus the EDF, allocates the rows.
  /// Throws std::range_error naming the statistic, the tau and the cause when a deviation is not
  /// a finite number (values whose squared differences overflow a double, a tau0 whose square
  /// leaves a double's range): such a result is never returned.
  Analysis result() const;
  /// The record held for the total family (empty unless a total statistic or keep_record was
  /// asked for); valid until the next add(). O(1).
  PhaseRecord record() const;
  /// The counts held (HeldCounts; `held` is known from construction on); valid until the next
  /// add(). O(1).
  HeldCounts held_counts() const;
  /// The state as the core characterizer's checkpoint (characterizer.hpp: header with the format
  /// version, stride factor, taus and checkpoint_tag, the run state, history and tau states, a
  /// CRC-32; native byte order), the bytes the board writes for its characterizer. Throws
  /// std::invalid_argument when a record is held (the total family, keep_record, hold_counts,
  /// hold_phase): the format does not carry it. O(history + taus).
  std::vector<std::byte> checkpoint() const;
  /// Restores a checkpoint() of an analyzer with the same options. The next value starts a new
  /// segment, as on the board after a restart (no term spans the restore). Returns "" or why the
  /// bytes were refused (the core's RestoreStatus in words); then nothing changed.
  /// O(history + taus).
  std::string restore(std::span<const std::byte> bytes);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace gyrochar
