#pragma once
// The contract every gyrochar program keeps with its caller (gyrochard and the host tools alike):
// data on stdout, each error as one line "program: what: why" on stderr, and an exit code from
// the table below, which every --help prints (exit_codes_help) and the README repeats. It lives
// in hal/program/ (the target gyrochar_program, with command_line.hpp), at the lowest layer that
// knows processes, so that firmware/ and host_tools/ share it without linking the HAL.
#include <cstdio>
#include <string>
#include <string_view>

namespace gyrochar::exit_code {

inline constexpr int ok = 0;
inline constexpr int internal = 1;       // a bug, or memory or another resource exhausted
inline constexpr int bad_input = 2;      // usage, an option, the configuration or the input data
inline constexpr int no_hardware = 3;    // a CAN interface, GPIO chip, counter or timer is unavailable
inline constexpr int output_failed = 4;  // a result could not be written: a file, a plot, stdout

/// The table above as the last lines of every --help (no trailing newline). A static string.
inline constexpr const char* help =
    "Exit codes: 0 success; 1 internal error; 2 bad usage, option, configuration or input;\n"
    "3 hardware (CAN interface, GPIO chip, counter) not available; 4 an output could not be written.\n"
    "Data goes to stdout, errors to stderr as 'program: what: why'.";

}  // namespace gyrochar::exit_code

namespace gyrochar {

/// Prints "program: what: why" (or "program: what" when `why` is empty) and a newline on stderr
/// with one write, so that lines of processes sharing stderr do not interleave. O(length);
/// allocates nothing for lines up to 1 KiB (longer ones are cut there); never fails.
void print_error(std::string_view program, std::string_view what, std::string_view why = {});

/// `text` for a message on a terminal or in a journal: bytes outside printable ASCII (control bytes
/// such as ESC and NUL, and bytes >= 0x7f) as \xNN, as the analyzer shows a data file's bytes.
/// O(length); allocates.
std::string printable(std::string_view text);

/// print_error, then std::exit(code) (stdio buffers are flushed, destructors do not run).
[[noreturn]] void exit_with(int code, std::string_view program, std::string_view what, std::string_view why = {});

/// Closes `file` (stdout too) after checking that every write to it succeeded: an earlier failed
/// write (the stream's error flag), the final flush and the close. On failure prints
/// "program: name: write failed: reason" and returns false. `file` is closed either way; nullptr
/// is fine (true). O(buffered bytes).
bool close_output(std::FILE* file, std::string_view program, std::string_view name);

/// The end of a program: close_output(stdout, program, "standard output"); returns `code`, or
/// exit_code::output_failed when stdout lost data and `code` was ok. Every program returns
/// through it, so `program > /dev/full` never exits 0.
int finish(std::string_view program, int code);

}  // namespace gyrochar
