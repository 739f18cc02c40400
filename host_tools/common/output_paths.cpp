#include "output_paths.hpp"

#include <sys/stat.h>
#include <unistd.h>

namespace gyrochar {

namespace {

// A file's identity: device and inode of the file, or, for a name not created yet, of its
// directory plus the name in it (`name` empty for an existing file).
struct Identity {
  dev_t device = 0;
  ino_t inode = 0;
  std::string name;
  bool operator==(const Identity&) const = default;
};

std::optional<Identity> regular_file(const struct stat& s) {
  if (!S_ISREG(s.st_mode)) return std::nullopt;
  return Identity{s.st_dev, s.st_ino, {}};
}

// nullopt: not compared (not a regular file, or not reachable: opening it will say why).
std::optional<Identity> identity(const std::string& path, bool is_input) {
  struct stat s {};
  if (path.empty()) return std::nullopt;
  if (path == "-") return is_input && ::fstat(STDIN_FILENO, &s) == 0 ? regular_file(s) : std::nullopt;
  if (::stat(path.c_str(), &s) == 0) return regular_file(s);
  if (is_input || path.back() == '/' || ::lstat(path.c_str(), &s) == 0) return std::nullopt;  // lstat: a dangling link
  const std::size_t slash = path.rfind('/');
  const std::string directory = slash == std::string::npos ? "." : slash == 0 ? "/" : path.substr(0, slash);
  if (::stat(directory.c_str(), &s) != 0 || !S_ISDIR(s.st_mode)) return std::nullopt;
  return Identity{s.st_dev, s.st_ino, path.substr(slash == std::string::npos ? 0 : slash + 1)};
}

std::string spelled(const NamedPath& p) {
  return p.path == "-" ? p.option + " (standard input)" : p.option + " '" + p.path + "'";
}

}  // namespace

std::optional<PathConflict> output_conflict(const std::vector<NamedPath>& inputs, const std::vector<NamedPath>& outputs) {
  std::vector<std::pair<const NamedPath*, Identity>> in, out;
  for (const NamedPath& p : inputs)
    if (const auto id = identity(p.path, true)) in.emplace_back(&p, *id);
  for (const NamedPath& p : outputs) {
    const auto id = identity(p.path, false);
    if (!id) continue;
    for (const auto& [input, input_id] : in)
      if (*id == input_id)
        return PathConflict{p.option, "'" + p.path + "' is the same file as the input " + spelled(*input) +
                                          ": refused before writing anything (the input would be lost)"};
    for (const auto& [earlier, earlier_id] : out)
      if (*id == earlier_id)
        return PathConflict{p.option, "'" + p.path + "' is the same file as the output " + spelled(*earlier) +
                                          ": refused before writing anything (one would overwrite the other)"};
    out.emplace_back(&p, *id);
  }
  return std::nullopt;
}

std::vector<NamedPath> plot_outputs(const std::string& option, const std::string& prefix) {
  if (prefix.empty()) return {};
  return {{option, prefix + ".svg"},
          {option, prefix + ".png"},
          {option, prefix + ".svg.part"},
          {option, prefix + ".png.part"}};
}

}  // namespace gyrochar
