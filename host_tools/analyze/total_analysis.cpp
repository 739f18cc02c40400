#include "total_analysis.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <exception>
#include <future>
#include <optional>
#include <type_traits>

#include "confidence.hpp"
#include "gyrochar/total.hpp"
#include "gyrochar/total_fast.hpp"
#include "gyrochar/total_lags.hpp"
#include "plan.hpp"
#include "threads.hpp"

namespace gyrochar {
namespace {

// The Allan-family row of `stat` at the largest m at or below `m`, or null.
const AnalysisRow* allan_row(const std::vector<AnalysisRow>& allan, DevStat stat, double m) {
  const AnalysisRow* found = nullptr;
  for (const AnalysisRow& r : allan)
    if (r.stat == stat && static_cast<double>(r.m) <= m) found = &r;
  return found;
}

// A row of a total statistic: deviation, noise and EDF from the Allan row it leans on, interval.
AnalysisRow make_row(DevStat stat, std::uint64_t m, double tau_s, const TotalVariance& v, double variance,
                     const AnalysisRow* allan, double edf, const AnalysisOptions& o) {
  AnalysisRow row;
  row.stat = stat;
  row.m = m;
  row.tau_s = tau_s;
  row.n = v.n;
  row.stride = v.stride;
  row.dev = std::sqrt(variance);
  if (allan != nullptr) {
    row.alpha = allan->alpha;
    row.noise = allan->noise;
    row.edf_alpha = allan->edf_alpha;
  }
  row.edf = edf > 0 ? edf : 0.0;
  if (row.edf > 0) row.ci = confidence_interval(row.dev, row.edf, o.confidence);
  return row;
}

// Whether the Allan row has an identified (or given) alpha: else no bias correction, no EDF.
bool known(const AnalysisRow* r) { return r != nullptr && r->alpha.has_value(); }

// The threads of the total family's taus: as --threads asks, at most two (the lag sums have two views).
unsigned total_threads(const AnalysisOptions& o) { return std::min(thread_count(o.threads), 2u); }

// A stage's progress (AnalysisOptions::on_progress): its pieces (`per_tau` a tau) finished on any
// thread, the taus they make told from the calling thread (worker 0) after each of its own pieces
// that finds more of them done, and once at the end. What the callback throws (the Python module's
// KeyboardInterrupt) stops the stage: on_threads lets the other threads finish their piece, then
// rethrows it.
class Tally {
 public:
  Tally(const AnalysisOptions& o, const char* stage, std::size_t taus, std::size_t per_tau = 1)
      : o_(o), stage_(stage), taus_(taus), per_tau_(per_tau) {}
  void piece_done(unsigned worker) {
    const std::size_t taus = ++pieces_ / per_tau_;
    if (worker != 0 || !o_.on_progress || taus == told_ || taus >= taus_) return;
    told_ = taus;
    o_.on_progress(stage_, taus, taus_);
  }
  void finish() const {
    if (o_.on_progress && taus_ > 0) o_.on_progress(stage_, taus_, taus_);
  }

 private:
  const AnalysisOptions& o_;
  const char* stage_;
  std::size_t taus_, per_tau_;
  std::atomic<std::size_t> pieces_{0};
  std::size_t told_ = 0;  // worker 0's alone
};

// Core's rows (TheoBR's bias ratio) on the run's threads, as ThreadRows, each a piece of `tally`.
// What the callback throws must not cross core's frames (built without exceptions): it is kept,
// the rows left are skipped (core then gives no ratio), and rethrow() raises it once core returns.
class TalliedRows final : public RowRunner {
 public:
  TalliedRows(unsigned threads, Tally& tally) : threads_(threads), tally_(tally) {}
  void run(const Rows& rows, std::size_t count) const override {
    on_threads(threads_, count, [&](unsigned worker, std::size_t i) {
      if (stop_) return;
      rows.row(i);
      try {
        tally_.piece_done(worker);
      } catch (...) {
        stopped_ = std::current_exception();  // worker 0's alone; read after the threads end
        stop_ = true;
      }
    });
  }
  void rethrow() const {
    if (stopped_) std::rethrow_exception(stopped_);
  }

 private:
  unsigned threads_;
  Tally& tally_;
  mutable std::atomic<bool> stop_{false};
  mutable std::exception_ptr stopped_;
};

// estimate(worker, m) at every m, the largest first (the dearest: threads then finish together), on
// `threads` threads, told to `stage`. Each m's estimate is the same bits on any thread.
template <class Estimate>
std::vector<TotalVariance> estimates(const std::vector<std::uint64_t>& ms, unsigned threads, const AnalysisOptions& o,
                                     const char* stage, const Estimate& estimate) {
  std::vector<TotalVariance> v(ms.size());
  Tally tally(o, stage, ms.size());
  on_threads(threads, ms.size(), [&](unsigned worker, std::size_t i) {
    const std::size_t k = ms.size() - 1 - i;
    v[k] = estimate(worker, ms[k]);
    tally.piece_done(worker);
  });
  tally.finish();
  return v;
}

// Theo1, or TheoH (the overlapping ADEV rows below its switch point, TheoBR above): k2 is
// phase_scale squared.
std::vector<AnalysisRow> theo_rows(DevStat stat, PhaseSpan x, double k2, const AnalysisOptions& o,
                                   const std::vector<AnalysisRow>& allan, LagSumRecord& lag_sums) {
  std::vector<AnalysisRow> rows;
  const std::uint64_t N = x.size();
  const double n = static_cast<double>(N), tau0 = o.tau0_s;
  const std::uint32_t S = o.total_stride_factor;
  const std::uint64_t k = theoh_switch(N);
  const unsigned threads = total_threads(o);
  // Exact Theo1 by lag sums (total_fast.hpp) unless the decimated estimator is asked for or its
  // workspace would pass the memory budget (plan.hpp): the record prepared once for the run
  // (O(N log N), 4 N + 2 fft_length(2 N) doubles and the twiddle table, shared with MTOTDEV), then
  // each tau, on a view of its own per thread. The rows' stride says which estimator ran.
  const bool decimated = o.theo_decimated || 8 * static_cast<std::uint64_t>(theo1_workspace_size(N)) > memory_budget();
  std::vector<std::uint64_t> ms;
  for (const std::uint64_t m : o.theo_m_list)
    if (stat != DevStat::theoh || 3 * m >= 4 * k) ms.push_back(m);  // TheoH: 0.75 m < k is ADEV's part
  double ratio = 1.0;
  if (stat == DevStat::theoh) {
    for (const AnalysisRow& r : allan)
      if (r.stat == DevStat::oadev && r.m < k) {
        AnalysisRow a = r;
        a.stat = DevStat::theoh;
        rows.push_back(a);
      }
    // The bias ratio's Theo1 taus, bound by memory traffic, on the run's threads while one more
    // prepares the record (its arithmetic in long double, then FFTs): the same work, the same
    // bits, sooner.
    std::future<void> prepared;
    if (!decimated && !ms.empty()) prepared = std::async(std::launch::async, [&] { lag_sums.views(x, false, threads); });
    const std::uint64_t bias_taus = theo_bias_taus(N, S);
    Tally bias(o, "theoh bias ratio", static_cast<std::size_t>(std::min(bias_taus, theo_bias_last(N) + 1)));
    const TalliedRows runner(threads, bias);
    ratio = theo_bias_ratio(x, tau0, S, bias_taus, &runner).ratio;
    if (prepared.valid()) prepared.get();
    runner.rethrow();
    bias.finish();
    if (!(ratio > 0)) return rows;
    lag_sums.theoh_bias = {ratio, S};
  }
  if (ms.empty()) return rows;
  std::vector<TotalVariance> v;
  if (decimated) {
    v = estimates(ms, threads, o, name(stat),
                  [&](unsigned, std::uint64_t m) { return theo1(x, m, tau0, theo1_stride(m, N, S)); });
  } else {
    // Each tau in its pieces (total_fast.hpp): the largest tau's two triangles, its dearest work,
    // go on both threads at once.
    const std::span<LagSumView> views = lag_sums.views(x, false, threads);
    std::vector<Theo1Pieces> pieces(ms.size());
    Tally tally(o, name(stat), ms.size(), theo1_pieces);
    on_threads(views.size(), theo1_pieces * ms.size(), [&](unsigned t, std::size_t i) {
      const std::size_t k = ms.size() - 1 - i / theo1_pieces;  // the largest m first, its triangles first
      theo1_piece(*views[t].work, ms[k], static_cast<int>(i % theo1_pieces + 1) % theo1_pieces, pieces[k]);
      tally.piece_done(t);
    });
    tally.finish();
    for (std::size_t k = 0; k < ms.size(); ++k) v.push_back(theo1_from_pieces(*views[0].work, ms[k], tau0, pieces[k]));
  }
  for (std::size_t i = 0; i < ms.size(); ++i) {
    const std::uint64_t m = ms[i];
    if (v[i].n == 0) continue;
    const AnalysisRow* a = allan_row(allan, DevStat::oadev, 0.75 * static_cast<double>(m));
    const double edf = known(a) ? edf_theo1(*a->alpha, n, static_cast<double>(m)) : 0.0;
    rows.push_back(make_row(stat, m, 0.75 * static_cast<double>(m) * tau0, v[i], v[i].var * ratio * k2, a, edf, o));
  }
  return rows;
}

// The sum of the overlapping AVAR's N - 2m terms at m, (x_{i+2m} - 2 x_{i+m} + x_i)^2, from the
// engine's exact sums of the held record (total_rows()), or -1 where they do not hold it.
double avar_terms(std::span<const TauSums> exact_sums, std::uint64_t m, std::uint64_t N) {
  const auto k = static_cast<std::size_t>(SumKind::avar);
  for (const TauSums& t : exact_sums)
    if (t.m == m && t.stride == 1 && t.clean && 2 * m < N && t.n[k] == N - 2 * m) {
      const double md = static_cast<double>(m);  // variance[k]: the sum / (2 n m^2) (estimates.hpp)
      return t.variance[k] * (2.0 * static_cast<double>(t.n[k]) * md * md);
    }
  return -1.0;
}

// The smallest group GroupSums holds for the decimated MTOTVAR: a 64th of the record's values, at
// most a sixteenth of its bytes while the sums fit in int32 (27 MB at 4.3 10^8 counts; a group of
// 16 would add 108 MB to the 120-hour job's peak, BENCHMARKS.md).
constexpr std::uint64_t held_group = 64;

// The decimated MTOTVAR of integer record x on blocks of b samples (b a power of two, m / b even, 3 m
// / b - 2 lags at most the table's) from the lag table of the block sums, exactly as mtotvar(x, b,
// m) computes it, rounded once; n = 0 where the table cannot hold the sums exactly. The blocks are
// summed from `held` (x's sums over groups dividing b) where given. `work` and `scratch`: the
// caller's, resized here.
TotalVariance mtotvar_of_blocks(PhaseSpan x, const GroupSums* held, std::uint64_t b, std::uint64_t m, double tau0,
                                std::vector<ExactSum>& work, std::vector<double>& scratch) {
  const std::uint64_t S = m / b, lags = 3 * S - 2;
  if (S > lag_table_max_m || 3 * S > x.size() / b) return {};
  work.resize(lag_table_size(lags));
  const bool from_held = held != nullptr && b % held->group() == 0;
  const LagTable table = from_held ? lag_table(held->sums(), 2, lags, work, nullptr, b / held->group())
                                   : lag_table(x, 2, lags, work, nullptr, b);
  if (!table.ready) return {};
  scratch.resize(lagged_scratch_size(S));
  TotalVariance t = mtotvar_lagged(table, S, tau0, scratch);
  int shift = 0;
  while ((std::uint64_t{1} << shift) < b) ++shift;
  t.var = std::ldexp(t.var, -4 * shift);  // (S / m)^4 = b^-4: tau and the 1 / m^2 of the definition
  t.stride = b;
  return t;
}

// TOTDEV, MTOTDEV, TTOTDEV or HTOTDEV at o.m_list: k2 is phase_scale squared.
std::vector<AnalysisRow> total_family_rows(DevStat stat, PhaseSpan x, double k2, const AnalysisOptions& o,
                                           const std::vector<AnalysisRow>& allan, std::span<const TauSums> exact_sums,
                                           LagSumRecord& lag_sums) {
  std::vector<AnalysisRow> rows;
  const std::uint64_t N = x.size();
  const double n = static_cast<double>(N), tau0 = o.tau0_s;
  const std::uint32_t S = o.total_stride_factor;
  const unsigned threads = total_threads(o);
  const bool hadamard = stat == DevStat::htotdev;
  std::vector<std::uint64_t> ms;  // the taus the record allows
  for (const std::uint64_t m : o.m_list) {
    if (stat == DevStat::totdev ? m > N / 2 : 3 * m > (hadamard ? N - 1 : N)) break;
    ms.push_back(m);
  }
  if (ms.empty()) return rows;

  // MTOTVAR (and TTOTVAR) and HTOTVAR exact at every tau by lag sums (total_fast.hpp) unless the
  // decimated plan is asked for or the workspace would pass the memory budget: the record (for
  // HTOTVAR its frequencies) prepared once as for Theo1, then O(m log m) a tau, on a view of its own
  // per thread. TOTVAR reads the record alone (O(N) a tau) and the decimated plan's taus each with
  // scratch of its own: their taus go on the threads too. The rows' stride says which estimator ran.
  const std::size_t n_fast = hadamard ? N - 1 : N, fast_size = theo1_workspace_size(n_fast) + mtotvar_scratch_size(n_fast);
  const bool total_decimated = o.total_decimated || N < 2 ||
                               8 * (static_cast<std::uint64_t>(fast_size) + N) > memory_budget();
  std::vector<TotalVariance> v;
  if (stat == DevStat::totdev) {
    // TOTVAR's terms that need no reflection are the overlapping AVAR's at the same m: where the
    // engine summed those exactly, only the 2 (m - 1) reflected ones are left, O(m) and not O(N).
    v = estimates(ms, threads, o, name(stat), [&](unsigned, std::uint64_t m) {
      const double interior = avar_terms(exact_sums, m, N);
      return interior >= 0 ? totvar_from_interior(x, m, tau0, interior) : totvar(x, m, tau0);
    });
  } else if (!total_decimated) {
    // Each tau in its two pieces (total_fast.hpp), the largest tau first and its FFTs first: its two
    // pieces, the dearest work, go on both threads at once.
    const std::span<LagSumView> views = lag_sums.views(x, hadamard, threads);  // HTOTVAR: the frequencies times tau0
    std::vector<MtotPieces> pieces(ms.size());
    Tally tally(o, name(stat), ms.size(), mtotvar_pieces);
    on_threads(views.size(), mtotvar_pieces * ms.size(), [&](unsigned t, std::size_t i) {
      const std::size_t k = ms.size() - 1 - i / mtotvar_pieces;
      const int piece = mtotvar_pieces - 1 - static_cast<int>(i % mtotvar_pieces);
      mtotvar_piece(*views[t].work, views[t].scratch, ms[k], piece, pieces[k]);
      tally.piece_done(t);
    });
    tally.finish();
    for (std::size_t k = 0; k < ms.size(); ++k) {
      if (!hadamard) {
        v.push_back(mtotvar_from_pieces(*views[0].work, ms[k], tau0, pieces[k]));
      } else if (ms[k] > 1) {
        v.push_back(htotvar_from_pieces(*views[0].work, ms[k], tau0, pieces[k]));
      } else {
        std::vector<double> scratch(total_scratch_size(1, 1));  // m = 1: the overlapping Hadamard variance, O(N)
        v.push_back(htotvar(x, 1, 1, tau0, scratch));
      }
    }
  } else {
    // The plan: the exact estimator where it costs at most 2^26 operations; for counts, exact from
    // the lag table of their differences (total_lags.hpp: one pass, then O(m^3) a tau) up to
    // lag_table_max_m beyond that; decimated from there on.
    const auto from_table = [&](std::uint64_t m) {
      return x.integers() && m <= lag_table_max_m && (!hadamard || m > 1) &&
             total_exact_cost(false, m, n_fast) > total_exact_budget;
    };
    std::uint64_t table_m = 0;
    for (const std::uint64_t m : ms)
      if (from_table(m)) table_m = m;
    std::vector<ExactSum> table_work(table_m > 0 ? lag_table_size(3 * table_m - 2) : 0);
    LagTable table;
    if (table_m > 0) {
      const ThreadRows runner(threads);
      table = lag_table(x, hadamard ? 3 : 2, 3 * table_m - 2, table_work, &runner);
    }
    // Counts' decimated MTOTVAR: the record's sums over the plan's smallest block of at least
    // held_group samples held once, the blocks of each tau whose block it divides summed from them.
    std::uint64_t smallest = 0;
    for (const std::uint64_t m : ms)
      if (const std::uint64_t b = total_block(m, N, S); !from_table(m) && b >= held_group)
        smallest = smallest == 0 ? b : std::min(smallest, b);
    std::optional<GroupSums> held;
    if (!hadamard && x.integers() && smallest > 0) held.emplace(x, smallest);
    // Per thread: the plan's block sums and prefix sums, or the table's coefficients; for counts'
    // decimated MTOTVAR the lag table of the block sums.
    std::array<std::vector<double>, 2> scratch;
    std::array<std::vector<ExactSum>, 2> blocks_work;
    v = estimates(ms, threads, o, name(stat), [&](unsigned worker, std::uint64_t m) {
      std::vector<double>& own = scratch[worker];
      if (table.ready && from_table(m)) {
        own.resize(lagged_scratch_size(m));
        return hadamard ? htotvar_lagged(table, m, tau0, own) : mtotvar_lagged(table, m, tau0, own);
      }
      const std::uint64_t b = total_block(m, N, S);
      if (!hadamard && b > 1 && x.integers()) {
        // The decimated MTOTVAR is MTOTVAR at m / b of the record's sums over blocks of b samples,
        // times b^-4 (docs/total.md). Counts' block sums are integers: their lag table gives it
        // exactly, O((N / b) (3 m / b)), where the table can hold their differences' products.
        const TotalVariance t = mtotvar_of_blocks(x, held ? &*held : nullptr, b, m, tau0, blocks_work[worker], own);
        if (t.n != 0) return t;
      }
      own.resize(total_scratch_size(m, b));
      return hadamard ? htotvar(x, b, m, tau0, own) : mtotvar(x, b, m, tau0, own);
    });
  }

  for (std::size_t i = 0; i < ms.size(); ++i) {
    const std::uint64_t m = ms[i];
    const double md = static_cast<double>(m);
    if (v[i].n == 0) continue;
    if (stat == DevStat::totdev) {
      const AnalysisRow* a = allan_row(allan, DevStat::oadev, md);
      const double bias = known(a) ? totvar_bias(*a->alpha, n, md) : 1.0;
      double edf = known(a) ? edf_totvar(*a->alpha, n, md) : 0.0;
      if (!(edf > 0) && a != nullptr && a->m == m) edf = a->edf;  // PM noise: the OADEV estimate's
      rows.push_back(make_row(stat, m, md * tau0, v[i], v[i].var / bias * k2, a, edf, o));
    } else if (!hadamard) {
      const AnalysisRow* a = allan_row(allan, DevStat::mdev, md);
      const double edf = known(a) ? edf_mtotvar(*a->alpha, n, md) : 0.0;
      const double tdev = stat == DevStat::ttotdev ? md * tau0 * md * tau0 / 3.0 : 1.0;
      rows.push_back(make_row(stat, m, md * tau0, v[i], v[i].var * tdev * k2, a, edf, o));
    } else {
      const AnalysisRow* a = allan_row(allan, DevStat::ohdev, md);
      const double bias = known(a) ? htotvar_bias(*a->alpha, m) : 1.0;
      double edf = known(a) && m >= 16 ? edf_htotvar(*a->alpha, n, md) : 0.0;
      if (!(edf > 0) && a != nullptr && a->m == m) edf = a->edf;  // below m = 16, or PM noise: OHDEV's
      rows.push_back(make_row(stat, m, md * tau0, v[i], v[i].var / bias * k2, a, edf, o));
    }
  }
  return rows;
}

}  // namespace

GroupSums::GroupSums(PhaseSpan x, std::uint64_t g) : g_(g) {
  x.visit([&]<class T>(std::span<const T> v) {
    if constexpr (std::is_integral_v<T>) {
      const std::size_t groups = g > 0 ? v.size() / g : 0;
      narrow_.reserve(groups);
      for (std::size_t k = 0; k < groups; ++k) {
        std::uint64_t total = 0;  // modulo 2^64, as lag_table sums the record's own groups
        for (std::size_t i = k * g; i < (k + 1) * g; ++i) total += static_cast<std::uint64_t>(std::int64_t{v[i]});
        const auto sum = static_cast<std::int64_t>(total);
        if (wide_.empty() && sum >= INT32_MIN && sum <= INT32_MAX) {
          narrow_.push_back(static_cast<std::int32_t>(sum));
          continue;
        }
        if (wide_.empty()) {  // the first that does not fit: every sum as int64 from here on
          wide_.reserve(groups);
          wide_.assign(narrow_.begin(), narrow_.end());
          narrow_ = {};
        }
        wide_.push_back(sum);
      }
    }
  });
}

std::span<LagSumView> LagSumRecord::views(PhaseSpan x, bool frequencies, unsigned threads) {
  const std::size_t n = frequencies ? x.size() - 1 : x.size();
  if (!(w_.ready && frequencies_ == frequencies && w_.r.size() == n)) {
    w_ = second_ = {};
    views_ = {};
    work_.reset();  // the other kind's preparation goes before this one's is allocated
    scratch_.reset();
    second_buffer_.reset();
    second_scratch_.reset();
    y_.clear();
    if (frequencies) {
      y_.resize(n);
      x.visit([&](auto v) {
        for (std::size_t i = 0; i < n; ++i) y_[i] = static_cast<double>(v[i + 1]) - static_cast<double>(v[i]);
      });
    }
    work_ = uninitialized_doubles(theo1_workspace_size(n));
    const ThreadRows runner(threads);  // the preparation's FFTs on the run's threads
    w_ = theo1_prepare(frequencies ? PhaseSpan(y_) : x, {work_.get(), theo1_workspace_size(n)}, &runner);
    scratch_ = uninitialized_doubles(mtotvar_scratch_size(n));
    views_[0] = {&w_, {scratch_.get(), mtotvar_scratch_size(n)}};
    frequencies_ = frequencies;
  }
  // A second thread's buffer and scratch, where the budget holds them beside the record and the
  // preparation (its fixed-term layout depends on the buffer's size: the same size, the same bits).
  const std::uint64_t both = 8 * (static_cast<std::uint64_t>(theo1_workspace_size(n)) + 2 * mtotvar_scratch_size(n) +
                                  w_.buffer.size() + x.size() + y_.size());
  if (threads >= 2 && views_[1].work == nullptr && w_.ready && both <= memory_budget()) {
    second_buffer_ = uninitialized_doubles(w_.buffer.size());
    second_scratch_ = uninitialized_doubles(mtotvar_scratch_size(n));
    second_ = w_;
    second_.buffer = {second_buffer_.get(), w_.buffer.size()};
    views_[1] = {&second_, {second_scratch_.get(), mtotvar_scratch_size(n)}};
  }
  return std::span<LagSumView>(views_).first(threads >= 2 && views_[1].work != nullptr ? 2 : 1);
}

std::vector<AnalysisRow> total_rows(DevStat stat, PhaseSpan x, double phase_scale, const AnalysisOptions& o,
                                    const std::vector<AnalysisRow>& allan, std::span<const TauSums> exact_sums,
                                    LagSumRecord& lag_sums) {
  const double k2 = phase_scale * phase_scale;
  if (stat == DevStat::theo1 || stat == DevStat::theoh) return theo_rows(stat, x, k2, o, allan, lag_sums);
  return total_family_rows(stat, x, k2, o, allan, exact_sums, lag_sums);
}

}  // namespace gyrochar
