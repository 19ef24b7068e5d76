// Particles from the files other programs write: LAMMPS data files
// (write_data), LAMMPS text dumps (dump atom/custom) and extended XYZ
// (ASE, OVITO, GPUMD), as a scene's `- file:` particle source beside pdyn's
// own CSV side files (docs/scenes.md, "Particles from LAMMPS and extended
// XYZ files"). Numbers are taken as written: pdyn is SI, so LAMMPS `lj`
// units arrive as the same numbers in m, kg and s.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "pdyn/domain.hpp"
#include "pdyn/host/scene.hpp"
#include "pdyn/host/side_files.hpp"

namespace pdyn::import_files {

enum class Format { Csv, LammpsData, LammpsDump, ExtXyz };

/// The names a scene's `format:` takes (side_files::kParticleFileFormats),
/// for messages: "csv, lammps_data, ...".
std::string format_names();

/// The format named `name` (one of side_files::kParticleFileFormats), or nothing.
std::optional<Format> parse_format(std::string_view name);
/// The format a file's extension says: .csv; .data, .lmp; .dump, .lammpstrj;
/// .xyz, .extxyz. Nothing for any other.
std::optional<Format> format_of_extension(const std::filesystem::path& file);

/// What a file gives. Particles are in id order (LAMMPS ids sorted; XYZ in
/// file order); LAMMPS types t >= 1 become pdyn types t - 1, XYZ species
/// types 0, 1, ... in order of first appearance.
struct Imported {
  side_files::ParticleRows rows;
  bool has_mass = false;      ///< the file gives every particle's mass
  std::optional<Domain> box;  ///< the file's box (orthogonal), if it has one
};

/// Reads `file` as `format`; the last frame of a dump or XYZ file with
/// several. Returns nothing and appends located problems
/// (`shown:LINE:COLUMN: ...`) if anything is wrong.
std::optional<Imported> read(const std::filesystem::path& file, Format format,
                             const std::string& shown, std::vector<Diagnostic>& problems);

}  // namespace pdyn::import_files
