// coverage_study: how often the offline engine's 68.3 % confidence intervals hold the true
// deviation, by Monte Carlo over power-law noise of known exponent (tests/support/coverage.hpp).
// Markdown tables on stdout (toolchain/metrology.sh puts them into docs/metrology.md), everything
// per cell in a CSV file (--csv), progress and the wall time on stderr.
#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "plan.hpp"
#include "support/coverage.hpp"

namespace {

using namespace gyrochar::test_support;

constexpr double nominal = 0.682689492137086;
constexpr double flag_points = 3.0;  // cells further than this from 68.3 % are flagged

const char* noise_name(int alpha) {
  switch (alpha) {
    case 2: return "white PM";
    case 1: return "flicker PM";
    case 0: return "white FM";
    case -1: return "flicker FM";
    case -2: return "RW FM";
  }
  return "?";
}

std::string stride_name(std::uint32_t s) { return s == 0 ? "full" : std::to_string(s); }

bool flagged(double coverage) { return std::fabs(100.0 * (coverage - nominal)) > flag_points; }

std::string percent(double coverage) {
  const std::string text = fmt::format("{:.1f}", 100.0 * coverage);
  return flagged(coverage) ? "**" + text + "**" : text;
}

// Writes every cell to `f` (opened before the study, so a bad path fails at once) and closes it.
bool write_csv(std::FILE* f, const std::vector<CoverageCell>& cells) {
  std::fprintf(f,
               "length,stride_factor,stat,alpha,m,terms,stride,true_dev,runs,coverage_auto,coverage_true,"
               "coverage_se,identified_right,no_interval_auto,no_interval_true,identified_p2,identified_p1,"
               "identified_0,identified_m1,identified_m2,identified_other,mean_edf_auto,edf_true,mc_edf,mean_ratio\n");
  for (const CoverageCell& c : cells) {
    std::fprintf(f, "%zu,%s,%s,%d,%llu,%llu,%llu,%.10g,%zu,%.4f,%.4f,%.4f,%.4f,%zu,%zu", c.length,
                 stride_name(c.stride_factor).c_str(), name(c.stat), c.alpha, static_cast<unsigned long long>(c.m),
                 static_cast<unsigned long long>(c.terms), static_cast<unsigned long long>(c.stride), c.true_dev, c.runs,
                 c.coverage_auto(), c.coverage_true(), coverage_standard_error(nominal, c.runs), c.identified_fraction(),
                 c.no_interval_auto, c.no_interval_true);
    for (const std::size_t n : c.identified) std::fprintf(f, ",%zu", n);
    std::fprintf(f, ",%.6g,%.6g,%.6g,%.6f\n", c.mean_edf_auto, c.edf_true, c.mc_edf, c.mean_ratio);
  }
  const bool ok = !std::ferror(f);
  return std::fclose(f) == 0 && ok;
}

void print_markdown(const StudySettings& s, const std::vector<CoverageCell>& cells, double wall_s, double cpu_s) {
  const double se = coverage_standard_error(nominal, s.runs);
  std::printf(
      "%zu runs per cell (independent realizations; the same realization serves every stride factor,\n"
      "statistic and m of its noise type and length). Binomial standard error of a coverage of 68.3 %%\n"
      "over %zu runs: %.1f points. Wall time %.0f s with %u workers, %.0f s of CPU time (the machine\n"
      "may be shared with other jobs, so the wall time is indicative).\n\n",
      s.runs, s.runs, 100.0 * se, wall_s, s.workers, cpu_s);
  std::printf(
      "Each cell: coverage (%%) of the 68.3 %% interval with alpha identified by the engine / coverage\n"
      "with the true alpha given to the engine / runs in which the engine identified alpha right (%%).\n"
      "**Bold**: coverage outside 68.3 +- %.0f points. Same estimate both ways: only the EDF, and so the\n"
      "interval, differs; the CSV also holds the stated EDFs, the Monte Carlo EDF (2 mean^2 / variance of\n"
      "the variance estimates) and the mean of estimate / truth.\n\n",
      flag_points);
  // Group: length, stride factor, statistic; rows m; columns alpha.
  std::map<std::tuple<std::size_t, std::uint32_t, int>, std::map<std::uint64_t, std::map<int, const CoverageCell*>>> tables;
  std::map<std::tuple<std::size_t, std::uint32_t, int>, std::map<std::uint64_t, std::uint64_t>> terms;
  for (const CoverageCell& c : cells) {
    const auto key = std::make_tuple(c.length, c.stride_factor, static_cast<int>(c.stat));
    tables[key][c.m][c.alpha] = &c;
    terms[key][c.m] = c.terms;
  }
  std::size_t total = 0, out_auto = 0, out_true = 0;
  std::vector<std::string> summary;
  for (const std::size_t length : s.lengths)
    for (const std::uint32_t stride : s.stride_factors)
      for (const Statistic stat : s.stats) {
        const auto key = std::make_tuple(length, stride, static_cast<int>(stat));
        const auto it = tables.find(key);
        if (it == tables.end()) continue;
        std::printf("### N = %zu, stride factor %s, %s\n\n| m | terms |", length, stride_name(stride).c_str(),
                    stat == Statistic::oadev ? "OADEV" : "MDEV");
        for (const int a : s.alphas) std::printf(" %s (%+d) |", noise_name(a), a);
        std::printf("\n|---:|---:|");
        for (std::size_t i = 0; i < s.alphas.size(); ++i) std::printf("---|");
        std::printf("\n");
        std::size_t table_auto = 0, table_true = 0, table_cells = 0;
        for (const auto& [m, by_alpha] : it->second) {
          std::printf("| %llu | %llu |", static_cast<unsigned long long>(m), static_cast<unsigned long long>(terms[key][m]));
          for (const int a : s.alphas) {
            const auto c = by_alpha.find(a);
            if (c == by_alpha.end()) {
              std::printf(" |");
              continue;
            }
            const CoverageCell& cell = *c->second;
            ++table_cells;
            table_auto += flagged(cell.coverage_auto());
            table_true += flagged(cell.coverage_true());
            std::printf(" %s / %s / %.0f |", percent(cell.coverage_auto()).c_str(), percent(cell.coverage_true()).c_str(),
                        100.0 * cell.identified_fraction());
          }
          std::printf("\n");
        }
        std::printf("\n");
        total += table_cells;
        out_auto += table_auto;
        out_true += table_true;
        summary.push_back(fmt::format("| {} | {} | {} | {} | {} | {} |", length, stride_name(stride),
                                      stat == Statistic::oadev ? "OADEV" : "MDEV", table_cells, table_auto, table_true));
      }
  std::printf(
      "### Cells outside 68.3 +- %.0f points\n\n| N | stride factor | statistic | cells | auto alpha | true alpha |\n"
      "|---:|---|---|---:|---:|---:|\n",
      flag_points);
  for (const auto& line : summary) std::printf("%s\n", line.c_str());
  std::printf("| all | | | %zu | %zu | %zu |\n", total, out_auto, out_true);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"coverage_study: Monte Carlo coverage of the offline engine's confidence intervals.", "coverage_study"};
  app.footer(R"(For each noise type alpha, length N, stride factor and statistic, RUNS realizations of power-law
phase noise (tests/support/power_law_noise.hpp) go through the engine twice: with alpha identified
by the engine and with the true alpha. At every octave m with a term, a cell counts the runs whose
68.3 % interval holds the true deviation (exact expectation from the noise's filter). Results do
not depend on the number of workers.

Examples:
  coverage_study                                   full study (1000 runs, about 2 minutes on 2 cores)
  coverage_study --runs 200 --lengths 4096 --csv coverage.csv
  coverage_study --alphas 0,2 --stride-factors 8 --stats mdev

Exit codes: 0 success, 1 the study failed otherwise, 2 bad options, 3 cannot write the CSV,
4 the engine refused a request.)");
  StudySettings s;
  s.lengths = {4096, 65536};
  s.stride_factors = {0, 8};
  std::vector<std::string> strides{"full", "8"}, stats{"oadev", "mdev"};
  std::string csv;
  app.add_option("--runs", s.runs, "realizations per (noise type, length)")->capture_default_str();
  app.add_option("--lengths", s.lengths, "phase points per realization")->delimiter(',')->capture_default_str();
  app.add_option("--alphas", s.alphas, "noise exponents, +2 .. -2")->delimiter(',')->capture_default_str();
  app.add_option("--stride-factors", strides, "'full' or powers of two >= 2")->delimiter(',')->capture_default_str();
  app.add_option("--stats", stats, "oadev, mdev")->delimiter(',')->capture_default_str();
  app.add_option("--max-m", s.max_m, "largest averaging factor (0: every octave with a term)")->capture_default_str();
  app.add_option("--workers", s.workers, "threads")->capture_default_str();
  app.add_option("--seed", s.seed, "base seed (runs are reproducible)")->capture_default_str();
  app.add_option("--csv", csv, "also write every cell to this CSV file")->option_text("PATH");
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "coverage_study: options: %s (see --help)\n", e.what());
    return 2;
  }
  auto bad = [](const char* what, const std::string& why) {
    std::fprintf(stderr, "coverage_study: %s: %s\n", what, why.c_str());
    return 2;
  };
  if (s.runs < 2) return bad("--runs", "at least 2");
  if (s.workers < 1 || s.workers > 256) return bad("--workers", "1 to 256");
  for (const int a : s.alphas)
    if (a < -2 || a > 2) return bad("--alphas", "each from -2 to +2 (AVAR and MVAR need alpha > -3)");
  for (const std::size_t n : s.lengths)
    if (n < 4 || n > (std::size_t{1} << 26)) return bad("--lengths", "each from 4 to 2^26 points");
  s.stride_factors.clear();
  for (const std::string& t : strides) {  // as gyrochar-analyze --stride-factor (plan.hpp), 0 for full
    const std::optional<gyrochar::StrideFactor> factor = gyrochar::StrideFactor::parse(t);
    if (!factor) return bad("--stride-factors", "'" + t + "' is neither 'full' nor a power of two from 2 to 2^24");
    s.stride_factors.push_back(factor->requested());
  }
  s.stats.clear();
  for (const std::string& t : stats) {
    if (t == "oadev") s.stats.push_back(Statistic::oadev);
    else if (t == "mdev") s.stats.push_back(Statistic::mdev);
    else return bad("--stats", "'" + t + "' is not oadev or mdev");
  }

  std::FILE* csv_file = nullptr;
  if (!csv.empty() && !(csv_file = std::fopen(csv.c_str(), "w"))) {
    std::fprintf(stderr, "coverage_study: %s: cannot write: %s\n", csv.c_str(), std::strerror(errno));
    return 3;
  }
  const auto start = std::chrono::steady_clock::now();
  auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); };
  s.progress = [&](std::size_t done, std::size_t total) {
    const double t = elapsed();
    const double left = done ? t * static_cast<double>(total - done) / static_cast<double>(done) : 0.0;
    std::fprintf(stderr, "\rcoverage_study: %zu of %zu realizations, %.0f s, about %.0f s left   ", done, total, t, left);
    if (done == total) std::fprintf(stderr, "\n");
  };
  std::vector<CoverageCell> cells;
  try {
    cells = run_coverage_study(s);
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "coverage_study: engine: %s\n", e.what());
    return 4;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "coverage_study: study: %s\n", e.what());
    return 1;
  }
  const double wall_s = elapsed();
  const double cpu_s = static_cast<double>(std::clock()) / CLOCKS_PER_SEC;  // all threads of the process
  std::fprintf(stderr, "coverage_study: %zu cells in %.1f s wall time (%u workers), %.1f s CPU time\n", cells.size(), wall_s,
               s.workers, cpu_s);
  if (csv_file && !write_csv(csv_file, cells)) {
    std::fprintf(stderr, "coverage_study: %s: cannot write: %s\n", csv.c_str(), std::strerror(errno));
    return 3;
  }
  print_markdown(s, cells, wall_s, cpu_s);
  return 0;
}
