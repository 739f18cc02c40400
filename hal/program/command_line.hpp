#pragma once
// The command line of every gyrochar program (CLI11): one parse with one answer to --help and one
// to a bad option, so that every program says them the same way (exit_codes.hpp's contract).
#include <optional>
#include <string_view>

#include <CLI/CLI.hpp>

namespace gyrochar {

/// Parses argv with `app`. --help: prints the help on stdout and returns exit_code::ok. A bad
/// option or argument: prints "program: options: why (see --help)" on stderr and returns
/// exit_code::bad_input. std::nullopt: parsed, the program goes on. The caller returns
/// finish(program, code) with a code it gets. O(argc).
std::optional<int> parse_command_line(CLI::App& app, int argc, const char* const* argv, std::string_view program);

}  // namespace gyrochar
