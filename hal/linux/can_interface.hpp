#pragma once
// SocketCAN interface names given on a command line: a name Linux can never give an interface is
// bad input (exit 2), told apart from an interface that does not exist now (no hardware, exit 3).
#include <string>
#include <string_view>

namespace gyrochar {

/// The longest interface name Linux allows: IFNAMSIZ - 1 (linux/if.h).
inline constexpr std::size_t max_interface_name = 15;

/// Empty when `name` could name a network interface; otherwise why it never can: empty, longer
/// than max_interface_name characters, "." or "..", or holding '/', ':', whitespace or a control
/// character (the kernel's dev_valid_name, and what a terminal could not show). O(length).
std::string interface_name_problem(std::string_view name);

}  // namespace gyrochar
