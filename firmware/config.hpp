#pragma once
// gyrochard's configuration: a file of `key = value` lines plus command-line overrides. Every key
// is also a long option (--tau0 0.001). Invalid values are reported with the key's name (and the
// file and line when they came from the file); nothing is started.
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace gyrochar::firmware {

enum class SourceKind { quadrature, strobe, can_counter };

/// Bounds on the configuration file: its size and a line's length, in bytes (--help states them).
inline constexpr std::size_t max_config_bytes = 65536;
inline constexpr std::size_t max_config_line = 4096;

struct Config {
  // CAN output
  std::uint8_t node = 0x01;            // node address: low byte of every 29-bit identifier
  std::string can_interface = "can0";  // SocketCAN interface
  // Count source
  SourceKind source = SourceKind::quadrature;
  std::string gpio_chip = "gpiochip0";  // quadrature and strobe sources
  unsigned line_a = 0, line_b = 1;      // quadrature A/B line offsets
  unsigned strobe_line = 0;             // strobe source: sample boundary line
  std::string counter_path;             // strobe source: hardware counter (sysfs count attribute)
  unsigned counter_node = 0x80;         // can_counter source: address of the gyro electronics
                                        // (their CounterInput frames are 0x0CFF50xx, docs/protocol.md)
  // Estimation
  double tau0_s = 0.001;             // sample interval
  double pulse_weight_arcsec = 1.0;  // angle per pulse
  std::uint32_t stride_factor = 8;   // S: power of two, 2..64
  unsigned octaves = 32;             // taus m = 1, 2, 4, ..., 2^(octaves-1)
  double report_period_s = 1.0;      // one report per period, frames paced over it
  double window_s = 0.0;             // dynamic Allan deviation: window length (0: none), at least
                                     // 4 report periods and 4 tau0 (window.hpp)
  std::string checkpoint_path;       // empty: no checkpoint
  double checkpoint_period_s = 60.0;
  bool verbose = false;
};

/// A configuration problem: where the value came from ("FILE:LINE" for the configuration file,
/// empty for the command line or a default), which key and why; shown as
/// "gyrochard: [FILE:LINE: ]<key>: <why>".
struct ConfigError {
  std::string key;
  std::string why;
  std::string where = {};
};

/// Outcome of parsing: a configuration, a request to exit with a message already printed
/// (--help, --version: exit code 0), or an error.
struct ParseResult {
  std::optional<Config> config;
  std::optional<ConfigError> error;
  bool exit_now = false;
};

/// Parses argv and the file named by --config, if any; the command line overrides the file.
/// The file holds `key = value` lines ('#' starts a comment, blank lines are skipped, a value may
/// be in double quotes); a line without '=', an unknown or repeated key, or a value of the wrong
/// type is an error naming the file and line. Then validate(). Never throws; prints help and
/// version on request. Reads the file once; allocates.
ParseResult parse_config(int argc, const char* const* argv);

/// Checks ranges and combinations (the report period within the protocol's 100 ms .. 2 s);
/// returns the first problem found. Pure: O(1), touches nothing outside `config`.
std::optional<ConfigError> validate(const Config& config);

/// Checks what the configuration needs from the file system, before any hardware is opened:
/// the checkpoint's directory exists and is writable, and an existing checkpoint is a regular
/// file this process can read and replace. Returns the first problem found. A few system calls.
std::optional<ConfigError> check_files(const Config& config);

}  // namespace gyrochar::firmware
