// LAMMPS input scripts as pdyn scenes (`pdyn convert`, issue 44 item 6).
#pragma once

#include <filesystem>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "pdyn/host/export.hpp"
#include "pdyn/host/scene.hpp"

namespace pdyn {

/// The scene equivalent to the LAMMPS input script `text` (read from `file`,
/// which names it in messages; the data files it reads are named as the
/// script names them, for a scene in lmp's working directory:
/// ConvertOptions::data_folder says otherwise), as commented YAML. Converts what
/// a simple input uses (docs/lammps.md lists the commands); anything else
/// throws SceneError with one diagnostic per problem, located
/// "FILE:LINE:COLUMN" at the word, "what (supported: ...)".
/// When the script makes its atoms itself (lattice, create_atoms), this
/// throws SceneError: they go to a data file, which convert_lammps_script
/// writes.
PDYN_HOST_API std::string convert_lammps_input(const std::string& text, const std::string& file);

/// A converted scene and the files it reads that the conversion made.
struct PDYN_HOST_API ConvertedScene {
  std::string scene;  ///< commented YAML
  /// Name (in the scene's folder) and contents of each file the scene
  /// reads that the script made: the atoms of create_atoms and velocity
  /// create, as a LAMMPS data file `STEM.data`.
  std::vector<std::pair<std::string, std::string>> files;
};

/// As convert_lammps_input; files the conversion makes are named after
/// `stem` (the scene's file name without its extension).
PDYN_HOST_API ConvertedScene convert_lammps_script(const std::string& text, const std::string& file,
                                                   const std::string& stem);

/// What `pdyn convert`'s command line adds to a script.
struct PDYN_HOST_API ConvertOptions {
  /// Variables as lmp's command line gives them (`-var NAME VALUE`):
  /// `${NAME}` in the script is VALUE, and an index variable of the same
  /// name in the script does not redefine it.
  std::map<std::string, std::string> variables;
  /// The folder read_data's relative names are relative to (lmp's working
  /// directory), as seen from the scene's folder: prefixed to them, so that
  /// a scene written elsewhere finds its data file. Empty: the same folder.
  std::string data_folder;
};

/// As above, with the command line's options.
PDYN_HOST_API ConvertedScene convert_lammps_script(const std::string& text, const std::string& file,
                                                   const std::string& stem,
                                                   const ConvertOptions& options);

}  // namespace pdyn
