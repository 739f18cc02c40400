// libFuzzer target: gyrochard's configuration file. Any content must give a configuration that
// passes validate(), or an error naming a key; never a crash or an exception escaping.
#include <sys/mman.h>
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <string>

#include "config.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const int fd = memfd_create("gyrochard.conf", 0);
  if (fd < 0 || ftruncate(fd, 0) != 0 || pwrite(fd, data, size, 0) != static_cast<ssize_t>(size)) std::abort();
  const std::string path = "/proc/self/fd/" + std::to_string(fd);
  const char* argv[] = {"gyrochard", "--config", path.c_str()};
  const auto result = gyrochar::firmware::parse_config(3, argv);
  if (result.config && gyrochar::firmware::validate(*result.config)) std::abort();
  if (!result.config && !result.exit_now && (!result.error || result.error->why.empty())) std::abort();
  return 0;
}
