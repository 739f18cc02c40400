#include "hal/linux/can_interface.hpp"

namespace gyrochar {

std::string interface_name_problem(std::string_view name) {
  if (name.empty()) return "an interface name cannot be empty";
  if (name.size() > max_interface_name)
    return "an interface name has at most " + std::to_string(max_interface_name) + " characters, this one " +
           std::to_string(name.size());
  if (name == "." || name == "..") return "'.' and '..' are not interface names";
  for (const char c : name) {
    const auto u = static_cast<unsigned char>(c);
    if (c == '/' || c == ':' || u <= ' ' || u == 0x7F)
      return "an interface name cannot hold '/', ':', spaces or control characters";
  }
  return {};
}

}  // namespace gyrochar
