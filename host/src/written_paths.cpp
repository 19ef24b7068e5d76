// Written paths (written_paths.hpp). Outputs are opened relative to the
// working folder and side files relative to the scene's folder, so both are
// made absolute before they are compared; weakly_canonical resolves the part
// of a path that exists (symbolic links, `..`) and keeps the rest as written,
// and fs::equivalent catches hard links between existing files.
#include "written_paths.hpp"

#include <fmt/format.h>

#include <optional>

namespace pdyn {

namespace fs = std::filesystem;

namespace {

fs::path resolved(const fs::path& p) {
  std::error_code ec;
  fs::path abs = fs::absolute(p, ec);
  if (ec) return p.lexically_normal();
  fs::path canon = fs::weakly_canonical(abs, ec);
  return ec ? abs.lexically_normal() : canon;
}

bool same_file(const fs::path& a, const fs::path& b) {
  if (resolved(a) == resolved(b)) return true;
  std::error_code ec;
  return fs::exists(a, ec) && fs::exists(b, ec) && fs::equivalent(a, b, ec) && !ec;
}

// The first existing ancestor of `p` that is not a folder, if any: a file on
// the way makes the path impossible to create.
std::optional<fs::path> blocking_file(const fs::path& p) {
  std::error_code ec;
  for (fs::path dir = fs::absolute(p, ec).parent_path(); !dir.empty(); dir = dir.parent_path()) {
    const auto st = fs::status(dir, ec);
    if (fs::exists(st)) {
      if (fs::is_directory(st)) return std::nullopt;
      return dir;
    }
    if (dir == dir.root_path()) break;
  }
  return std::nullopt;
}

}  // namespace

std::vector<Diagnostic> check_written_paths(const std::vector<NamedPath>& written,
                                            const std::vector<NamedPath>& read) {
  std::vector<Diagnostic> out;
  for (std::size_t i = 0; i < written.size(); ++i) {
    const NamedPath& w = written[i];
    if (auto file = w.same_folder_as_earlier ? std::nullopt : blocking_file(w.path)) {
      out.push_back(
          {w.location, fmt::format("{}: cannot create '{}': '{}' is a file, not a folder (expected "
                                   "a path whose folders exist or can be created)",
                                   w.key, w.path.string(), file->string())});
      continue;
    }
    bool clash = false;
    for (const NamedPath& r : read) {
      if (!same_file(w.path, r.path)) continue;
      const std::string what =
          r.location.empty() ? r.key : fmt::format("{} (at {})", r.key, r.location);
      out.push_back(
          {w.location, fmt::format("{}: '{}' is {}, which the run reads (expected an output file "
                                   "that is not an input)",
                                   w.key, w.path.string(), what)});
      clash = true;
      break;
    }
    if (clash) continue;
    for (std::size_t j = 0; j < i; ++j) {
      if (!same_file(w.path, written[j].path)) continue;
      out.push_back(
          {w.location, fmt::format("{}: '{}' is the same file as {} (at {}) (expected a different "
                                   "file for each output)",
                                   w.key, w.path.string(), written[j].key, written[j].location)});
      break;
    }
  }
  return out;
}

}  // namespace pdyn
