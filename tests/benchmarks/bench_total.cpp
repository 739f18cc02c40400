// Speed and memory of the total and Theo family (core/include/gyrochar/total.hpp) as the offline
// analysis runs them: the phase record held as doubles, the block sums of the decimated MTOTVAR in
// one reused buffer, the exact estimator where it costs at most 2^26 operations per tau and the
// decimated one (stride factor S) beyond. toolchain/total_benchmarks.sh runs it beside allantools
// and writes the figures into BENCHMARKS.md.
//
//   bench_total octave FILE S   MTOTDEV and Theo1 at octave taus of the phase values in FILE (one
//                               per line), exact (S = 0) or with the plan for S; one line per tau;
//                               then Theo1 and MTOTDEV by lag sums (exact) at the same taus
//   bench_total long N S        N points of random-walk plus white phase: TOTDEV, MTOTDEV and
//                               TheoH at octave taus; time per statistic and peak RSS
//   bench_total lagsums N S     N points as for `long`: exact Theo1 by lag sums (total_fast.hpp) at
//                               every octave m, then TheoH with exact Theo1 rows (its bias ratio
//                               with the plan for S); time of each part and peak RSS
//   bench_total mtotlagsums N   N points as for `long`: exact MTOTDEV by lag sums (mtotvar_fast) at
//                               every octave m; the preparation, the taus and peak RSS
//   bench_total decimation FILE S [freq]
//                               the decimated estimators against the exact ones at octave taus
//                               (a markdown table; freq: FILE holds frequencies in Hz of 10 MHz)
#include <sys/resource.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "gyrochar/total.hpp"
#include "gyrochar/total_fast.hpp"
#include "total_analysis.hpp"

namespace {

using namespace gyrochar;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// CPU seconds of the process so far (user + system): the figure that does not grow with the load
// of the shared machine.
double cpu_seconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

long peak_rss_kib() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss;
}

// MTOTVAR at m with the plan for S.
TotalVariance mtot(const std::vector<double>& x, std::uint64_t m, std::uint32_t S, std::vector<double>& scratch) {
  const std::uint64_t b = total_block(m, x.size(), S);
  scratch.resize(total_scratch_size(m, b));
  return mtotvar(x, b, m, 1.0, scratch);
}

// The values of a file, one per line ('#' lines skipped); frequencies in Hz of a 10 MHz
// oscillator become phase (x[0] = 0, x[k+1] = x[k] + (f - 1e7) / 1e7).
std::vector<double> read_phase(const char* file, bool frequency_hz) {
  std::ifstream in(file);
  std::vector<double> x;
  if (frequency_hz) x.push_back(0.0);
  for (std::string line; std::getline(in, line);)
    if (!line.empty() && line[0] != '#')
      x.push_back(frequency_hz ? x.back() + (std::stod(line) - 1e7) / 1e7 : std::stod(line));
  return x;
}

// Theo1 by lag sums at every octave m of a prepared record: one line per tau, their seconds returned.
double lag_sum_octaves(Theo1Workspace& w) {
  double total = 0;
  for (std::uint64_t m = 2; m <= w.r.size() - 1; m *= 2) {
    const auto t0 = Clock::now();
    const TotalVariance v = theo1_fast(w, m, 1.0);
    const double s = seconds_since(t0);
    total += s;
    std::printf("theo1-lagsums,%llu,%.9f,%.6e,1\n", static_cast<unsigned long long>(m), s, std::sqrt(v.var));
  }
  return total;
}

// MTOTVAR by lag sums (mtotvar_fast) at every octave m of a prepared record: one line per tau,
// their seconds returned.
double mtot_lag_sum_octaves(Theo1Workspace& w) {
  const std::size_t size = mtotvar_scratch_size(w.r.size());
  const auto scratch = uninitialized_doubles(size);  // as the analyzer allocates it (not zero-filled)
  double total = 0;
  for (std::uint64_t m = 1; 3 * m <= w.r.size(); m *= 2) {
    const auto t0 = Clock::now();
    const TotalVariance v = mtotvar_fast(w, {scratch.get(), size}, m, 1.0);
    const double s = seconds_since(t0);
    total += s;
    std::printf("mtotdev-lagsums,%llu,%.9f,%.6e,1\n", static_cast<unsigned long long>(m), s, std::sqrt(v.var));
  }
  return total;
}

int octave(const char* file, std::uint32_t S) {
  const std::vector<double> x = read_phase(file, false);
  if (x.size() < 10) {
    std::fprintf(stderr, "bench_total: %s: too few values\n", file);
    return 1;
  }
  std::vector<double> scratch;
  double total = 0;
  for (std::uint64_t m = 1; 3 * m <= x.size(); m *= 2) {
    const auto t0 = Clock::now();
    const TotalVariance v = mtot(x, m, S, scratch);
    const double s = seconds_since(t0);
    total += s;
    std::printf("mtotdev,%llu,%.9f,%.6e,%llu\n", static_cast<unsigned long long>(m), s, std::sqrt(v.var),
                static_cast<unsigned long long>(v.stride));
  }
  std::printf("mtotdev,total,%.9f\n", total);
  total = 0;
  for (std::uint64_t m = 2; m <= x.size() - 1; m *= 2) {
    const auto t0 = Clock::now();
    const TotalVariance v = theo1(x, m, 1.0, theo1_stride(m, x.size(), S));
    const double s = seconds_since(t0);
    total += s;
    std::printf("theo1,%llu,%.9f,%.6e,%llu\n", static_cast<unsigned long long>(m), s, std::sqrt(v.var),
                static_cast<unsigned long long>(v.stride));
  }
  std::printf("theo1,total,%.9f\n", total);
  auto t0 = Clock::now();  // the exact lag-sum Theo1 (total_fast.hpp), its preparation included
  const std::size_t size = theo1_workspace_size(x.size());
  const auto work = uninitialized_doubles(size);  // as the analyzer allocates it (not zero-filled)
  Theo1Workspace w = theo1_prepare(x, {work.get(), size});
  total = seconds_since(t0);
  std::printf("theo1-lagsums,prepare,%.9f\n", total);
  const double prepare = total;
  total += lag_sum_octaves(w);
  std::printf("theo1-lagsums,total,%.9f\n", total);
  total = prepare + mtot_lag_sum_octaves(w);  // the same prepared record
  std::printf("mtotdev-lagsums,total,%.9f\n", total);
  return 0;
}

// Random-walk plus white phase, seed 1 (the `long` and `lagsums` record).
std::vector<double> simulated(std::uint64_t n) {
  auto t0 = Clock::now();
  std::vector<double> x(n);
  std::mt19937_64 rng(1);
  std::normal_distribution<double> z;
  double walk = 0;
  for (double& v : x) v = (walk += 0.1 * z(rng)) + z(rng);
  std::printf("record: %llu points, %.2f s to simulate\n", static_cast<unsigned long long>(n), seconds_since(t0));
  return x;
}

int lag_sums(std::uint64_t n, std::uint32_t S) {
  const std::vector<double> x = simulated(n);
  auto t0 = Clock::now();
  double c0 = cpu_seconds();
  const std::size_t size = theo1_workspace_size(n);
  const auto work = uninitialized_doubles(size);  // as the analyzer allocates it (not zero-filled)
  Theo1Workspace w = theo1_prepare(x, {work.get(), size});
  const double prepare = seconds_since(t0), prepare_cpu = cpu_seconds() - c0;
  std::printf("prepare: %.2f s, CPU %.2f s (%.0f MB of workspace)\n", prepare, prepare_cpu,
              8e-6 * static_cast<double>(size));
  c0 = cpu_seconds();
  const double taus = lag_sum_octaves(w), taus_cpu = cpu_seconds() - c0;
  std::printf("theo1 exact: every octave m in %.2f s (CPU %.2f s) after prepare; in all %.2f s, CPU %.2f s\n", taus,
              taus_cpu, prepare + taus, prepare_cpu + taus_cpu);
  t0 = Clock::now();
  const std::uint64_t k = theoh_switch(n);
  int rows = 0;
  for (std::uint64_t m = 1; m < k; m *= 2, ++rows) oavar(x, m, 1.0);
  const double t_avar = seconds_since(t0);
  t0 = Clock::now();
  const TheoBiasRatio ratio = theo_bias_ratio(x, 1.0, S, theo_bias_taus(n, S));
  const double t_ratio = seconds_since(t0);
  t0 = Clock::now();
  c0 = cpu_seconds();
  for (std::uint64_t m = 2 * k; m <= n - 1; m *= 2, ++rows) theo1_fast(w, m, 1.0);
  std::printf("theoh: %d taus: AVAR %.2f s, ratio %.4f over %llu taus (%s) %.2f s, exact Theo1 rows %.2f s (CPU %.2f s)\n",
              rows, t_avar, ratio.ratio, static_cast<unsigned long long>(ratio.taus), ratio.exact ? "exact" : "plan",
              t_ratio, seconds_since(t0), cpu_seconds() - c0);
  std::printf("peak RSS: %ld KiB\n", peak_rss_kib());
  return 0;
}

int mtot_lag_sums(std::uint64_t n) {
  const std::vector<double> x = simulated(n);
  auto t0 = Clock::now();
  double c0 = cpu_seconds();
  const std::size_t size = theo1_workspace_size(n);
  const auto work = uninitialized_doubles(size);  // as the analyzer allocates it (not zero-filled)
  Theo1Workspace w = theo1_prepare(x, {work.get(), size});
  const double prepare = seconds_since(t0), prepare_cpu = cpu_seconds() - c0;
  std::printf("prepare: %.2f s, CPU %.2f s (%.0f MB of workspace, %.0f MB of scratch)\n", prepare, prepare_cpu,
              8e-6 * static_cast<double>(size), 8e-6 * static_cast<double>(mtotvar_scratch_size(n)));
  c0 = cpu_seconds();
  const double taus = mtot_lag_sum_octaves(w), taus_cpu = cpu_seconds() - c0;
  std::printf("mtotdev exact: every octave m in %.2f s (CPU %.2f s) after prepare; in all %.2f s, CPU %.2f s\n", taus,
              taus_cpu, prepare + taus, prepare_cpu + taus_cpu);
  // The direct exact estimator where it is cheap (at most 2^28 operations): the lag sums' rounding at
  // this N, as a relative difference of the deviations.
  std::vector<double> direct_scratch, scratch(mtotvar_scratch_size(n));
  for (std::uint64_t m = 1; 3 * m <= n && total_exact_cost(false, m, n) <= 4 * total_exact_budget; m *= 2) {
    direct_scratch.resize(total_scratch_size(m, 1));
    const double direct = mtotvar(x, 1, m, 1.0, direct_scratch).var;
    const double fast = mtotvar_fast(w, scratch, m, 1.0).var;
    std::printf("m = %llu: direct %.9e, lag sums %.9e, deviations differ by %.1e\n", static_cast<unsigned long long>(m),
                std::sqrt(direct), std::sqrt(fast), std::sqrt(fast / direct) - 1);
  }
  return 0;
}

int long_record(std::uint64_t n, std::uint32_t S) {
  const std::vector<double> x = simulated(n);
  auto t0 = Clock::now();

  int rows = 0;
  for (std::uint64_t m = 1; 2 * m <= n; m *= 2, ++rows) totvar(x, m, 1.0);
  std::printf("totdev: %d taus in %.2f s\n", rows, seconds_since(t0));

  t0 = Clock::now();
  std::vector<double> scratch;
  rows = 0;
  for (std::uint64_t m = 1; 3 * m <= n; m *= 2, ++rows) mtot(x, m, S, scratch);
  std::printf("mtotdev: %d taus in %.2f s\n", rows, seconds_since(t0));

  t0 = Clock::now();
  const std::uint64_t k = theoh_switch(n);
  rows = 0;
  for (std::uint64_t m = 1; m < k; m *= 2, ++rows) oavar(x, m, 1.0);
  const TheoBiasRatio ratio = theo_bias_ratio(x, 1.0, S, theo_bias_taus(n, S));
  for (std::uint64_t m = 2 * k; m <= n - 1; m *= 2, ++rows) theo1(x, m, 1.0, theo1_stride(m, n, S));
  std::printf("theoh: %d taus (AVAR below %llu, TheoBR from %llu; ratio %.4f over %llu taus) in %.2f s\n", rows,
              static_cast<unsigned long long>(k), static_cast<unsigned long long>(2 * k), ratio.ratio,
              static_cast<unsigned long long>(ratio.taus), seconds_since(t0));
  std::printf("peak RSS: %ld KiB\n", peak_rss_kib());
  return 0;
}

// Relative difference of the decimated deviation from the exact one, also in units of the exact
// estimate's standard uncertainty 1 / sqrt(2 EDF) (white FM EDF of SP 1065).
int decimation(const char* file, std::uint32_t S, bool frequency_hz) {
  const std::vector<double> x = read_phase(file, frequency_hz);
  const std::uint64_t N = x.size();
  const double n = static_cast<double>(N);
  std::vector<double> scratch, exact_scratch;
  std::printf("| m | block | MTOTDEV | HTOTDEV | Theo1 stride | Theo1 |\n|---:|---:|---|---|---:|---|\n");
  auto cell = [](double exact, double fast, double edf) {
    const double rel = std::sqrt(fast / exact) - 1.0;
    char text[64];
    std::snprintf(text, sizeof text, "%+.2f %% (%+.2f sigma)", 100 * rel, edf > 0 ? rel * std::sqrt(2 * edf) : 0.0);
    return std::string(text);
  };
  for (std::uint64_t m = 32; m <= N - 1; m *= 2) {
    const std::uint64_t b = total_block(m, N, S) > 1 ? total_block(m, N, S) : (m / S);
    const std::uint64_t d = m / S;
    std::string mt = "-", ht = "-", th = "-";
    if (3 * m + 1 <= N) {
      exact_scratch.resize(total_scratch_size(m, 1));
      scratch.resize(total_scratch_size(m, b));
      const double md = static_cast<double>(m);
      mt = cell(mtotvar(x, 1, m, 1.0, exact_scratch).var, mtotvar(x, b, m, 1.0, scratch).var, edf_mtotvar(0, n, md));
      ht = cell(htotvar(x, 1, m, 1.0, exact_scratch).var, htotvar(x, b, m, 1.0, scratch).var, edf_htotvar(0, n, md));
    }
    th = cell(theo1(x, m, 1.0).var, theo1(x, m, 1.0, d).var, edf_theo1(0, n, static_cast<double>(m)));
    std::printf("| %llu | %llu | %s | %s | %llu | %s |\n", static_cast<unsigned long long>(m),
                static_cast<unsigned long long>(b), mt.c_str(), ht.c_str(), static_cast<unsigned long long>(d), th.c_str());
  }
  // The exact ratio costs sum (N - m) m / 2 over N / 6 taus: computed only where that is below 2^33.
  double cost = 0;
  for (std::uint64_t m = 12; m <= 12 + 4 * (N / 6 - 3); m += 4) cost += total_exact_cost(true, m, N);
  const TheoBiasRatio fast = theo_bias_ratio(x, 1.0, S, 64);
  if (cost > 8589934592.0) {
    std::printf("\nTheoBR's bias ratio: decimated %.5f (%llu taus); the exact one (%.1e operations) not computed\n",
                fast.ratio, static_cast<unsigned long long>(fast.taus), cost);
    return 0;
  }
  const TheoBiasRatio exact = theo_bias_ratio(x, 1.0, 0, ~0ull);
  std::printf("\nTheoBR's bias ratio: exact %.5f (%llu taus), decimated %.5f (%llu taus): %+.2f %%\n", exact.ratio,
              static_cast<unsigned long long>(exact.taus), fast.ratio, static_cast<unsigned long long>(fast.taus),
              100 * (fast.ratio / exact.ratio - 1));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string mode = argc > 1 ? argv[1] : "";
  if (argc == 4 && mode == "octave") return octave(argv[2], static_cast<std::uint32_t>(std::stoul(argv[3])));
  if (argc == 4 && mode == "long") return long_record(std::stoull(argv[2]), static_cast<std::uint32_t>(std::stoul(argv[3])));
  if (argc == 4 && mode == "lagsums") return lag_sums(std::stoull(argv[2]), static_cast<std::uint32_t>(std::stoul(argv[3])));
  if (argc == 3 && mode == "mtotlagsums") return mtot_lag_sums(std::stoull(argv[2]));
  if ((argc == 4 || argc == 5) && mode == "decimation")
    return decimation(argv[2], static_cast<std::uint32_t>(std::stoul(argv[3])), argc == 5 && std::string(argv[4]) == "freq");
  std::fprintf(
      stderr,
      "usage: bench_total octave FILE S | bench_total long N S | bench_total lagsums N S | bench_total mtotlagsums N | "
      "bench_total decimation FILE S [freq]\n");
  return 2;
}
