// libFuzzer target: the data file reader on any bytes (plain or gzip), from an in-memory file.
// Every value it returns is finite, on a line that exists, in a column that exists; anything else
// is a DataFileError whose message holds printable ASCII only (input bytes are never echoed raw).
#include <sys/mman.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "datafile.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const unsigned column = data[0] % 4u;  // 0: the reader chooses
  const int fd = memfd_create("datafile", 0);
  if (fd < 0 || write(fd, data + 1, size - 1) != static_cast<ssize_t>(size - 1)) std::abort();
  try {
    gyrochar::DataFile file("/proc/self/fd/" + std::to_string(fd), column);
    double values[7];
    std::uint64_t last_line = 0;
    while (const std::size_t n = file.read(values)) {
      for (std::size_t i = 0; i < n; ++i) {
        if (!std::isfinite(values[i]) || file.line_of(i) <= last_line || file.column() == 0) std::abort();
        last_line = file.line_of(i);
      }
    }
  } catch (const gyrochar::DataFileError& e) {
    for (const char* p = e.what(); *p; ++p)
      if (*p < 0x20 || *p == 0x7f) std::abort();
  }
  close(fd);
  return 0;
}
