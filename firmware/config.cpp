#include "config.hpp"

#include <CLI/CLI.hpp>

#include <bit>
#include <cmath>
#include <map>

namespace gyrochar::firmware {

ParseResult parse_config(int argc, const char* const* argv) {
  Config c;
  CLI::App app{"gyrochard: live Allan-variance characterization of a gyro, broadcast over CAN.\n"
               "Every option may also be given as 'key = value' in the --config file; the\n"
               "command line overrides the file.",
               "gyrochard"};
  app.footer(
      "Examples:\n"
      "  gyrochard --config /etc/gyrochar/gyrochard.conf\n"
      "  gyrochard --source quadrature --gpio-chip gpiochip0 --line-a 3 --line-b 4 --can-interface can0\n"
      "  gyrochard --source can-counter --can-interface vcan0 --node 7 --tau0 0.01\n"
      "Exit codes: 0 clean stop (SIGTERM/SIGINT), 2 invalid configuration, 3 hardware not available.");
  app.set_config("--config", "", "configuration file (key = value lines)");
  app.set_version_flag("--version", "gyrochard 0.1.0");
  std::map<std::string, SourceKind> sources{{"quadrature", SourceKind::quadrature},
                                            {"strobe", SourceKind::strobe},
                                            {"can-counter", SourceKind::can_counter}};
  unsigned node = c.node;
  app.add_option("--node", node, "node address, 0..253 (low byte of the CAN identifiers)")->capture_default_str();
  app.add_option("--can-interface", c.can_interface, "SocketCAN interface for reports")->capture_default_str();
  app.add_option("--source", c.source, "count source: quadrature, strobe, can-counter")
      ->transform(CLI::CheckedTransformer(sources, CLI::ignore_case));
  app.add_option("--gpio-chip", c.gpio_chip, "GPIO chip (quadrature, strobe)")->capture_default_str();
  app.add_option("--line-a", c.line_a, "quadrature channel A line offset")->capture_default_str();
  app.add_option("--line-b", c.line_b, "quadrature channel B line offset")->capture_default_str();
  app.add_option("--strobe-line", c.strobe_line, "sample strobe line offset")->capture_default_str();
  app.add_option("--counter-path", c.counter_path, "hardware counter count attribute (strobe source)");
  app.add_option("--counter-node", c.counter_node, "address of the gyro electronics sending CounterInput frames")
      ->capture_default_str();
  app.add_option("--tau0", c.tau0_s, "sample interval in seconds")->capture_default_str();
  app.add_option("--pulse-weight", c.pulse_weight_arcsec, "angle per pulse in arcsec")->capture_default_str();
  app.add_option("--stride-factor", c.stride_factor, "stride factor S, power of two 2..64")->capture_default_str();
  app.add_option("--octaves", c.octaves, "number of octave taus, 1..40")->capture_default_str();
  app.add_option("--report-period", c.report_period_s, "seconds between reports")->capture_default_str();
  app.add_option("--window", c.window_s,
                 "dynamic Allan deviation: seconds per window, restarted every window (0: none)")
      ->capture_default_str();
  app.add_option("--checkpoint", c.checkpoint_path, "checkpoint file (empty: none)");
  app.add_option("--checkpoint-period", c.checkpoint_period_s, "seconds between checkpoints")->capture_default_str();
  app.add_flag("--verbose", c.verbose, "log every report");

  ParseResult result;
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    app.exit(e);
    result.exit_now = true;
    return result;
  } catch (const CLI::CallForVersion& e) {
    app.exit(e);
    result.exit_now = true;
    return result;
  } catch (const CLI::ParseError& e) {
    result.error = ConfigError{"command line", e.what()};
    return result;
  }
  if (node > 253) {
    result.error = ConfigError{"node", "must be 0..253, got " + std::to_string(node)};
    return result;
  }
  c.node = static_cast<std::uint8_t>(node);
  if (auto problem = validate(c)) {
    result.error = problem;
    return result;
  }
  result.config = c;
  return result;
}

std::optional<ConfigError> validate(const Config& c) {
  auto positive = [](double v) { return std::isfinite(v) && v > 0; };
  if (!positive(c.tau0_s)) return ConfigError{"tau0", "must be a positive number of seconds"};
  if (!positive(c.pulse_weight_arcsec)) return ConfigError{"pulse-weight", "must be a positive angle in arcsec"};
  if (c.stride_factor < 2 || c.stride_factor > 64 || !std::has_single_bit(c.stride_factor))
    return ConfigError{"stride-factor", "must be a power of two from 2 to 64"};
  if (c.octaves < 1 || c.octaves > 40) return ConfigError{"octaves", "must be 1..40"};
  if (!positive(c.report_period_s) || c.report_period_s < c.tau0_s)
    return ConfigError{"report-period", "must be at least tau0"};
  if (!std::isfinite(c.window_s) || c.window_s < 0 ||
      (c.window_s > 0 && (c.window_s < 4 * c.report_period_s || c.window_s < 4 * c.tau0_s || c.window_s / c.tau0_s >= 0x1p40)))
    return ConfigError{"window", "must be 0 (none) or at least 4 report periods and 4 tau0, below 2^40 tau0"};
  if (!c.checkpoint_path.empty() && !positive(c.checkpoint_period_s))
    return ConfigError{"checkpoint-period", "must be positive"};
  if (c.can_interface.empty() || c.can_interface.size() > 15)
    return ConfigError{"can-interface", "must be an interface name of 1..15 characters"};
  if (c.source == SourceKind::quadrature && c.line_a == c.line_b)
    return ConfigError{"line-b", "must differ from line-a"};
  if (c.source == SourceKind::strobe && c.counter_path.empty())
    return ConfigError{"counter-path", "is required by the strobe source"};
  if (c.counter_node > 253) return ConfigError{"counter-node", "must be an address 0..253"};
  return std::nullopt;
}

}  // namespace gyrochar::firmware
