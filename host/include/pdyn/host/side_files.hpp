// Side files: bulk particle and index lists in CSV, named by a scene.
//
// A scene's particles and any index-pair list (a spring's `pairs`) may come
// from a CSV file instead of YAML, which costs about 1 us and 1 kB of
// parser state per node at a million nodes:
//
//   particles:
//     - file: cloth.csv          # header x,y,z[,vx,vy,vz],mass[,fixed][,radius][,type]
//   forces:
//     - { type: spring, ks: 100, pairs: { file: springs.csv } }   # header i,j
//
// Paths are relative to the scene file's folder. The first line is a header
// naming the columns (any order); every other non-empty line is one record.
// Numbers are parsed with std::from_chars (C locale, exact round trip).
// Problems are reported as `FILE:LINE:COLUMN: what is wrong (expected ...)`,
// LINE and COLUMN 1-based, COLUMN the character where the field starts; at
// most kMaxProblemsPerFile of them per file.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "pdyn/host/export.hpp"
#include "pdyn/host/scene.hpp"
#include "pdyn/types.hpp"

namespace pdyn::side_files {

inline constexpr std::size_t kMaxProblemsPerFile = 20;

/// The formats a scene's `- file:` particle source takes (its `format:`
/// key): pdyn's CSV, LAMMPS data files and text dumps, extended XYZ
/// (docs/scenes.md).
inline constexpr std::array<const char*, 4> kParticleFileFormats = {"csv", "lammps_data",
                                                                    "lammps_dump", "extxyz"};

/// Particles read from a CSV file, one entry per record.
struct PDYN_HOST_API ParticleRows {
  std::vector<Vec3> x;              ///< m
  std::vector<Vec3> v;              ///< m/s (zero when the file has no vx,vy,vz)
  std::vector<double> mass;         ///< kg, > 0
  std::vector<std::uint8_t> fixed;  ///< 1: nailed (0 when the file has no fixed column)
  std::vector<double> radius;       ///< m, >= 0; empty when the file has no radius column
  std::vector<std::int32_t> type;   ///< >= 0; empty when the file has no type column
};

/// Reads a particle file (columns x,y,z,mass required; vx,vy,vz together or
/// not at all; fixed as 0/1/true/false; radius (m, >= 0) and type (a whole
/// number >= 0) optional). `shown` is the name used in
/// messages. Returns nothing and appends to `out` its problems if anything
/// is wrong.
PDYN_HOST_API std::optional<ParticleRows> read_particles(const std::filesystem::path& file,
                                                         const std::string& shown,
                                                         std::vector<Diagnostic>& out);

/// Reads an index-tuple file with header i,j (K = 2), i,j,k (K = 3) or i,j,k,l (K = 4); every
/// index must be a whole number in 0..n_particles-1 (unchecked if
/// n_particles < 0).
template <std::size_t K>
PDYN_HOST_API std::optional<std::vector<std::array<Index, K>>> read_tuples(
    const std::filesystem::path& file, const std::string& shown, Index n_particles,
    std::vector<Diagnostic>& out);

/// Writes particles in the format read_particles reads (17 significant
/// digits: the round trip is exact), with radius and type columns when
/// `rows` holds them.
PDYN_HOST_API void write_particles(const std::filesystem::path& file, const ParticleRows& rows);
/// Writes pairs with header i,j.
PDYN_HOST_API void write_pairs(const std::filesystem::path& file,
                               const std::vector<IndexPair>& pairs);

}  // namespace pdyn::side_files
