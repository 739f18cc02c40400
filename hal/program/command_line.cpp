#include "hal/program/command_line.hpp"

#include <string>

#include "hal/program/exit_codes.hpp"

namespace gyrochar {

std::optional<int> parse_command_line(CLI::App& app, int argc, const char* const* argv, std::string_view program) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {  // --help
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    print_error(program, "options", std::string(e.what()) + " (see --help)");
    return exit_code::bad_input;
  }
  return std::nullopt;
}

}  // namespace gyrochar
