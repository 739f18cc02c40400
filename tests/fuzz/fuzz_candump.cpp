// libFuzzer target: candump log lines. Any input must parse or be rejected with a reason; an accepted
// line must survive format -> parse with the same frame.
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "candump.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  gyrochar::CandumpLine line;
  std::string why;
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  if (!gyrochar::parse_candump_line(text, line, why)) {
    if (why.empty()) std::abort();
    return 0;
  }
  if (line.remote) return 0;
  gyrochar::CandumpLine again;
  const std::string formatted = gyrochar::format_candump_line(line.time_s, line.interface, line.frame);
  if (!gyrochar::parse_candump_line(formatted, again, why)) std::abort();
  if (again.frame.id != line.frame.id || again.frame.len != line.frame.len || again.frame.data != line.frame.data)
    std::abort();
  return 0;
}
