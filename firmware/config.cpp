#include "config.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <CLI/CLI.hpp>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>

#include "hal/program/exit_codes.hpp"
#include "hal/linux/can_interface.hpp"

namespace gyrochar::firmware {

namespace {

// The options, bound to `c` (`node` is range-checked after parsing). Built once for the command
// line, once per line of the configuration file (to check its value alone) and once for both.
std::unique_ptr<CLI::App> make_app(Config& c, unsigned& node, std::string& config_path) {
  auto app = std::make_unique<CLI::App>(
      "gyrochard: live Allan-variance characterization of a gyro, broadcast over CAN.\n"
      "Every option may also be given as 'key = value' in the --config file; the\n"
      "command line overrides the file.",
      "gyrochard");
  app->footer(
      "Configuration file: one 'key = value' per line, keys as the long options without '--'\n"
      "(tau0 = 0.01); '#' starts a comment. A line without '=', an unknown or repeated key and a\n"
      "bad value are errors naming the file and line. The file may hold at most " +
      std::to_string(max_config_bytes) + " bytes, a line at\n" + "most " + std::to_string(max_config_line) +
      " bytes. The whole configuration, and the checkpoint's directory, are checked before any\n"
      "hardware is opened; control bytes in values are shown as \\xNN in messages.\n\n"
      "Examples:\n"
      "  gyrochard --config /etc/gyrochar/gyrochard.conf\n"
      "  gyrochard --source quadrature --gpio-chip gpiochip0 --line-a 3 --line-b 4 --can-interface can0\n"
      "  gyrochard --source can-counter --can-interface vcan0 --node 7 --tau0 0.01\n\n"
      "Success (0) is a clean stop on SIGTERM or SIGINT with every checkpoint written; 4 when a\n"
      "checkpoint could not be written during the run (the error is logged each time).\n" +
      std::string(exit_code::help));
  app->add_option("--config", config_path, "configuration file (key = value lines)");
  app->set_version_flag("--version", "gyrochard 0.1.0");
  static const std::map<std::string, SourceKind> sources{{"quadrature", SourceKind::quadrature},
                                                         {"strobe", SourceKind::strobe},
                                                         {"can-counter", SourceKind::can_counter}};
  app->add_option("--node", node, "node address, 0..253 (low byte of the CAN identifiers)")->capture_default_str();
  app->add_option("--can-interface", c.can_interface, "SocketCAN interface for reports")->capture_default_str();
  app->add_option("--source", c.source, "count source: quadrature, strobe, can-counter")
      ->transform(CLI::CheckedTransformer(sources, CLI::ignore_case));
  app->add_option("--gpio-chip", c.gpio_chip, "GPIO chip (quadrature, strobe)")->capture_default_str();
  app->add_option("--line-a", c.line_a, "quadrature channel A line offset")->capture_default_str();
  app->add_option("--line-b", c.line_b, "quadrature channel B line offset")->capture_default_str();
  app->add_option("--strobe-line", c.strobe_line, "sample strobe line offset")->capture_default_str();
  app->add_option("--counter-path", c.counter_path, "hardware counter count attribute (strobe source)");
  app->add_option("--counter-node", c.counter_node, "address of the gyro electronics sending CounterInput frames")
      ->capture_default_str();
  app->add_option("--tau0", c.tau0_s, "sample interval in seconds")->capture_default_str();
  app->add_option("--pulse-weight", c.pulse_weight_arcsec, "angle per pulse in arcsec")->capture_default_str();
  app->add_option("--stride-factor", c.stride_factor, "stride factor S, power of two 2..64")->capture_default_str();
  app->add_option("--octaves", c.octaves, "number of octave taus, 1..40")->capture_default_str();
  app->add_option("--report-period", c.report_period_s, "seconds between reports, 0.1..2 (the protocol's range)")
      ->capture_default_str();
  app->add_option("--window", c.window_s, "dynamic Allan deviation: seconds per window, restarted every window (0: none)")
      ->capture_default_str();
  app->add_option("--checkpoint", c.checkpoint_path, "checkpoint file (empty: none)");
  app->add_option("--checkpoint-period", c.checkpoint_period_s, "seconds between checkpoints")->capture_default_str();
  app->add_flag("--verbose", c.verbose, "log every report");
  return app;
}

// CLI11 parses in reverse order.
void parse_args(CLI::App& app, std::vector<std::string> args) {
  std::reverse(args.begin(), args.end());
  app.parse(args);
}

// One `key = value` line of the configuration file.
struct FileEntry {
  std::string key, value, where;
};

std::string_view trim(std::string_view s) {
  const auto first = s.find_first_not_of(" \t\r");
  if (first == std::string_view::npos) return {};
  return s.substr(first, s.find_last_not_of(" \t\r") - first + 1);
}

// The whole file, read up to max_config_bytes + 1 bytes (so /dev/zero or a huge file costs no more).
std::optional<ConfigError> read_bounded(const std::string& path, std::string& text) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return ConfigError{"config", path + ": " + std::strerror(errno)};
  text.resize(max_config_bytes + 1);
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  if (in.bad()) return ConfigError{"config", path + ": " + std::strerror(errno)};
  text.resize(static_cast<std::size_t>(in.gcount()));
  if (text.size() > max_config_bytes)
    return ConfigError{"config", path + ": larger than " + std::to_string(max_config_bytes) +
                                     " bytes (the limit for a configuration file)"};
  return std::nullopt;
}

// The entries of `path`, each key checked against the options and its value parsed alone.
std::optional<ConfigError> read_file(const std::string& path, std::vector<FileEntry>& entries) {
  std::string whole;
  if (auto problem = read_bounded(path, whole)) return problem;
  std::map<std::string, unsigned> first_line;
  std::size_t next = 0;
  for (unsigned number = 1; next < whole.size(); ++number) {
    const std::size_t newline = std::min(whole.find('\n', next), whole.size());
    const std::string text = whole.substr(next, newline - next);
    next = newline + 1;
    const std::string where = path + ":" + std::to_string(number);
    if (text.size() > max_config_line)
      return ConfigError{"config", "line longer than " + std::to_string(max_config_line) + " bytes (the limit)", where};
    // '#' starts a comment, outside double quotes.
    bool quoted = false;
    std::size_t end = 0;
    for (; end < text.size() && (quoted || text[end] != '#'); ++end)
      if (text[end] == '"') quoted = !quoted;
    const std::string_view line = trim(std::string_view(text).substr(0, end));
    if (line.empty()) continue;
    const std::size_t equals = line.find('=');
    if (equals == std::string_view::npos) return ConfigError{std::string(line), "not a 'key = value' line", where};
    const std::string key(trim(line.substr(0, equals)));
    std::string value(trim(line.substr(equals + 1)));
    if (value.size() >= 2 && value.front() == '"' && value.back() == '"') value = value.substr(1, value.size() - 2);
    if (key.empty()) return ConfigError{std::string(line), "no key before '='", where};
    Config scratch;
    unsigned node = 0;
    std::string nested;
    auto app = make_app(scratch, node, nested);
    if (key == "config" || key == "help" || key == "version" || app->get_option_no_throw("--" + key) == nullptr)
      return ConfigError{key, "unknown key (gyrochard --help lists them)", where};
    if (const auto [it, fresh] = first_line.emplace(key, number); !fresh)
      return ConfigError{key, "given twice (first at line " + std::to_string(it->second) + ")", where};
    try {
      parse_args(*app, {"--" + key + "=" + value});
    } catch (const CLI::ParseError& e) {
      std::string why = e.what();
      if (why.rfind("--" + key + ": ", 0) == 0) why.erase(0, key.size() + 4);
      return ConfigError{key, "'" + value + "' is not valid: " + why, where};
    }
    entries.push_back({key, value, where});
  }
  return std::nullopt;
}

}  // namespace

ParseResult parse_config(int argc, const char* const* argv) {
  ParseResult result;
  std::vector<std::string> args(argv + 1, argv + argc);
  Config c;
  unsigned node = c.node;
  std::string config_path;
  auto app = make_app(c, node, config_path);
  try {
    parse_args(*app, args);
  } catch (const CLI::CallForHelp& e) {
    app->exit(e);
    result.exit_now = true;
    return result;
  } catch (const CLI::CallForVersion& e) {
    app->exit(e);
    result.exit_now = true;
    return result;
  } catch (const CLI::ParseError& e) {
    result.error = ConfigError{"command line", e.what()};
    return result;
  }

  // The file's values, under the command line's.
  std::map<std::string, std::string> origin;  // key -> FILE:LINE of the value in force
  if (!config_path.empty()) {
    std::vector<FileEntry> entries;
    if (auto problem = read_file(config_path, entries)) {
      result.error = problem;
      return result;
    }
    for (const FileEntry& e : entries) {
      if (app->get_option("--" + e.key)->count() > 0) continue;
      args.push_back("--" + e.key + "=" + e.value);
      origin[e.key] = e.where;
    }
    c = Config{};
    node = c.node;
    app = make_app(c, node, config_path);
    try {
      parse_args(*app, args);
    } catch (const CLI::ParseError& e) {  // each line parsed alone above: not expected
      result.error = ConfigError{"configuration", e.what()};
      return result;
    }
  }
  std::optional<ConfigError> problem;
  if (node > 253) problem = ConfigError{"node", "must be 0..253, got " + std::to_string(node)};
  c.node = static_cast<std::uint8_t>(node);
  if (!problem) problem = validate(c);
  if (problem) {
    if (const auto it = origin.find(problem->key); it != origin.end()) problem->where = it->second;
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
  // The protocol's ReportPeriod field: 100..2000 ms (docs/protocol.md, section 2.3).
  if (!(c.report_period_s >= 0.1 && c.report_period_s <= 2.0))
    return ConfigError{"report-period", "must be 0.1..2 s (the protocol's range)"};
  if (c.report_period_s < c.tau0_s) return ConfigError{"report-period", "must be at least tau0"};
  if (!std::isfinite(c.window_s) || c.window_s < 0 ||
      (c.window_s > 0 &&
       (c.window_s < 4 * c.report_period_s || c.window_s < 4 * c.tau0_s || c.window_s / c.tau0_s >= 0x1p40)))
    return ConfigError{"window", "must be 0 (none) or at least 4 report periods and 4 tau0, below 2^40 tau0"};
  if (!c.checkpoint_path.empty() && !positive(c.checkpoint_period_s))
    return ConfigError{"checkpoint-period", "must be positive"};
  if (const std::string why = interface_name_problem(c.can_interface); !why.empty())
    return ConfigError{"can-interface", why};
  if (c.source == SourceKind::quadrature && c.line_a == c.line_b) return ConfigError{"line-b", "must differ from line-a"};
  if (c.source == SourceKind::strobe && c.counter_path.empty())
    return ConfigError{"counter-path", "is required by the strobe source"};
  if (c.counter_node > 253) return ConfigError{"counter-node", "must be an address 0..253"};
  return std::nullopt;
}

std::optional<ConfigError> check_files(const Config& c) {
  if (c.checkpoint_path.empty()) return std::nullopt;
  std::string dir = std::filesystem::path(c.checkpoint_path).parent_path().string();
  if (dir.empty()) dir = ".";
  struct stat st {};
  if (::stat(dir.c_str(), &st) != 0) return ConfigError{"checkpoint", dir + ": " + std::strerror(errno)};
  if (!S_ISDIR(st.st_mode)) return ConfigError{"checkpoint", dir + ": not a directory"};
  // The checkpoint is replaced by a temporary file renamed over it: the directory must be writable.
  if (::access(dir.c_str(), W_OK | X_OK) != 0)
    return ConfigError{"checkpoint", dir + ": directory not writable: " + std::strerror(errno)};
  if (::stat(c.checkpoint_path.c_str(), &st) == 0) {
    if (!S_ISREG(st.st_mode)) return ConfigError{"checkpoint", c.checkpoint_path + ": not a regular file"};
    if (::access(c.checkpoint_path.c_str(), R_OK) != 0)
      return ConfigError{"checkpoint", c.checkpoint_path + ": " + std::strerror(errno)};
  }
  return std::nullopt;
}

}  // namespace gyrochar::firmware
