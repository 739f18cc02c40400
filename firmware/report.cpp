#include "report.hpp"

#include <cmath>
#include <cstring>

#include "gyrochar/crc32.hpp"

#include "gyrochar/edf.hpp"
#include "gyrochar/ieee952.hpp"

namespace gyrochar::firmware {

bool Estimator::configure(const EstimatorSettings& s) {
  if (s.octaves < 1 || s.octaves > max_octaves || s.stride_factor > max_stride_factor || !(s.tau0_s > 0)) return false;
  std::array<std::uint64_t, max_octaves> m_list{};
  for (unsigned k = 0; k < s.octaves; ++k) m_list[k] = std::uint64_t{1} << k;
  if (pyramid_.configure({s.stride_factor, false}, std::span(m_list.data(), s.octaves)) != PyramidStatus::ok)
    return false;
  settings_ = s;
  decimation_ = {};
  x_ = 0;
  samples_ = 0;
  first_ = true;
  return true;
}

namespace {
struct EstimatorTail {  // what the estimator adds to the pyramid's checkpoint
  std::int64_t x = 0;
  std::uint64_t samples = 0;
};
}  // namespace

std::size_t Estimator::checkpoint_size() const {
  return pyramid_.checkpoint_size() + sizeof(EstimatorTail) + sizeof decimation_ + sizeof(std::uint32_t);
}

std::size_t Estimator::save(std::span<std::byte> out) const {
  if (out.size() < checkpoint_size()) return 0;
  std::size_t k = pyramid_.save(out);
  const EstimatorTail tail{x_, samples_};
  std::memcpy(out.data() + k, &tail, sizeof tail);
  k += sizeof tail;
  std::memcpy(out.data() + k, &decimation_, sizeof decimation_);
  k += sizeof decimation_;
  const std::uint32_t crc = crc32(out.first(k));
  std::memcpy(out.data() + k, &crc, sizeof crc);
  return k + sizeof crc;
}

RestoreStatus Estimator::restore(std::span<const std::byte> in) {
  const std::size_t size = checkpoint_size();
  std::uint32_t magic = 0;
  if (in.size() >= sizeof magic) std::memcpy(&magic, in.data(), sizeof magic);
  if (in.size() >= sizeof magic && magic != pyramid_.checkpoint_magic) return RestoreStatus::not_a_checkpoint;
  if (in.size() < size) return RestoreStatus::truncated;
  std::uint32_t crc = 0;
  std::memcpy(&crc, in.data() + size - sizeof crc, sizeof crc);
  if (crc != crc32(in.first(size - sizeof crc))) return RestoreStatus::corrupted;
  const RestoreStatus s = pyramid_.restore(in.first(pyramid_.checkpoint_size()));
  if (s != RestoreStatus::ok) return s;
  EstimatorTail tail;
  std::memcpy(&tail, in.data() + pyramid_.checkpoint_size(), sizeof tail);
  std::memcpy(&decimation_, in.data() + pyramid_.checkpoint_size() + sizeof tail, sizeof decimation_);
  x_ = tail.x;
  samples_ = tail.samples;
  mark_gap();
  return RestoreStatus::ok;
}

void Estimator::decimate(std::int64_t x) {
  for (unsigned i = 0; i < settings_.octaves; ++i) {
    Decimation& d = decimation_[i];
    if (d.countdown-- != 0) continue;
    d.countdown = (std::uint64_t{1} << i) - 1;
    d.noise.add(static_cast<double>(x));
  }
}

void Estimator::add_count(std::int32_t count) {
  if (first_) {
    decimate(x_);
    first_ = false;
  }
  x_ += count;
  ++samples_;
  pyramid_.add_increment(count);
  decimate(x_);
}

void Estimator::mark_gap() {
  pyramid_.mark_gap();
  for (Decimation& d : decimation_) {
    d.noise.reset_segment();
    d.countdown = 0;
  }
  first_ = true;
}

void Estimator::report(std::uint8_t seq, std::uint64_t uptime_ms, const FaultCounters& f, ReportContent& out) const {
  using namespace protocol;
  const auto taus = static_cast<std::uint8_t>(settings_.octaves);
  out.status = {seq, samples_ ? NodeState::running : NodeState::starting, taus, samples_};
  out.faults = {seq, f.lost_edges, f.sample_gaps, f.tx_dropped_frames, f.bus_off_events};
  const double arcsec_per_pulse = settings_.pulse_weight_arcsec;
  const std::uint64_t n_phase = pyramid_.phase_points();
  std::array<VariancePoint, max_octaves> points{};
  std::size_t n_points = 0;
  for (std::size_t i = 0; i < taus; ++i) {
    const auto r = pyramid_.result(i);
    const double tau = static_cast<double>(r.m) * settings_.tau0_s;
    const double avar = variance(r, Stat::avar, settings_.tau0_s, arcsec_per_pulse);
    const double mvar = variance(r, Stat::mvar, settings_.tau0_s, arcsec_per_pulse);
    NoiseIdInput in;
    in.m = r.m;
    in.tau0_s = settings_.tau0_s;
    in.avar = variance(r, Stat::avar, settings_.tau0_s);
    in.mvar = variance(r, Stat::mvar, settings_.tau0_s);
    const NoiseId id = identify_noise(decimation_[i].noise, in);
    const bool known = id.method != NoiseIdMethod::none;
    const std::uint64_t stride = pyramid_.stride(i);
    const double edf_a = known ? edf_for_terms(EdfStat::avar, id.alpha, r.m, stride, n_phase, r.n[0]) : 0.0;
    const double edf_m = known ? edf_for_terms(EdfStat::mvar, id.alpha, r.m, stride, n_phase, r.n[1]) : 0.0;
    const NoiseType noise = known ? noise_type(id.alpha) : NoiseType::not_identified;
    const bool clean = r.out_of_range == 0 && !r.sum_overflow;
    const auto idx = static_cast<std::uint8_t>(i);
    out.adev[i] = {seq, idx, DevKind::adev, static_cast<float>(std::sqrt(avar)), edf_a, noise, clean && r.n[0] > 0};
    out.mdev[i] = {seq, idx, DevKind::mdev, static_cast<float>(std::sqrt(mvar)), edf_m, noise, clean && r.n[1] > 0};
    out.terms[i] = {seq, idx, r.n[0]};
    out.info[i] = {seq, idx, r.m, static_cast<std::uint8_t>(std::countr_zero(stride))};
    if (r.n[0] > 0 && edf_a > 0) points[n_points++] = {tau, avar, edf_a};
  }
  out.sampling = {seq, static_cast<float>(settings_.tau0_s), static_cast<std::uint16_t>(settings_.stride_factor)};
  out.clock = {seq, uptime_ms, version};
  out.scale = {seq, static_cast<float>(arcsec_per_pulse), AngleUnit::arcsec, settings_.source};
  out.config = {seq, settings_.config_hash, settings_.report_period_ms};
  const Ieee952Fit fit = fit_ieee952(std::span(points.data(), n_points), Ieee952Curve::avar, settings_.tau0_s);
  for (std::size_t k = 0; k < 5; ++k) {
    const Ieee952Parameter& p = fit.p[k];
    const bool resolved = fit.ok && p.resolved && p.value > 0;
    out.ieee952[k] = {seq, static_cast<Ieee952Term>(k), resolved, resolved ? static_cast<float>(p.value) : 0.0f,
                      resolved ? p.uncertainty / p.value : 0.0};
  }
}

protocol::Message report_message(const ReportContent& c, std::size_t k) {
  using namespace protocol;
  const ReportSlot s = report_slot(c.status.seq, c.status.tau_count, k);
  switch (s.slot) {
    case Slot::status: return c.status;
    case Slot::faults: return c.faults;
    case Slot::adev: return c.adev[s.index];
    case Slot::mdev: return c.mdev[s.index];
    case Slot::terms: return c.terms[s.index];
    case Slot::tau_info: return c.info[s.index];
    case Slot::sampling: return c.sampling;
    case Slot::clock: return c.clock;
    case Slot::scale: return c.scale;
    case Slot::config: return c.config;
    case Slot::ieee952: return c.ieee952[s.index];
  }
  return c.status;
}

}  // namespace gyrochar::firmware
