// libFuzzer target: data-file lines. Every line is a value, blank, a missing column or not a number;
// a value is always finite.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "datafile.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const unsigned column = 1u + data[0] % 4u;
  const std::string_view line(reinterpret_cast<const char*>(data + 1), size - 1);
  double value = 0;
  unsigned fields = 0;
  if (gyrochar::parse_data_line(line, column, value, fields) == gyrochar::LineKind::value && !std::isfinite(value))
    std::abort();
  return 0;
}
