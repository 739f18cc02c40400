#include "checkpoint.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>

namespace gyrochar::firmware {

CheckpointFile::CheckpointFile(std::string path) : path_(std::move(path)), tmp_(path_ + ".tmp"), bad_(path_ + ".bad") {
  const auto slash = path_.rfind('/');
  dir_ = slash == std::string::npos ? "." : slash == 0 ? "/" : path_.substr(0, slash);
}

int CheckpointFile::write(std::span<const std::byte> data) const {
  const int fd = open(tmp_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) return errno;
  std::size_t done = 0;
  while (done < data.size()) {
    const ssize_t n = ::write(fd, data.data() + done, data.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int e = n < 0 ? errno : EIO;
      close(fd);
      return e;
    }
    done += static_cast<std::size_t>(n);
  }
  if (fsync(fd) != 0) {
    const int e = errno;
    close(fd);
    return e;
  }
  if (close(fd) != 0) return errno;
  if (std::rename(tmp_.c_str(), path_.c_str()) != 0) return errno;
  const int dir = open(dir_.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);  // make the rename durable
  if (dir < 0) return errno;
  const int r = fsync(dir) == 0 ? 0 : errno;
  close(dir);
  return r;
}

long CheckpointFile::read(std::span<std::byte> buffer) const {
  const int fd = open(path_.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return -errno;
  std::size_t done = 0;
  for (;;) {
    if (done == buffer.size()) {  // full: is there more?
      std::byte probe;
      const ssize_t n = ::read(fd, &probe, 1);
      close(fd);
      return n == 0 ? static_cast<long>(done) : -EFBIG;
    }
    const ssize_t n = ::read(fd, buffer.data() + done, buffer.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      const int e = errno;
      close(fd);
      return -e;
    }
    if (n == 0) break;
    done += static_cast<std::size_t>(n);
  }
  close(fd);
  return static_cast<long>(done);
}

int CheckpointFile::set_aside() const { return std::rename(path_.c_str(), bad_.c_str()) == 0 ? 0 : errno; }

}  // namespace gyrochar::firmware
