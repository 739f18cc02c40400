#include "hal/program/exit_codes.hpp"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <string>

namespace gyrochar {

void print_error(std::string_view program, std::string_view what, std::string_view why) {
  char line[1024];
  std::size_t n = 0;
  const auto append = [&](std::string_view text) {
    const std::size_t k = std::min(text.size(), sizeof line - 1 - n);
    std::memcpy(line + n, text.data(), k);
    n += k;
  };
  append(program);
  append(": ");
  append(what);
  if (!why.empty()) {
    append(": ");
    append(why);
  }
  line[n++] = '\n';
  std::fflush(stderr);  // whatever the program printed before stays before
  for (std::size_t done = 0; done < n;) {
    const ssize_t w = ::write(STDERR_FILENO, line + done, n - done);
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) return;  // stderr is gone: nothing else can be told
    done += static_cast<std::size_t>(w);
  }
}

std::string printable(std::string_view text) {
  static constexpr char hex[] = "0123456789abcdef";
  std::string out;
  out.reserve(text.size());
  for (const char ch : text) {
    const auto c = static_cast<unsigned char>(ch);
    if (c >= 0x20 && c < 0x7f) {
      out += ch;
    } else {
      out += "\\x";
      out += hex[c >> 4];
      out += hex[c & 15];
    }
  }
  return out;
}

void exit_with(int code, std::string_view program, std::string_view what, std::string_view why) {
  print_error(program, what, why);
  std::exit(code);
}

bool close_output(std::FILE* file, std::string_view program, std::string_view name) {
  if (file == nullptr) return true;
  const bool failed_before = std::ferror(file) != 0;
  errno = 0;
  const bool flushed = std::fflush(file) == 0;
  int error = errno;
  const bool closed = std::fclose(file) == 0;
  if (error == 0) error = errno;
  if (flushed && closed && !failed_before) return true;
  print_error(program, name,
              std::string("write failed: ") + (error != 0 ? std::strerror(error) : "an earlier write was refused"));
  return false;
}

int finish(std::string_view program, int code) {
  if (!close_output(stdout, program, "standard output") && code == exit_code::ok) return exit_code::output_failed;
  return code;
}

}  // namespace gyrochar
