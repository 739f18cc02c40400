#pragma once
// Outputs that would destroy an input, or each other: checked by every host program after its
// options are parsed and before it opens anything for writing (opening truncates).
#include <optional>
#include <string>
#include <vector>

namespace gyrochar {

/// A file a program reads or writes, as the user named it: `option` is how ("LOG", "--csv",
/// "--plot PREFIX"), `path` the file. The input "-" is standard input (its file, when it is one);
/// the output "-" (standard output) and empty paths are not checked.
struct NamedPath {
  std::string option;
  std::string path;
};

/// What `output_conflict` found: `what` names the output option, `why` the path and the other
/// option it collides with (for "program: what: why").
struct PathConflict {
  std::string what;
  std::string why;
};

/// The first output that is the same file as an input, or as an earlier output; nullopt when
/// there is none. "The same file" is the same device and inode, so symbolic links, hard links and
/// different spellings of one path are all caught; an output that does not exist yet is the same
/// file as another when both are the same name in the same directory (device and inode of the
/// directory). Only regular files and names not yet created are compared: writing two outputs to
/// /dev/null, or reading and writing one terminal, is fine. Inputs that cannot be examined are
/// skipped (opening them reports why). O(inputs x outputs + outputs^2) stat calls; opens nothing.
std::optional<PathConflict> output_conflict(const std::vector<NamedPath>& inputs, const std::vector<NamedPath>& outputs);

/// The files `--plot PREFIX` writes: PREFIX.svg, PREFIX.png and their temporary PREFIX.svg.part and
/// PREFIX.png.part (write_figure), each named by `option` ("--plot"); none when PREFIX is empty.
std::vector<NamedPath> plot_outputs(const std::string& option, const std::string& prefix);

}  // namespace gyrochar
