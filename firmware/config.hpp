#pragma once
// gyrochard's configuration: a file (INI/TOML key = value, CLI11's format) plus command-line
// overrides. Every key is also a long option (--tau0 0.001). Invalid values are reported with the
// key's name; nothing is started.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace gyrochar::firmware {

enum class SourceKind { quadrature, strobe, can_counter };

struct Config {
  // CAN output
  std::uint8_t node = 0x01;             // node address: low byte of every 29-bit identifier
  std::string can_interface = "can0";   // SocketCAN interface
  // Count source
  SourceKind source = SourceKind::quadrature;
  std::string gpio_chip = "gpiochip0";  // quadrature and strobe sources
  unsigned line_a = 0, line_b = 1;      // quadrature A/B line offsets
  unsigned strobe_line = 0;             // strobe source: sample boundary line
  std::string counter_path;             // strobe source: hardware counter (sysfs count attribute)
  unsigned counter_node = 0x80;         // can_counter source: address of the gyro electronics
                                        // (their CounterInput frames are 0x0CFF50xx, docs/protocol.md)
  // Estimation
  double tau0_s = 0.001;                // sample interval
  double pulse_weight_arcsec = 1.0;     // angle per pulse
  std::uint32_t stride_factor = 8;      // S: power of two, 2..64
  unsigned octaves = 32;                // taus m = 1, 2, 4, ..., 2^(octaves-1)
  double report_period_s = 1.0;         // one report per period, frames paced over it
  double window_s = 0.0;                // dynamic Allan deviation: window length (0: none), at least
                                        // 4 report periods and 4 tau0 (window.hpp)
  std::string checkpoint_path;          // empty: no checkpoint
  double checkpoint_period_s = 60.0;
  bool verbose = false;
};

/// A configuration problem: which key and why (shown as "gyrochard: <key>: <why>").
struct ConfigError {
  std::string key;
  std::string why;
};

/// Outcome of parsing: a configuration, a request to exit with a message already printed
/// (--help, --version: exit code 0), or an error.
struct ParseResult {
  std::optional<Config> config;
  std::optional<ConfigError> error;
  bool exit_now = false;
};

/// Parses argv (and the file named by --config, if any). Never throws; prints help on request.
ParseResult parse_config(int argc, const char* const* argv);

/// Checks ranges and combinations; returns the first problem found.
std::optional<ConfigError> validate(const Config& config);

}  // namespace gyrochar::firmware
