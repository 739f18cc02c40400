// The report's schedule (which frame goes in which report, docs/protocol.md "Schedule") and the
// worst-case bus load it makes.
#include "gyrochar/wire/protocol.hpp"

#include <algorithm>

namespace gyrochar::protocol {

namespace {
constexpr std::size_t fast_frames(std::size_t tau_count) { return 2 + 2 * tau_count; }
constexpr std::size_t metadata_pages = 4;
constexpr std::size_t ieee952_terms = 5;
/// Metadata pages, tau info and terms per tau, the IEEE-952 terms and (version 2) the fit summary.
constexpr std::size_t slow_list_length(std::size_t tau_count, std::uint8_t protocol_version) {
  return metadata_pages + 2 * tau_count + ieee952_terms + (protocol_version >= 2 ? 1 : 0);
}
/// Versions 1 and 2 cut into parts of the same length (9 + 2T is odd, 10 + 2T the next integer).
constexpr std::size_t slow_part_length(std::size_t tau_count) {
  return (slow_list_length(tau_count, 1) + slow_cycle_reports - 1) / slow_cycle_reports;
}
constexpr bool part_lengths_agree() {
  for (std::size_t t = 0; t <= max_taus; ++t)
    if ((slow_list_length(t, 2) + slow_cycle_reports - 1) / slow_cycle_reports != slow_part_length(t)) return false;
  return true;
}
static_assert(part_lengths_agree(), "the summary must not move any frame of the version-1 schedule");
std::size_t slow_part_begin(std::uint8_t seq, std::size_t tau_count) {
  return seq % slow_cycle_reports * slow_part_length(tau_count);
}
std::size_t part_of(std::uint8_t seq, std::size_t list_length, std::size_t part_length) {
  const std::size_t begin = seq % slow_cycle_reports * part_length;
  return begin >= list_length ? 0 : std::min(part_length, list_length - begin);
}

/// The window list (version 3): the window page, the window length, then one WindowDevMsg per
/// window tau; empty without window taus. Cut into parts like the slow list.
constexpr std::size_t window_list_length(std::size_t window_taus, std::uint8_t protocol_version) {
  return protocol_version >= 3 && window_taus > 0 ? 2 + window_taus : 0;
}
constexpr std::size_t window_part_length(std::size_t window_taus, std::uint8_t protocol_version) {
  return (window_list_length(window_taus, protocol_version) + slow_cycle_reports - 1) / slow_cycle_reports;
}

/// The model list (version 4): the Ieee952 model page, then every parameter page. Cut into parts
/// like the slow list.
constexpr std::size_t model_list_length(std::uint8_t protocol_version) {
  return protocol_version >= 4 ? 1 + fit_parameter_pages : 0;
}
constexpr std::size_t model_part_length(std::uint8_t protocol_version) {
  return (model_list_length(protocol_version) + slow_cycle_reports - 1) / slow_cycle_reports;
}

/// The unconstrained list (version 5): the Ieee952Unconstrained frames of Q N B K R. Cut into parts
/// like the slow list.
constexpr std::size_t unconstrained_list_length(std::uint8_t protocol_version) {
  return protocol_version >= 5 ? ieee952_terms : 0;
}
constexpr std::size_t unconstrained_part_length(std::uint8_t protocol_version) {
  return (unconstrained_list_length(protocol_version) + slow_cycle_reports - 1) / slow_cycle_reports;
}

/// Entry j of the slow list: metadata pages, tau info for every tau, terms for every tau, IEEE-952
/// terms, then the fit summary (version 2; the caller keeps j below the version's list length).
ReportSlot slow_slot(std::size_t j, std::size_t tau_count) {
  if (j < metadata_pages) {
    constexpr Slot pages[metadata_pages] = {Slot::sampling, Slot::clock, Slot::scale, Slot::config};
    return {pages[j], 0};
  }
  j -= metadata_pages;
  if (j < tau_count) return {Slot::tau_info, std::uint8_t(static_cast<unsigned>(j))};
  j -= tau_count;
  if (j < tau_count) return {Slot::terms, std::uint8_t(static_cast<unsigned>(j))};
  return {Slot::ieee952, std::uint8_t(static_cast<unsigned>(j - tau_count))};
}

/// Entry j of the window list.
ReportSlot window_slot(std::size_t j) {
  if (j == 0) return {Slot::window, 0};
  if (j == 1) return {Slot::window_length, 0};
  return {Slot::window_dev, std::uint8_t(static_cast<unsigned>(j - 2))};
}

/// Entry j of the model list.
ReportSlot model_slot(std::size_t j) {
  if (j == 0) return {Slot::fit_model, 0};
  return {Slot::fit_parameter, std::uint8_t(static_cast<unsigned>(j - 1))};
}

/// Frames of report seq before its window part: the fast frames and its part of the slow list.
std::size_t frames_before_window(std::uint8_t seq, std::size_t tau_count, std::uint8_t protocol_version) {
  return fast_frames(tau_count) + part_of(seq, slow_list_length(tau_count, protocol_version), slow_part_length(tau_count));
}
/// Frames of report seq before its model part: those and its part of the window list.
std::size_t frames_before_model(std::uint8_t seq, std::size_t tau_count, std::uint8_t protocol_version,
                                std::size_t window_taus) {
  return frames_before_window(seq, tau_count, protocol_version) +
         part_of(seq, window_list_length(window_taus, protocol_version), window_part_length(window_taus, protocol_version));
}
/// Frames of report seq before its unconstrained part: those and its part of the model list.
std::size_t frames_before_unconstrained(std::uint8_t seq, std::size_t tau_count, std::uint8_t protocol_version,
                                        std::size_t window_taus) {
  return frames_before_model(seq, tau_count, protocol_version, window_taus) +
         part_of(seq, model_list_length(protocol_version), model_part_length(protocol_version));
}
}  // namespace

std::size_t report_frame_count(std::uint8_t seq, std::size_t tau_count, std::uint8_t protocol_version,
                               std::size_t window_taus) {
  return frames_before_unconstrained(seq, tau_count, protocol_version, window_taus) +
         part_of(seq, unconstrained_list_length(protocol_version), unconstrained_part_length(protocol_version));
}

ReportSlot report_slot(std::uint8_t seq, std::size_t tau_count, std::size_t position, std::uint8_t protocol_version,
                       std::size_t window_taus) {
  if (position == 0) return {Slot::status, 0};
  if (position == 1) return {Slot::faults, 0};
  if (position < fast_frames(tau_count)) {
    const std::size_t k = position - 2;
    return {k % 2 == 0 ? Slot::adev : Slot::mdev, std::uint8_t(static_cast<unsigned>(k / 2))};
  }
  const std::size_t before_window = frames_before_window(seq, tau_count, protocol_version);
  if (position < before_window)
    return slow_slot(slow_part_begin(seq, tau_count) + position - fast_frames(tau_count), tau_count);
  const std::size_t before_model = frames_before_model(seq, tau_count, protocol_version, window_taus);
  if (position < before_model)
    return window_slot(seq % slow_cycle_reports * window_part_length(window_taus, protocol_version) + position -
                       before_window);
  const std::size_t before_unconstrained = frames_before_unconstrained(seq, tau_count, protocol_version, window_taus);
  if (position < before_unconstrained)
    return model_slot(seq % slow_cycle_reports * model_part_length(protocol_version) + position - before_model);
  return {Slot::unconstrained,
          std::uint8_t(static_cast<unsigned>(seq % slow_cycle_reports * unconstrained_part_length(protocol_version) +
                                             position - before_unconstrained))};
}

double worst_case_bus_load(std::size_t tau_count, double report_period_s, double bitrate_bps, std::size_t window_taus) {
  std::size_t frames = 0;
  for (std::uint8_t seq = 0; seq < slow_cycle_reports; ++seq)
    frames = std::max(frames, report_frame_count(seq, tau_count, version, window_taus));
  return static_cast<double>(frames) * worst_case_frame_bits(report_frame_len) / report_period_s / bitrate_bps;
}

}  // namespace gyrochar::protocol
