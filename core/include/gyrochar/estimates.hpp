#pragma once
// The extractors: what the characterizer's sums say, per tau. The board's reports and the offline
// analyzer call the same functions on the same sums, so they print the same numbers.
//
//   take_sums()       the sums of every tau, in floating point (one snapshot)
//   identify_noise()  the power-law noise at every tau of a curve, and how it was chosen
//   estimate()        one statistic at one tau: deviation, number of terms, EDF
//
// Noise identification weighs, for every candidate alpha, the evidence at each tau:
//   - the lag-1 autocorrelation rule (noise_id.hpp) where the decimated series x[k m] has at least
//     lag1_min_points points: p = 2 - alpha with its standard error;
//   - R(n) = MVAR/AVAR against its exact expectation for pure noise alpha, with the exact variance
//     of the ratio of the two estimates (noise_model.hpp): it separates white from flicker PM and
//     keeps its power at long taus, where the decimated series is short;
//   - the identification of the next shorter tau (a power-law model changes slowly with tau).
// Each counts as a squared z-score (with a floor of 10 % for model error); the alpha with the least
// total wins, and every alpha within one unit of it is "plausible". With none of these available
// (very short records), the B1 ratio and R(n) decide as Stable32 does.
//
// EDF. The EDF of the estimator actually used (its stride, its number of phase points, the terms
// a gap removed), computed exactly for the discrete power-law noise (noise_model.hpp). Where more
// than one alpha is plausible, the smallest of their EDFs: the widest interval the data allow.
// With it the skewness of the estimate's distribution (skew_dof), for intervals that match three
// moments instead of two.
// EdfModel::greenhall gives Greenhall & Riley's approximation for the identified alpha instead, as
// Stable32 and allantools print it (for comparisons; it overstates the EDF at small m).
//
// All functions are deterministic, allocate nothing and read no clock.
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "gyrochar/characterizer.hpp"
#include "gyrochar/noise_id.hpp"
#include "gyrochar/noise_model.hpp"
#include "gyrochar/stat.hpp"

namespace gyrochar {

// The statistics (DevStat), their names and sums: stat.hpp.

/// The sums of one tau in floating point. variance[k] is in (x step / tau0)^2 (variance() with
/// tau0 = 1 and unit 1); `noise` summarizes the lag-1 sums of the decimated series (when has_noise).
struct TauSums {
  std::uint64_t m = 0;
  std::uint64_t stride = 1;
  std::array<double, sum_kinds> variance{};
  std::array<std::uint64_t, sum_kinds> n{};
  bool clean = true;  // no term out of range, no sum overflow
  bool has_noise = false;
  Lag1Summary noise;
};

/// The sums of one tau from its exact or floating sums and its noise sums (either accumulator of
/// noise_id.hpp): what the characterizer (take_sums()) and the batch path (batch.hpp) both give
/// the extractors. O(1), no allocation.
template <class Sum, class NoiseSums>
TauSums tau_sums(const TauResult<Sum>& r, const NoiseSums& noise) {
  TauSums t;
  t.m = r.m;
  t.stride = r.stride;
  t.n = r.n;
  for (std::size_t k = 0; k < sum_kinds; ++k) t.variance[k] = variance(r, static_cast<SumKind>(k), 1.0);
  t.clean = r.out_of_range == 0 && !r.sum_overflow;
  t.has_noise = true;
  t.noise = summarize(noise);
  return t;
}

/// Fills out[0 .. tau_count) from the characterizer. O(taus), no allocation.
template <class Arith>
void take_sums(const Characterizer<Arith>& c, std::span<TauSums> out) {
  for (std::size_t i = 0; i < c.tau_count() && i < out.size(); ++i) out[i] = tau_sums(c.result(i), c.noise(i));
}

enum class NoiseIdMethod : std::uint8_t {
  none,       // not identified: no EDF, no interval
  given,      // alpha fixed by the user
  lag1,       // lag-1 autocorrelation of this tau's decimated series (with R(n) and the neighbour)
  rn,         // R(n) = MVAR/AVAR and the neighbouring tau (too few points for the lag-1 rule)
  neighbour,  // taken from the next shorter tau (no evidence of its own at this tau)
  b1,         // B1 ratio (no tau had enough points for the lag-1 rule)
  b1_rn,      // B1 ratio, white and flicker PM told apart by R(n)
};
/// "none", "given", "lag1", "neighbour", "b1", "b1_rn": a static string.
const char* name(NoiseIdMethod m);

struct NoiseId {
  int alpha = 0;          // the most likely exponent
  int low = 0, high = 0;  // plausible exponents: low <= alpha <= high
  NoiseIdMethod method = NoiseIdMethod::none;
  bool identified() const { return method != NoiseIdMethod::none; }
};

/// Decimated points the lag-1 rule needs at a tau (Riley & Greenhall: about 30).
inline constexpr std::uint64_t lag1_min_points = 30;

/// Identifies the noise at every tau of one curve (taus in increasing m) of a run of n_phase phase
/// points. dmax = 2 for the Allan and modified Allan statistics, 3 for Hadamard (R(n) needs AVAR,
/// which diverges below alpha = -2: there it scores as random-walk FM); frequency_input: the data were
/// frequency, so the lag-1 rule starts at the first difference. out.size() >= taus.size().
/// O(taus x alphas x pair_sums()), no allocation.
void identify_noise(std::span<const TauSums> taus, std::uint64_t n_phase, int dmax, bool frequency_input,
                    std::span<NoiseId> out, PairSumCache* cache = nullptr);

/// A fixed alpha, as the user gives it.
constexpr NoiseId given_noise(int alpha) { return {alpha, alpha, alpha, NoiseIdMethod::given}; }

enum class EdfModel : std::uint8_t { exact, greenhall };

struct EstimateOptions {
  double tau0_s = 1.0;  // sample interval
  double unit = 1.0;    // phase unit of one x step (pulse weight for counts; tau0 for frequency)
  EdfModel edf = EdfModel::exact;
  bool skewness = true;  // also the skew degrees of freedom (where the EDF is below 100)
};

/// One statistic at one tau. Deviations are in phase unit per second (TDEV: phase unit).
struct Estimate {
  DevStat stat = DevStat::oadev;
  std::uint64_t m = 0;
  double tau_s = 0;
  std::uint64_t n = 0;       // terms (Stable32's "#")
  std::uint64_t stride = 1;  // terms every `stride` phase points (m for adev and hdev)
  double variance = 0;       // AVAR, MVAR, TVAR or HVAR in (phase unit / s)^2 (TVAR: phase unit^2)
  double deviation = 0;
  NoiseId noise;
  int edf_alpha = 0;    // the alpha whose EDF was used (the smallest of the plausible ones)
  double edf = 0;       // 0: not available (no identification, or alpha outside the statistic's range)
  double skew_dof = 0;  // nu3 of noise_model.hpp (the distribution's skewness); 0: plain chi-squared
  bool clean = true;
};

/// The estimate of `stat` at one tau of a run of n_phase phase points, with its EDF for `noise`.
/// n = 0 when the tau has no term yet. O(EDF): pair_sums() of noise_model.hpp, at most a few
/// thousand covariance evaluations, or O(1) from `cache` (optional; so for identify_noise()).
Estimate estimate(const TauSums& tau, std::uint64_t n_phase, DevStat stat, const NoiseId& noise,
                  const EstimateOptions& options, PairSumCache* cache = nullptr);

}  // namespace gyrochar
