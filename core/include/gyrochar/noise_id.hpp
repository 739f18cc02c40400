#pragma once
// Power-law noise identification per tau, streaming, as Stable32 does it (W. J. Riley and
// C. A. Greenhall, "Power law noise identification using the lag 1 autocorrelation", 2004; NIST
// SP 1065 section 5.6):
// - with at least 30 points of the decimated phase series: the lag-1 autocorrelation r1 of the
//   series and of its differences; difference until delta = r1/(1+r1) < 0.25 (or d = dmax),
//   alpha = 2 - round(2 delta) - 2 d;
// - with fewer points: the B1 ratio (standard variance of the m-averaged frequency over the
//   Allan variance) picks mu against Barnes' B1(N, mu), and for mu = -2 the ratio
//   R(n) = MVAR/AVAR separates white PM (1/n) from flicker PM.
// Only running sums are kept (about 250 bytes per tau); no heap, no clock.
#include <cstdint>

namespace gyrochar {

/// Lag-1 autocorrelation of a series from running sums, values shifted by the first one.
struct Lag1Sums {
  std::uint64_t n = 0, pairs = 0;
  double shift = 0, sum = 0, sum_sq = 0;         // of v = z - shift (shift: the first value)
  double sum_lag = 0, sum_left = 0, sum_right = 0;  // over adjacent pairs (v_i, v_i+1)
  double last = 0;
  bool linked = false;                           // the next value pairs with `last`
  void add(double z);
  /// The next value starts a new segment (no pair spans a gap).
  void unlink() { linked = false; }
  /// r1 = sum (z_i - mean)(z_{i+1} - mean) / sum (z_i - mean)^2; 0 with fewer than 3 values.
  double r1() const;
  /// Standard (n-1) variance of the values; 0 with fewer than 2.
  double variance() const;
};

/// Fed with the decimated phase series z_k = x[k m] (relative to any fixed reference): keeps the
/// lag-1 sums of the series and of its first, second and third differences.
class NoiseIdAccumulator {
 public:
  void add(double z);
  /// A gap: the next value starts a new segment; no difference or pair spans it.
  void reset_segment();
  std::uint64_t points() const { return order_[0].n; }
  const Lag1Sums& order(int d) const { return order_[d]; }

 private:
  Lag1Sums order_[4];
  double last_[3] = {0, 0, 0};  // last value of orders 0..2 in this segment
  int have_ = 0;                // values of this segment seen so far (capped at 3)
};

enum class NoiseIdMethod : std::uint8_t { none, lag1, b1, b1_rn };

struct NoiseId {
  int alpha = 0;
  NoiseIdMethod method = NoiseIdMethod::none;  // none: could not identify (too few points)
};

struct NoiseIdInput {
  std::uint64_t m = 1;        // averaging factor
  int dmax = 2;               // 2 for Allan and modified Allan, 3 for Hadamard
  bool frequency_data = false;  // the input was frequency: differencing starts at 1
  double avar = 0;            // overlapping AVAR at m (for B1 and R(n)), phase unit^2 / s^2
  double mvar = 0;            // MVAR at m, same unit
  double tau0_s = 1;          // sample interval (B1's frequency averages are in phase/(m tau0))
};

/// Identifies alpha at one tau. O(1), no allocation.
NoiseId identify_noise(const NoiseIdAccumulator& acc, const NoiseIdInput& in);

}  // namespace gyrochar
