#pragma once
// The board's estimator and its reports: counts go into the pyramid (exact), the decimated phase
// into the per-tau noise identification, and a report turns one snapshot into the protocol's
// messages (deviations, EDF, noise type, n, m, metadata, IEEE-952 fit). No heap: capacities are
// fixed (40 octave taus, stride factor up to 64); the firmware's event loop and the host
// simulation share this code.
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "gyrochar/noise_id.hpp"
#include "gyrochar/protocol.hpp"
#include "gyrochar/pyramid.hpp"

namespace gyrochar::firmware {

inline constexpr unsigned max_octaves = 40;
inline constexpr std::uint32_t max_stride_factor = 64;

struct EstimatorSettings {
  double tau0_s = 0.001;
  double pulse_weight_arcsec = 1.0;  // the angle unit on the wire is arcsec
  std::uint32_t stride_factor = 8;
  unsigned octaves = 32;
  protocol::InputSource source = protocol::InputSource::unknown;
  std::uint32_t config_hash = 0;
  std::uint16_t report_period_ms = 1000;
};

struct FaultCounters {
  std::uint32_t lost_edges = 0;
  std::uint32_t sample_gaps = 0;
  std::uint32_t tx_dropped_frames = 0;
  std::uint32_t bus_off_events = 0;
};

/// Everything one report says, from one snapshot.
struct ReportContent {
  protocol::StatusMsg status;
  protocol::StatusFaultsMsg faults;
  std::array<protocol::TauDevMsg, max_octaves> adev{}, mdev{};
  std::array<protocol::TauTermsMsg, max_octaves> terms{};
  std::array<protocol::TauInfoMsg, max_octaves> info{};
  protocol::MetaSamplingMsg sampling;
  protocol::MetaClockMsg clock;
  protocol::MetaScaleMsg scale;
  protocol::MetaConfigMsg config;
  std::array<protocol::Ieee952Msg, 5> ieee952{};
};

class Estimator {
 public:
  /// Returns false (nothing configured) for settings outside the fixed capacities.
  bool configure(const EstimatorSettings& s);
  /// One sample: pulses in one tau0 interval. O(S) amortized, no allocation.
  void add_count(std::int32_t count);
  /// A lost sample (gap): no term spans it.
  void mark_gap();
  /// Fills `out` for report `seq` from the current state. O(taus), no allocation.
  void report(std::uint8_t seq, std::uint64_t uptime_ms, const FaultCounters& faults, ReportContent& out) const;
  std::uint64_t samples() const { return samples_; }

  // Checkpoints: the pyramid's (versioned, CRC-checked) followed by the estimator's own state and a
  // second CRC. Restoring is a restart: a gap, then accumulation goes on. No allocation.
  std::size_t checkpoint_size() const;
  std::size_t save(std::span<std::byte> out) const;
  RestoreStatus restore(std::span<const std::byte> in);
  const Pyramid<CountArith>& pyramid() const { return pyramid_; }

 private:
  EstimatorSettings settings_;
  StaticPyramid<CountArith, max_octaves, max_stride_factor> pyramid_;
  struct Decimation {
    std::uint64_t countdown = 0;
    NoiseIdAccumulator noise;
  };
  std::array<Decimation, max_octaves> decimation_{};
  std::int64_t x_ = 0;
  std::uint64_t samples_ = 0;
  bool first_ = true;
  void decimate(std::int64_t x);
};

/// The message at position k of report `content.status.seq` (protocol::report_slot order).
protocol::Message report_message(const ReportContent& content, std::size_t k);

}  // namespace gyrochar::firmware
