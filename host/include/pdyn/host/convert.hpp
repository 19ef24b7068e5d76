// LAMMPS input scripts as pdyn scenes (`pdyn convert`, issue 44 item 6).
#pragma once

#include <filesystem>
#include <string>

#include "pdyn/host/export.hpp"
#include "pdyn/host/scene.hpp"

namespace pdyn {

/// The scene equivalent to the LAMMPS input script `text` (read from `file`,
/// which names it in messages; the data files it reads are named relative
/// to the script, as LAMMPS reads them), as commented YAML. Converts what
/// a simple input uses (docs/lammps.md lists the commands); anything else
/// throws SceneError with one diagnostic per problem, located
/// "FILE:LINE:COLUMN" at the word, "what (supported: ...)".
PDYN_HOST_API std::string convert_lammps_input(const std::string& text, const std::string& file);

}  // namespace pdyn
