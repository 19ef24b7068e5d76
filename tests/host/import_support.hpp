// Helpers shared by the importer tests (import_files_test.cpp,
// import_lammps_test.cpp, import_xyz_test.cpp): the LAMMPS-written samples
// of tests/scenes/import/, a scene of a file's particles and box, an
// independent reader of LAMMPS text dumps, and the exact problems of a bad
// file.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "support/test_support.hpp"

namespace pdyn::test {

/// Image counts, one per particle (System::images()).
using Images = std::vector<std::array<std::int32_t, 3>>;

/// tests/scenes/import/NAME.
inline std::string import_sample(const std::string& name) {
  return source_path("tests/scenes/import/" + name).string();
}

/// A scene of the particles of `file` (an absolute path) and its box, with
/// `extra` keys in the particle entry (", masses: { 1: 1 }").
inline Scene load_imported(const std::string& file, const std::string& extra = "",
                           const std::string& box_extra = "") {
  return load_text("simulation: { dt: 0.005, steps: 1, box: { file: " + file + box_extra +
                   " }, solver: { type: verlet } }\n"
                   "particles:\n"
                   "  - { file: " +
                   file + extra + " }\n");
}

/// Same particles, types, masses, box and image counts, bit for bit.
inline void expect_same_particles(const Scene& a, const Scene& b) {
  const System& s = *a.system;
  const System& t = *b.system;
  ASSERT_EQ(s.size(), t.size());
  EXPECT_EQ(s.positions(), t.positions());
  EXPECT_EQ(s.velocities(), t.velocities());
  EXPECT_EQ(s.masses(), t.masses());
  EXPECT_EQ(s.types(), t.types());
  EXPECT_EQ(s.radii(), t.radii());
  EXPECT_EQ(s.images(), t.images());
  EXPECT_EQ(s.domain(), t.domain());
}

/// One frame of a LAMMPS text dump as an independent reader sees it
/// (std::istream's numbers, not pdyn's from_chars): the box's upper corner
/// and, by id, each row's numbers in the order of the column names.
struct DumpFrame {
  std::vector<std::string> columns;  // after "ITEM: ATOMS"
  Vec3 hi = Vec3::Zero();
  std::map<long long, std::map<std::string, double>> rows;
};

/// The frames of the dump `file`.
inline std::vector<DumpFrame> read_dump(const std::string& file) {
  std::ifstream in(file);
  std::vector<DumpFrame> frames;
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("ITEM: TIMESTEP", 0) != 0) continue;
    DumpFrame f;
    std::getline(in, line);  // the step
    std::getline(in, line);  // ITEM: NUMBER OF ATOMS
    std::getline(in, line);
    const long long n = std::stoll(line);
    std::getline(in, line);  // ITEM: BOX BOUNDS
    for (int k = 0; k < 3; ++k) {
      std::getline(in, line);
      std::istringstream s(line);
      double lo = 0;
      s >> lo >> f.hi[k];
    }
    std::getline(in, line);
    std::istringstream names(line.substr(std::string("ITEM: ATOMS").size()));
    for (std::string name; names >> name;) f.columns.push_back(name);
    for (long long i = 0; i < n && std::getline(in, line); ++i) {
      std::istringstream s(line);
      std::map<std::string, double> row;
      for (const auto& name : f.columns) s >> row[name];
      f.rows[static_cast<long long>(row["id"])] = row;
    }
    frames.push_back(std::move(f));
  }
  return frames;
}

/// Where `needle` starts in the scene text `yaml` (its first occurrence),
/// as load_text's messages say it: "test.yaml:LINE:COLUMN".
inline std::string scene_at(const std::string& yaml, const std::string& needle) {
  const auto at = yaml.find(needle);
  EXPECT_NE(at, std::string::npos) << needle;
  const auto line_start = yaml.rfind('\n', at);
  const auto line = std::count(yaml.begin(), yaml.begin() + static_cast<std::ptrdiff_t>(at), '\n');
  const auto column = line_start == std::string::npos ? at + 1 : at - line_start;
  return "test.yaml:" + std::to_string(line + 1) + ":" + std::to_string(column);
}

/// A bad file `name` with `text`, read as the particles of a scene with
/// `extra` keys: its path and every problem the loader reports.
struct BadImport {
  std::filesystem::path file;
  std::string problems;
};
inline BadImport import_problems(const std::string& name, const std::string& text,
                                 const std::string& extra = "") {
  const auto file = write_file(temp_dir("import-bad") / name, text);
  return {file, load_problems("simulation: { dt: 0.01, steps: 1 }\n"
                              "particles:\n"
                              "  - { file: " +
                              file.string() + extra + " }\n")};
}

/// `expected` with each "FILE" replaced by the path of `bad`'s file.
inline std::string with_file(std::string expected, const BadImport& bad) {
  for (std::size_t at; (at = expected.find("FILE")) != std::string::npos;) {
    expected.replace(at, 4, bad.file.string());
  }
  return expected;
}

}  // namespace pdyn::test
