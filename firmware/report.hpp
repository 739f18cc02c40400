#pragma once
// The board's reports: the characterizer (core/, the same one the offline analyzer runs) read out
// by the core extractors and the IEEE-952 fit, turned into the protocol's messages. Capacities are
// fixed (40 octave taus, stride factor up to 64) and the report's workspace is allocated once, at
// start-up; the firmware's event loop and the host simulation share this code.
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "gyrochar/characterizer.hpp"
#include "gyrochar/ieee952.hpp"
#include "gyrochar/wire/protocol.hpp"
#include "capacities.hpp"
#include "fit_worker.hpp"
#include "window.hpp"

namespace gyrochar::firmware {

using BoardCharacterizer = StaticCharacterizer<CountArith, max_octaves, max_stride_factor>;

struct ReportSettings {
  double tau0_s = 0.001;
  double pulse_weight_arcsec = 1.0;  // the angle unit on the wire is arcsec
  std::uint32_t stride_factor = 8;
  unsigned octaves = 32;
  protocol::InputSource source = protocol::InputSource::unknown;
  std::uint32_t config_hash = 0;  // also the characterizer's checkpoint tag
  std::uint32_t identity = 0;     // the gyro the data belongs to (gyro_identity()), in checkpoints
  std::uint16_t report_period_ms = 1000;
  std::uint64_t window_length = 0;  // samples per window of the dynamic Allan deviation (window.hpp)
  unsigned window_taus = 0;         // its taus, window_taus(octaves, window_length); 0: no window
};

/// Configures `c` for octave taus 1, 2, ..., 2^(octaves-1) with the settings' stride factor and
/// the config hash as checkpoint tag and the identity as checkpoint identity. False (c unusable) for settings outside the capacities.
bool configure(BoardCharacterizer& c, const ReportSettings& s);

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
  protocol::Ieee952SummaryMsg ieee952_summary;
  // The selected model beyond the five terms (version 4), from the same fit.
  protocol::Ieee952ModelMsg ieee952_model;
  std::array<protocol::Ieee952ParameterMsg, protocol::fit_parameter_pages> ieee952_parameters{};
  // Each term's unconstrained estimate (version 5), from the same fit.
  std::array<protocol::Ieee952UnconstrainedMsg, 5> unconstrained{};
  // The window curve (version 3): the window completed last when the slow cycle began.
  std::size_t window_taus = 0;  // 0: the node has no window, and the reports no window frames
  protocol::WindowMsg window;
  protocol::WindowLengthMsg window_length;
  std::array<protocol::WindowDevMsg, max_window_taus> window_dev{};
  // The fit the IEEE-952 frames of the current slow cycle are made from (taken at its first report;
  // kept across reports: build_report() reads it), and the samples it was made from (0: none yet).
  Ieee952Fit fit;
  std::uint64_t fit_samples = 0;
};

/// What build_report() works in, allocated once for `octaves` taus: the cache of the covariance
/// sums behind the EDFs and the noise identification (noise_model.hpp: computed once per tau, then
/// O(1) per report as the run grows), and the IEEE-952 fit (fit_worker.hpp: inline or beside the
/// report loop, with its own cache).
class ReportWorkspace {
 public:
  explicit ReportWorkspace(unsigned octaves, FitMode fit_mode = FitMode::inline_fit);
  PairSumCache& cache() { return cache_; }
  FitWorker& fitter() { return fitter_; }

 private:
  std::vector<PairSumCache::Entry> entries_;
  PairSumCache cache_;
  FitWorker fitter_;
};
static_assert(2 * max_octaves <= FitWorker::max_points);
static_assert(max_markov <= protocol::wire_markov_terms && max_sinusoids <= protocol::wire_sinusoids,
              "the protocol must carry every Markov term and sinusoid a fit can hold");

/// When a report that carries the IEEE-952 frames asks for a new fit: once the run has grown by a
/// quarter since the points of the last fit, or by `refit_after_s` of samples. In between the
/// frames repeat the latest fit: it changes slowly as the run grows.
inline constexpr double refit_after_s = 900.0;
bool refit_due(std::uint64_t samples, std::uint64_t last_fit_samples, double tau0_s);

/// Fills `out` for report `seq` from the characterizer's current state: the deviations, EDFs and
/// noise types of every report, the IEEE-952 frames of the fit taken at the first report of the
/// slow cycle (`out` keeps it for the cycle's other reports: pass the same `out` every report) and, when the settings have window taus, the curve of `window` (the
/// board's latest completed window), taken at the first report of each slow cycle and repeated
/// through it. No allocation: everything is worked out in `work` (built for the same number of
/// octaves).
void build_report(const Characterizer<CountArith>& c, const ReportSettings& s, std::uint8_t seq, std::uint64_t uptime_ms,
                  const FaultCounters& faults, ReportWorkspace& work, ReportContent& out,
                  const WindowCurve* window = nullptr);

/// The message at position k of report `content.status.seq` (protocol::report_slot order, with
/// content.window_taus window taus).
protocol::Message report_message(const ReportContent& content, std::size_t k);

}  // namespace gyrochar::firmware
