// The offline analysis engine against Stable32 and NIST SP 1065 on the reference sets in
// tests/data (README there): n exact; deviation within 1e-4 relative (Stable32 prints 5
// digits), 5e-5 for the OCXO all-tau files, 2e-3 for the OCXO octave files (Stable32 lost
// precision normalising them); CI bounds within 1e-3 relative (2e-3 OCXO octave) when computed
// with Stable32's alpha and Stable32's EDF (EdfModel::greenhall). gyrochar's own intervals use the
// exact EDF of the discrete noise model on purpose: Greenhall's approximation overstates the EDF at
// small m (white FM, m = 1: 3204 where the estimator has 2730, tests/core/test_noise_model.cpp), so
// Stable32's intervals are too narrow there. The automatic noise identification equal to Stable32's
// where both use the lag-1 rule.
#include <gtest/gtest.h>

#include <cctype>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "analysis.hpp"
#include "datafile.hpp"

namespace gyrochar {
namespace {

const std::string ref = GYROCHAR_TEST_DATA;
const std::vector<std::string> stat_names{"adev", "oadev", "mdev", "tdev", "hdev", "ohdev"};

// One data row of a Stable32 result file: AF Tau # Alpha MinSigma Sigma MaxSigma.
struct Stable32Row {
  std::uint64_t m = 0, n = 0;
  int alpha = 0;
  double min = 0, sigma = 0, max = 0;
};

// commented: also the rows the files keep behind a '#' (the longest taus of some total-family files).
std::vector<Stable32Row> read_stable32(const std::string& path, bool commented = false) {
  std::ifstream in(path);
  EXPECT_TRUE(in) << path;
  std::vector<Stable32Row> rows;
  for (std::string line; std::getline(in, line);) {
    if (commented && line.size() > 1 && line[0] == '#' &&
        std::isdigit(static_cast<unsigned char>(line[line.find_first_not_of("# ")])))
      line = line.substr(1);
    if (line.empty() || line[0] == '#') continue;
    std::istringstream ss(line);
    Stable32Row r;
    double tau = 0, n = 0;  // Theo1 prints # as 4.9550e+03
    if (ss >> r.m >> tau >> n >> r.alpha >> r.min >> r.sigma >> r.max) {
      r.n = static_cast<std::uint64_t>(std::llround(n));
      rows.push_back(r);
    }
  }
  return rows;
}

// n as Stable32 prints it: to 5 significant digits, halves rounded up (102245 -> 1.0225e+05).
std::uint64_t printed(std::uint64_t n) {
  std::uint64_t unit = 1;
  while (n / unit >= 100000) unit *= 10;
  return (n + unit / 2) / unit * unit;
}

std::vector<double> read_values(const std::string& path) {
  DataFile file(path);
  std::vector<double> v;
  for (double x = 0; file.next(x);) v.push_back(x);
  return v;
}

Analysis run(const std::vector<double>& values, DataType type, DevStat stat, std::vector<std::uint64_t> m_list,
             std::optional<int> alpha = std::nullopt, EdfModel edf = EdfModel::exact) {
  AnalysisOptions o;
  o.edf = edf;
  o.type = type;
  o.tau0_s = 1.0;
  o.theo_m_list = m_list;  // Theo1 and TheoBR rows at the file's averaging factors
  o.m_list = std::move(m_list);
  o.stats = {stat};
  o.alpha = alpha;
  o.total_stride_factor = 0;  // the exact estimators
  Analyzer analyzer(o);
  for (const double v : values) analyzer.add(v);
  return analyzer.result();
}

const AnalysisRow* find(const Analysis& a, std::uint64_t m) {
  for (const auto& r : a.rows)
    if (r.m == m) return &r;
  return nullptr;
}

struct Tolerance {
  double dev = 1e-4;
  double ci = 1e-3;
  bool commented = false;  // compare the '#' rows too
  // Rows whose bounds must be within `ci`; the others (where Stable32's EDF is not the one gyrochar
  // uses, documented in docs/total.md) within `departure`.
  std::function<bool(const Stable32Row&)> ci_where = [](const Stable32Row&) { return true; };
  double departure = 0;
};

// Every row of a Stable32 file: n, deviation and (where the file has them) the CI bounds computed
// with the file's alpha. Returns the engine's automatic analysis of the same taus.
Analysis compare(const std::vector<double>& values, DataType type, DevStat stat, const std::string& file, Tolerance tol) {
  const auto rows = read_stable32(file, tol.commented);
  EXPECT_FALSE(rows.empty()) << file;
  std::vector<std::uint64_t> m_list;
  for (const auto& r : rows) m_list.push_back(r.m);
  std::map<int, Analysis> with_alpha;  // one run per alpha Stable32 used
  for (const auto& r : rows)
    if (!with_alpha.count(r.alpha)) with_alpha[r.alpha] = run(values, type, stat, m_list, r.alpha, EdfModel::greenhall);
  for (const auto& r : rows) {
    const AnalysisRow* got = find(with_alpha[r.alpha], r.m);
    if (got == nullptr) {
      ADD_FAILURE() << file << " m=" << r.m << " missing";
      continue;
    }
    EXPECT_EQ(printed(got->n), printed(r.n)) << file << " m=" << r.m;  // exact below 10^5
    EXPECT_NEAR(got->dev / r.sigma, 1.0, tol.dev) << file << " m=" << r.m;
    if (r.min > 0) {
      EXPECT_TRUE(got->ci.valid) << file << " m=" << r.m;
      const double t = tol.ci_where(r) ? tol.ci : tol.departure;
      EXPECT_NEAR(got->ci.low / r.min, 1.0, t) << file << " m=" << r.m << " low";
      EXPECT_NEAR(got->ci.high / r.max, 1.0, t) << file << " m=" << r.m << " high";
    }
  }
  return run(values, type, stat, m_list);
}

// The automatic alpha equals Stable32's on the rows `where` selects; returns the rows compared.
int expect_same_alpha(const Analysis& automatic, const std::string& file,
                      const std::function<bool(const Stable32Row&)>& where) {
  int compared = 0;
  for (const auto& r : read_stable32(file)) {
    if (!where(r)) continue;
    const AnalysisRow* got = find(automatic, r.m);
    ++compared;
    if (got == nullptr || !got->alpha) {
      ADD_FAILURE() << file << " m=" << r.m << ": no alpha";
      continue;
    }
    EXPECT_EQ(*got->alpha, r.alpha) << file << " m=" << r.m << " (noise identification)";
  }
  return compared;
}

std::vector<double> ocxo_fractional_frequency() {
  auto f = read_values(ref + "/ocxo/ocxo_frequency.txt");
  for (double& v : f) v = (v - 1e7) / 1e7;  // frequency in Hz of a 10 MHz oscillator
  return f;
}

TEST(Stable32, PhaseDatEveryAveragingFactor) {
  const auto x = read_values(ref + "/phasedat/PHASE.DAT");
  ASSERT_EQ(x.size(), 1001u);
  for (const auto& s : stat_names)
    compare(x, DataType::phase, *parse_dev_stat(s), ref + "/phasedat/phase_dat_" + s + ".txt", {});
}

TEST(Stable32, PhaseDatOctavesWithConfidenceIntervals) {
  const auto x = read_values(ref + "/phasedat/PHASE.DAT");
  for (const auto& s : stat_names)
    compare(x, DataType::phase, *parse_dev_stat(s), ref + "/phasedat/phase_dat_" + s + "_octave.txt", {});
}

TEST(Stable32, OcxoFrequencyAllTaus) {
  const auto y = ocxo_fractional_frequency();
  ASSERT_EQ(y.size(), 19982u);
  for (const auto& s : stat_names)
    compare(y, DataType::freq, *parse_dev_stat(s), ref + "/ocxo/stable32_" + s + "_alltau.txt", {5e-5, 0});
}

TEST(Stable32, OcxoFrequencyOctavesWithConfidenceIntervalsAndNoiseIdentification) {
  const auto y = ocxo_fractional_frequency();
  // Where Stable32 and gyrochar identify differently on purpose (m = 16 and 32): Stable32's lag-1
  // rule alone says random-walk FM (-2), gyrochar's combined evidence (R(n) = MVAR/AVAR with its
  // exact variance, and the neighbouring taus) says flicker FM (-1). Oracle for which is right: the
  // curve itself, ADEV ~ tau^((-alpha-1)/2): from m = 16 to 64 it falls and then stays flat
  // (slopes about -0.3 and 0), where random-walk FM would rise as tau^0.5.
  const std::set<std::uint64_t> departures{16, 32};
  for (const auto& s : stat_names) {
    const std::string file = ref + "/ocxo/" + s + "_octave.txt";
    const Analysis automatic = compare(y, DataType::freq, *parse_dev_stat(s), file, {2e-3, 2e-3});
    // The lag-1 autocorrelation rule (>= 30 averages) reproduces Stable32 on every such row but the
    // departures. With fewer (m >= 1024 here) Stable32 falls back to the B1 ratio alone and picks
    // white FM at m = 2048 and 4096 where the ADEV rises: not required, not checked.
    EXPECT_GE(expect_same_alpha(automatic, file,
                                [&](const Stable32Row& r) { return (y.size() + 1) / r.m >= 30 && !departures.count(r.m); }),
              8)
        << file;
    if (s != "oadev") continue;
    for (const std::uint64_t m : departures) {
      const AnalysisRow* here = find(automatic, m);
      const AnalysisRow* later = find(automatic, 2 * m);
      ASSERT_TRUE(here && later && here->alpha);
      EXPECT_EQ(*here->alpha, -1) << "m=" << m;
      const double slope = std::log2(later->dev / here->dev);  // (-alpha - 1) / 2 for pure noise
      EXPECT_LT(slope, 0.25) << "m=" << m << ": nearer flicker FM (0) than random-walk FM (0.5)";
    }
  }
}

TEST(Stable32, KeysightTimeIntervalNoiseFloorWithNoiseIdentification) {
  const auto x = read_values(ref + "/Keysight53230A_ti_noise_floor/tic_phase.txt");
  ASSERT_EQ(x.size(), 55688u);
  for (const auto& s : stat_names) {
    const std::string file = ref + "/Keysight53230A_ti_noise_floor/tic_" + s + ".txt";
    const Analysis automatic = compare(x, DataType::phase, *parse_dev_stat(s), file, {});
    // Octave rows (1..8192; 1..64 in the log-spaced adev file), alpha 2 then 1: the case only
    // R(n) = MVAR/AVAR separates.
    EXPECT_GE(expect_same_alpha(automatic, file, [](const Stable32Row& r) { return (r.m & (r.m - 1)) == 0; }), 7) << file;
  }
}

TEST(Stable32, KeysightNoiseIdentificationAtEveryAveragingFactor) {
  // tic_adev.txt has 260 averaging factors. Stable32's choices there are not all reproducible from
  // its published rules (lag-1 ACF with >= 30 points, B1 and R(n) below): at some non-octave m it
  // reports alpha 0 where both the lag-1 ACF and B1/R(n) give 1 or 2. We require the agreement
  // measured (222 of 260 = 85 %; every octave row agrees, see above) not to drop.
  const auto x = read_values(ref + "/Keysight53230A_ti_noise_floor/tic_phase.txt");
  const auto rows = read_stable32(ref + "/Keysight53230A_ti_noise_floor/tic_adev.txt");
  ASSERT_EQ(rows.size(), 260u);
  std::vector<std::uint64_t> m_list;
  for (const auto& r : rows) m_list.push_back(r.m);
  const Analysis a = run(x, DataType::phase, DevStat::adev, m_list);
  int agree = 0;
  for (const auto& r : rows) {
    const AnalysisRow* got = find(a, r.m);
    if (got && got->alpha && *got->alpha == r.alpha) ++agree;
  }
  std::printf("noise identification agrees with Stable32 on %d of %zu averaging factors\n", agree, rows.size());
  EXPECT_GE(agree, 222);
}

// The total and Theo family (docs/total.md): every row of Stable32's files, the '#' rows included,
// with Stable32's alpha: deviations within 1e-4 (2e-3 OCXO octave), n exact (Theo1's as printed).
// Intervals from NIST SP 1065's EDF formulas within 1e-2 of Stable32's where Stable32 uses them:
// TOTDEV (white, flicker, random-walk FM), HTOTDEV for alpha <= 0 (table 9 from m = 16, the OHDEV
// estimate's EDF below), MTOTDEV and TTOTDEV up to m = 16. Elsewhere Stable32's EDF is not SP
// 1065's (inverted from its bounds: about 1.33 N/m - 1.9 for MTOTDEV at white FM where table 8 has
// 1.10 N/m - 1.2; for TOTDEV and HTOTDEV at flicker PM, where SP 1065 has no formula and gyrochar
// takes the Allan-family estimate's exact EDF): there the bounds depart by up to the amounts below,
// measured, the largest at the longest taus.
TEST(Stable32, TotalFamilyOnPhaseDat) {
  const auto x = read_values(ref + "/phasedat/PHASE.DAT");
  const std::string dir = ref + "/phasedat/phase_dat_";
  Tolerance tol{1e-4, 1e-2, true};
  for (const char* f : {"totdev", "totdev_octave"}) compare(x, DataType::phase, DevStat::totdev, dir + f + ".txt", tol);
  tol.ci_where = [](const Stable32Row& r) { return r.alpha <= 0; };
  tol.departure = 0.035;  // measured 3.1 % (alpha 1, m = 256)
  for (const char* f : {"htotdev_octave", "htotdev_octave_nobias"})
    compare(x, DataType::phase, DevStat::htotdev, dir + f + ".txt", tol);
  tol.ci_where = [](const Stable32Row& r) { return r.m <= 16; };
  tol.departure = 0.07;  // measured 6.4 % (m = 200, alpha 1)
  for (const char* f : {"mtotdev_octave", "mtotdev_octave_alpha0", "mtotdev_decade"})
    compare(x, DataType::phase, DevStat::mtotdev, dir + f + ".txt", tol);
  for (const char* f : {"ttotdev_octave", "ttotdev_decade"})
    compare(x, DataType::phase, DevStat::ttotdev, dir + f + ".txt", tol);
  for (const char* f : {"theo1_alpha0", "theo1_alpha0_decade"})
    compare(x, DataType::phase, DevStat::theo1, dir + f + ".txt", tol);
}

TEST(Stable32, TotdevOnTheOcxoAndKeysightSets) {
  const auto y = ocxo_fractional_frequency();
  compare(y, DataType::freq, DevStat::totdev, ref + "/ocxo/stable32_totdev_alltau.txt", {5e-5, 0});
  compare(y, DataType::freq, DevStat::totdev, ref + "/ocxo/totdev_octave.txt", {2e-3, 1e-2});
  Tolerance tol{1e-4, 1e-2};
  tol.ci_where = [](const Stable32Row& r) { return r.alpha != 1; };
  tol.departure = 0.02;  // measured 1.5 % (m = 4096)
  compare(read_values(ref + "/Keysight53230A_ti_noise_floor/tic_phase.txt"), DataType::phase, DevStat::totdev,
          ref + "/Keysight53230A_ti_noise_floor/tic_totdev.txt", tol);
}

// NIST SP 1065 values from a *_expected.csv: {stat -> deviations at the file's m}.
std::map<DevStat, std::vector<double>> read_expected(const std::string& path, std::size_t columns) {
  std::ifstream in(path);
  EXPECT_TRUE(in) << path;
  std::map<DevStat, std::vector<double>> out;
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream ss(line);
    std::string field;
    std::getline(ss, field, ',');
    const auto stat = parse_dev_stat(field);
    if (!stat) continue;  // header, and the statistics the engine does not have
    for (std::size_t k = 0; k < columns && std::getline(ss, field, ','); ++k) out[*stat].push_back(std::stod(field));
  }
  return out;
}

void expect_nist(const std::vector<double>& values, DataType type, const std::string& expected_csv,
                 const std::vector<std::uint64_t>& m_list, std::size_t statistics) {
  const auto expected = read_expected(expected_csv, m_list.size());
  EXPECT_EQ(expected.size(), statistics) << expected_csv;  // every statistic of the table the engine has
  for (const auto& [stat, devs] : expected) {
    ASSERT_EQ(devs.size(), m_list.size());
    const Analysis a = run(values, type, stat, m_list, 0);
    for (std::size_t k = 0; k < m_list.size(); ++k) {
      const AnalysisRow* got = find(a, m_list[k]);
      ASSERT_NE(got, nullptr) << name(stat) << " m=" << m_list[k];
      EXPECT_NEAR(got->dev / devs[k], 1.0, 1e-4) << name(stat) << " m=" << m_list[k];
    }
  }
}

TEST(NistSp1065, Nbs14TenPointPhaseAndNinePointFrequency) {
  // The 9 frequency values are the differences of the 10 phase values plus a constant, which no
  // statistic sees: both reproduce the same table (NIST SP 1065 NBS14, m = 1 and 2).
  const std::string expected = ref + "/nbs14/nbs14_10point_expected.csv";
  // The six Allan-family statistics and TOTDEV, MTOTDEV, TTOTDEV, HTOTDEV (HTOTDEV at m = 2 with the
  // white-FM bias correction the table's value carries).
  expect_nist(read_values(ref + "/nbs14/nbs14_10point_phase.txt"), DataType::phase, expected, {1, 2}, 10);
  expect_nist(read_values(ref + "/nbs14/nbs14_10point_freq.txt"), DataType::freq, expected, {1, 2}, 10);
}

TEST(NistSp1065, Nbs14ThousandPointFrequency) {
  expect_nist(read_values(ref + "/nbs14/nbs14_1000point_freq.txt"), DataType::freq,
              ref + "/nbs14/nbs14_1000point_expected.csv", {1, 10, 100}, 8);
}

}  // namespace
}  // namespace gyrochar
