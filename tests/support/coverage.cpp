#include "coverage.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <exception>
#include <map>
#include <mutex>
#include <thread>
#include <tuple>

#include "analysis.hpp"
#include "power_law_noise.hpp"

namespace gyrochar::test_support {

const char* name(Statistic s) { return s == Statistic::oadev ? "oadev" : "mdev"; }

// ---------------------------------------------------------------------------------------------
// The adapter: the only code that knows the engine's API.

std::vector<EngineEstimate> run_engine(const std::vector<double>& phase, const EngineRequest& request) {
  AnalysisOptions o;
  o.type = DataType::phase;
  o.tau0_s = 1.0;
  o.m_list = request.m_list;
  o.stats.clear();
  for (const Statistic s : request.stats) o.stats.push_back(s == Statistic::oadev ? DevStat::oadev : DevStat::mdev);
  o.stride_factor = request.stride_factor;
  o.alpha = request.alpha;
  Analyzer analyzer(o);
  for (const double x : phase) analyzer.add(x);
  std::vector<EngineEstimate> out;
  for (const AnalysisRow& row : analyzer.result().rows) {
    EngineEstimate e;
    e.stat = row.stat == DevStat::oadev ? Statistic::oadev : Statistic::mdev;
    e.m = row.m;
    e.terms = row.n;
    e.stride = row.stride;
    e.dev = row.dev;
    e.ci_low = row.ci.low;
    e.ci_high = row.ci.high;
    e.ci_valid = row.ci.valid;
    e.alpha = row.alpha;
    e.edf = row.edf;
    out.push_back(e);
  }
  return out;
}

// ---------------------------------------------------------------------------------------------
// The truth.

double true_variance(int alpha, Statistic stat, std::uint64_t m) {
  static std::mutex mutex;
  static std::map<std::tuple<int, Statistic, std::uint64_t>, double> cache;
  const auto key = std::make_tuple(alpha, stat, m);
  {
    const std::lock_guard<std::mutex> lock(mutex);
    if (const auto it = cache.find(key); it != cache.end()) return it->second;
  }
  const double v = expected_variance(alpha, stat == Statistic::oadev ? Variance::avar : Variance::mvar, m);
  const std::lock_guard<std::mutex> lock(mutex);
  cache.emplace(key, v);
  return v;
}

double coverage_standard_error(double p, std::size_t runs) {
  return runs ? std::sqrt(p * (1.0 - p) / static_cast<double>(runs)) : 0.0;
}

// ---------------------------------------------------------------------------------------------
// The study.

namespace {

std::uint64_t splitmix64(std::uint64_t z) {
  z += 0x9e3779b97f4a7c15ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

std::uint64_t run_seed(std::uint64_t seed, std::size_t length, int alpha, std::size_t run) {
  std::uint64_t h = splitmix64(seed);
  h = splitmix64(h ^ length);
  h = splitmix64(h ^ static_cast<std::uint64_t>(alpha + 16));
  return splitmix64(h ^ run);
}

// One realization analyzed every way: per stride factor, the estimates with alpha identified and
// with the true alpha.
struct Task {
  std::size_t length = 0;
  int alpha = 0;
  std::size_t run = 0;
};
struct TaskResult {
  std::vector<std::vector<EngineEstimate>> identified, given;  // per stride factor
};

std::vector<std::uint64_t> octaves_up_to(std::size_t length, std::uint64_t max_m) {
  std::vector<std::uint64_t> m;
  for (std::uint64_t v = 1; v <= length / 2 && (max_m == 0 || v <= max_m); v *= 2) m.push_back(v);
  return m;
}

TaskResult analyze(const StudySettings& s, const Task& t) {
  const std::vector<double> x = power_law_phase(t.alpha, t.length, run_seed(s.seed, t.length, t.alpha, t.run));
  TaskResult r;
  for (const std::uint32_t stride_factor : s.stride_factors) {
    EngineRequest q;
    q.m_list = octaves_up_to(t.length, s.max_m);
    q.stats = s.stats;
    q.stride_factor = stride_factor;
    r.identified.push_back(run_engine(x, q));
    q.alpha = t.alpha;
    r.given.push_back(run_engine(x, q));
  }
  return r;
}

std::size_t identified_slot(const std::optional<int>& alpha) {
  if (!alpha || *alpha > 2 || *alpha < -2) return 5;
  return static_cast<std::size_t>(2 - *alpha);
}

bool holds(const EngineEstimate& e, double true_dev) { return e.ci_valid && e.ci_low <= true_dev && true_dev <= e.ci_high; }

struct Accumulator {
  CoverageCell cell;
  double sum_edf_auto = 0.0, sum_edf_true = 0.0;
  std::size_t with_edf_auto = 0;
  double ratio_mean = 0.0, ratio_m2 = 0.0;  // Welford: running mean and sum of squared deviations
};

}  // namespace

std::vector<CoverageCell> run_coverage_study(const StudySettings& s) {
  // Tasks: longest series first (they take longest), then run, then alpha.
  std::vector<std::size_t> lengths = s.lengths;
  std::sort(lengths.begin(), lengths.end(), std::greater<>());
  std::vector<Task> tasks;
  for (const std::size_t length : lengths)
    for (std::size_t run = 0; run < s.runs; ++run)
      for (const int alpha : s.alphas) tasks.push_back({length, alpha, run});

  // Cells keyed by list positions, so they come out in the order the settings list them.
  using Key =
      std::tuple<std::size_t, std::size_t, std::size_t, std::size_t, std::uint64_t>;  // length, stride, stat, alpha, m
  std::map<Key, Accumulator> cells;
  auto index_of = [](const auto& list, const auto& value) {
    return static_cast<std::size_t>(std::find(list.begin(), list.end(), value) - list.begin());
  };
  auto reduce = [&](const Task& t, const TaskResult& r) {
    for (std::size_t si = 0; si < s.stride_factors.size(); ++si) {
      const auto& auto_rows = r.identified[si];
      const auto& true_rows = r.given[si];
      for (const EngineEstimate& a : auto_rows) {
        const Key key{index_of(s.lengths, t.length), si, index_of(s.stats, a.stat), index_of(s.alphas, t.alpha), a.m};
        Accumulator& acc = cells[key];
        CoverageCell& c = acc.cell;
        if (c.runs == 0) {
          c.length = t.length;
          c.stride_factor = s.stride_factors[si];
          c.stat = a.stat;
          c.alpha = t.alpha;
          c.m = a.m;
          c.terms = a.terms;
          c.stride = a.stride;
          c.true_dev = std::sqrt(true_variance(t.alpha, a.stat, a.m));
        }
        ++c.runs;
        if (holds(a, c.true_dev)) ++c.covered_auto;
        if (!a.ci_valid) ++c.no_interval_auto;
        if (a.alpha && *a.alpha == t.alpha) ++c.identified_right;
        ++c.identified[identified_slot(a.alpha)];
        if (a.edf > 0) {
          acc.sum_edf_auto += a.edf;
          ++acc.with_edf_auto;
        }
        const double ratio = a.dev * a.dev / (c.true_dev * c.true_dev);
        const double delta = ratio - acc.ratio_mean;
        acc.ratio_mean += delta / static_cast<double>(c.runs);
        acc.ratio_m2 += delta * (ratio - acc.ratio_mean);
        // The same estimate with the true alpha.
        const auto it = std::find_if(true_rows.begin(), true_rows.end(),
                                     [&](const EngineEstimate& e) { return e.stat == a.stat && e.m == a.m; });
        if (it != true_rows.end()) {
          if (holds(*it, c.true_dev)) ++c.covered_true;
          if (!it->ci_valid) ++c.no_interval_true;
          acc.sum_edf_true += it->edf;
        } else {
          ++c.no_interval_true;
        }
      }
    }
  };

  // Workers take tasks in turn; this thread reduces the finished ones strictly in task order (so
  // the sums do not depend on scheduling) and frees them, so only the tasks between the oldest
  // unfinished one and the newest started one are held.
  std::vector<TaskResult> results(tasks.size());
  std::vector<std::atomic<bool>> ready(tasks.size());
  std::atomic<std::size_t> next{0};
  std::atomic<bool> failed{false};
  std::exception_ptr failure;
  std::mutex failure_mutex;
  auto worker = [&] {
    for (;;) {
      const std::size_t i = next.fetch_add(1);
      if (i >= tasks.size() || failed.load()) return;
      try {
        results[i] = analyze(s, tasks[i]);
      } catch (...) {
        const std::lock_guard<std::mutex> lock(failure_mutex);
        if (!failure) failure = std::current_exception();
        failed.store(true);
        return;
      }
      ready[i].store(true, std::memory_order_release);
    }
  };
  std::vector<std::thread> threads;
  for (unsigned w = 0; w < std::max(1u, s.workers); ++w) threads.emplace_back(worker);
  auto last = std::chrono::steady_clock::now();
  std::size_t reduced = 0;
  while (reduced < tasks.size() && !failed.load()) {
    if (!ready[reduced].load(std::memory_order_acquire)) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    } else {
      reduce(tasks[reduced], results[reduced]);
      results[reduced] = TaskResult{};
      ++reduced;
    }
    if (s.progress && std::chrono::steady_clock::now() - last >= std::chrono::seconds(1)) {
      last = std::chrono::steady_clock::now();
      s.progress(reduced, tasks.size());
    }
  }
  for (auto& t : threads) t.join();
  if (failure) std::rethrow_exception(failure);
  if (s.progress) s.progress(reduced, tasks.size());

  std::vector<CoverageCell> out;
  for (auto& [key, acc] : cells) {
    CoverageCell c = acc.cell;
    const double n = static_cast<double>(c.runs);
    c.mean_edf_auto = acc.with_edf_auto ? acc.sum_edf_auto / static_cast<double>(acc.with_edf_auto) : 0.0;
    c.edf_true = acc.sum_edf_true / n;
    c.mean_ratio = acc.ratio_mean;
    const double var = c.runs > 1 ? acc.ratio_m2 / (n - 1.0) : 0.0;
    c.mc_edf = var > 0 ? 2.0 * c.mean_ratio * c.mean_ratio / var : 0.0;
    out.push_back(c);
  }
  return out;
}

}  // namespace gyrochar::test_support
