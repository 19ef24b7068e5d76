// The project templates of `pdyn new`, embedded at build time from
// cli/templates/ (see cli/CMakeLists.txt). In paths and text, @NAME@ stands
// for the plugin's name and @KIND@ for its kind.
#pragma once

#include <span>
#include <string_view>

namespace pdyn::cli {

struct TemplateFile {
  std::string_view
      path;  ///< relative to cli/templates/: "common/CMakeLists.txt", "force/@NAME@.cpp"
  std::string_view text;
};

/// Every template file, sorted by path.
std::span<const TemplateFile> template_files();

}  // namespace pdyn::cli
