#pragma once
// Checkpoint files that a crash cannot tear: the new state goes to <path>.tmp, is fsynced, then
// renamed over <path> and the directory fsynced, so at any instant <path> holds the previous or
// the new checkpoint, complete. A file that fails its checks is kept aside as <path>.bad.
// Writing and reading allocate nothing (the paths are built once).
#include <cstddef>
#include <span>
#include <string>

namespace gyrochar::firmware {

class CheckpointFile {
 public:
  explicit CheckpointFile(std::string path);
  const std::string& path() const { return path_; }
  /// Writes `data` atomically. Returns 0 or the errno of the step that failed.
  int write(std::span<const std::byte> data) const;
  /// Reads the file into `buffer`; returns the bytes read, or -errno (-ENOENT: no checkpoint,
  /// -EFBIG: larger than the buffer).
  long read(std::span<std::byte> buffer) const;
  /// Renames the file to <path>.bad (a newer bad file replaces an older one). Returns 0 or errno.
  int set_aside() const;
  const std::string& aside_path() const { return bad_; }

 private:
  std::string path_, tmp_, bad_, dir_;
};

}  // namespace gyrochar::firmware
