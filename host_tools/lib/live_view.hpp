#pragma once
// What the decoder knows, for people and for files: the refreshing per-node table (deviations in
// deg/h with confidence intervals, noise types, IEEE-952 parameters in gyro units, link health)
// and the CSV / JSON-lines rows written for every closed report. Shared by gyrochar-decode and
// gyrochar-demo. Units: the wire carries arcsec and seconds (1 arcsec/s = 1 deg/h).
#include <cstdint>
#include <cstdio>

#include "decoder.hpp"

namespace gyrochar {

/// Prints every node's table to `out`; `clear` first clears a terminal screen.
void print_view(std::FILE* out, const Decoder& decoder, double t_s, bool clear);

/// CSV header and one row per valid tau of a closed report.
void write_csv_header(std::FILE* out);
void write_csv_rows(std::FILE* out, const NodeView& node, std::uint8_t seq, double t_s);

/// One JSON object per closed report (a line): node, seq, time, health, taus, IEEE-952.
void write_json_line(std::FILE* out, const NodeView& node, std::uint8_t seq, double t_s);

}  // namespace gyrochar
