// Written paths: every file a run will write, checked at load time against
// every other written file, every file the scene reads and the filesystem,
// so that no run ever overwrites its own input or one output with another.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "pdyn/host/scene.hpp"

namespace pdyn {

/// One file the scene names: the key that names it ("output.path",
/// "particles[0].file", "the scene file"), where that key is
/// ("FILE:LINE:COLUMN" or "--set ..."), and the path as the run will open it.
struct NamedPath {
  std::string key;
  std::string location;
  std::filesystem::path path;
  /// In the folder of an earlier entry by construction (the implicit
  /// checkpoint beside output.path): its folder is not checked twice.
  bool same_folder_as_earlier = false;
};

/// Every problem with the files in `written`: two of them the same file
/// (by path after resolving `.`, `..` and symbolic links, or as the same
/// inode), one of them an input in `read` (the scene file, its side files),
/// a folder, or a path whose parent cannot be a folder (an existing file on
/// the way). One Diagnostic per problem, at the later key, naming both.
std::vector<Diagnostic> check_written_paths(const std::vector<NamedPath>& written,
                                            const std::vector<NamedPath>& read);

}  // namespace pdyn
