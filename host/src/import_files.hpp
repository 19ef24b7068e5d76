// Particles from the files other programs write: LAMMPS data files
// (write_data), LAMMPS text dumps (dump atom/custom) and extended XYZ
// (ASE, OVITO, GPUMD), as a scene's `- file:` particle source beside pdyn's
// own CSV side files (docs/scenes.md, "Particles from LAMMPS and extended
// XYZ files"). Numbers are taken as written: pdyn is SI, so LAMMPS `lj`
// units arrive as the same numbers in m, kg and s.
//
// One reader per format (import_lammps_data.cpp, import_lammps_dump.cpp,
// import_xyz.cpp, sharing import_reader.hpp); this header is what the scene
// loader sees of them.
#pragma once

#include <array>
#include <cstdint>
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
/// for messages: "csv, lammps_data, lammps_dump, extxyz".
std::string format_names();
/// The extensions that name a format, for messages: ".csv, .data, ... or .extxyz".
std::string extension_names();

/// The format named `name` (one of side_files::kParticleFileFormats), or nothing.
std::optional<Format> parse_format(std::string_view name);
/// The format a file's extension says: .csv; .data, .lmp; .dump, .lammpstrj;
/// .xyz, .extxyz. Nothing for any other.
std::optional<Format> format_of_extension(const std::filesystem::path& file);
/// Whether the format's files hold several frames (dumps, XYZ): `frame:`.
bool has_frames(Format format);
/// The LAMMPS atom styles a data file's Atoms section may have, for
/// messages: "atomic, charge, sphere, bond, angle, molecular, full".
std::string atom_style_names();
/// Whether `name` is one of atom_style_names().
bool is_atom_style(std::string_view name);

/// What a file gives, particles in id order: LAMMPS ids sorted (a dump
/// lists atoms in any order), extended XYZ in file order or by its `id`
/// column. LAMMPS type t is pdyn type t; XYZ species are types 0, 1, ... in
/// order of first appearance (the loader may map them by `types:`).
struct Imported {
  Format format = Format::Csv;  ///< the format it was read as
  side_files::ParticleRows rows;
  bool has_mass = false;  ///< the file gives every particle's mass
  /// Per particle, its image flags (LAMMPS ix iy iz: the unwrapped position
  /// is x + n L); empty when the file has none.
  std::vector<std::array<std::int32_t, 3>> images;
  /// The kinds `masses:` is keyed by: LAMMPS types as text ("1", "2", every
  /// type a data file's header declares) or XYZ species ("Ar"), and per
  /// particle the index of its kind. No kinds: the file has no types.
  std::vector<std::string> kinds;
  std::vector<std::uint32_t> kind;
  bool species = false;       ///< kinds are XYZ species, not LAMMPS types
  std::optional<Domain> box;  ///< the file's box (orthogonal), if it has one
  /// Sections with rows that no part of pdyn reads yet (a data file's Bonds,
  /// Angles, Dihedrals, Impropers, Ellipsoids, Lines, Triangles, Bodies):
  /// the scene's loader names them in a warning, so that a molecule never
  /// runs as free atoms without a word.
  struct Unread {
    std::string section;  ///< its title: "Bonds"
    long long rows = 0;
    std::size_t line = 0;  ///< its title's line
  };
  std::vector<Unread> unread;
  /// A data file's Bonds, Angles, Dihedrals and Impropers (issue 44): each
  /// term's particles as indices into `rows` (id order) and its LAMMPS type
  /// (1..types). A scene's bonded force or constraint takes one section as
  /// its term list (`pairs: { file: polymer.data }`).
  struct Terms {
    std::string section;  ///< "Bonds", "Angles", "Dihedrals" or "Impropers"
    int arity = 2;        ///< particles per term: 2, 3, 4, 4
    std::vector<std::array<std::size_t, 4>> particles;  ///< the first `arity` used
    std::vector<long long> type;                        ///< per term, 1..the header's count
    std::vector<std::size_t> lines;                     ///< per term, its row's line
  };
  std::vector<Terms> topology;
};

/// The outcome of reading a file: its particles, or nothing (the problems
/// are in the caller's list), and how many frames the file has.
struct ReadResult {
  std::optional<Imported> imported;
  std::size_t frames = 0;
  /// The frame asked for is not in the file (no problem is reported: the
  /// loader reports it at the scene's `frame:`).
  bool no_such_frame = false;
};

/// Reads `file` as `format`: frame `frame` of a dump or XYZ file (0 the
/// first, -1 the last). A data file's Atoms are read in `atom_style` (one
/// of atom_style_names(), as LAMMPS's input script names it) when it is
/// given, else in the style the section's title comment names. Appends to
/// `out` located problems (`shown:LINE:COLUMN: ...`, at most
/// side_files::kMaxProblemsPerFile) if anything is wrong.
ReadResult read(const std::filesystem::path& file, Format format, long long frame,
                std::string_view atom_style, const std::string& shown,
                std::vector<Diagnostic>& out);

}  // namespace pdyn::import_files
