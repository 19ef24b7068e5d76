// Particles from LAMMPS data files, LAMMPS dumps and extended XYZ
// (host/src/import_files.cpp): the three files of one state, written by
// LAMMPS itself (tests/scenes/import/make_samples.lmp), load to the same
// bits; where `lmp` is installed, a fresh state LAMMPS writes now is
// imported the same way; and each bad file gets its located message.
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <sstream>

#include "support/test_support.hpp"

namespace pdyn {
namespace {

namespace fs = std::filesystem;

std::string sample(const std::string& name) {
  return test::source_path("tests/scenes/import/" + name).string();
}

// A scene of the particles and the box of `file` (an absolute path).
Scene imported(const std::string& file, const std::string& extra = "") {
  return test::load_text("simulation: { dt: 0.005, steps: 1, box: { file: " + file +
                         " }, solver: { type: verlet } }\n"
                         "particles:\n"
                         "  - { file: " +
                         file + extra +
                         " }\n"
                         "forces:\n"
                         "  - { type: lennard_jones, cutoff: 2.5 }\n");
}

void expect_same_state(const Scene& a, const Scene& b) {
  const System& s = *a.system;
  const System& t = *b.system;
  ASSERT_EQ(s.size(), t.size());
  EXPECT_EQ(s.positions(), t.positions());
  EXPECT_EQ(s.velocities(), t.velocities());
  EXPECT_EQ(s.masses(), t.masses());
  EXPECT_EQ(s.types(), t.types());
  EXPECT_EQ(s.domain().min, t.domain().min);
  EXPECT_EQ(s.domain().max, t.domain().max);
  EXPECT_EQ(s.domain().periodic, t.domain().periodic);
}

// The dump's rows as an independent reader sees them: id -> the row's
// numbers (type x y z vx vy vz mass).
std::map<long long, std::vector<double>> dump_rows(const std::string& file) {
  std::ifstream in(file);
  std::string line;
  std::map<long long, std::vector<double>> rows;
  bool atoms = false;
  while (std::getline(in, line)) {
    if (line.rfind("ITEM: ATOMS", 0) == 0) {
      atoms = true;
      continue;
    }
    if (!atoms) continue;
    std::istringstream s(line);
    long long id = 0;
    s >> id;
    std::vector<double> r(8);
    for (double& x : r) s >> x;
    rows[id] = r;
  }
  return rows;
}

TEST(ImportFiles, LammpsDataDumpAndExtendedXyzOfOneStateLoadToTheSameBits) {
  const Scene data = imported(sample("melt.data"));
  const Scene dump = imported(sample("melt.dump"));
  const Scene xyz = imported(sample("melt.xyz"));
  expect_same_state(data, dump);
  expect_same_state(data, xyz);

  // Against the dump as written: particle k is LAMMPS atom k + 1, its type
  // one less, every number the same double.
  const auto rows = dump_rows(sample("melt.dump"));
  const System& s = *data.system;
  ASSERT_EQ(static_cast<std::size_t>(s.size()), rows.size());
  ASSERT_EQ(s.size(), 256);
  int heavy = 0;
  for (const auto& [id, r] : rows) {
    const Index k = static_cast<Index>(id - 1);
    EXPECT_EQ(s.types()[static_cast<std::size_t>(k)], static_cast<int>(r[0]) - 1);
    EXPECT_EQ(s.positions().col(k), Vec3(r[1], r[2], r[3]));
    EXPECT_EQ(s.velocities().col(k), Vec3(r[4], r[5], r[6]));
    EXPECT_EQ(s.masses()[k], r[7]);  // the data file's Masses: 1 for type 1, 2 for type 2
    heavy += r[0] == 2;
  }
  EXPECT_GT(heavy, 0);
  EXPECT_LT(heavy, 256);
  // The box: lattice fcc 0.8442 in lj units, 4 cells a side: 4 (4 / 0.8442)^(1/3).
  EXPECT_EQ(s.domain().min, Vec3::Zero());
  EXPECT_NEAR(s.domain().max.x(), 4.0 * std::cbrt(4.0 / 0.8442), 1e-12);
  EXPECT_EQ(s.domain().periodic, (std::array<bool, 3>{true, true, true}));
}

// Where LAMMPS is installed: it writes a fresh state (other seed, other
// size, a sphere-style data file with diameters and densities), and pdyn
// reads what it wrote.
TEST(ImportFiles, WhatLammpsWritesNowLoadsTheSameFromItsDataAndDumpFiles) {
  if (std::system("command -v lmp >/dev/null 2>&1") != 0) {
    GTEST_SKIP() << "lmp (Debian's lammps) is not installed: the shipped samples are checked "
                    "instead (ImportFiles.LammpsDataDumpAndExtendedXyzOfOneStateLoadToTheSameBits)";
  }
  const fs::path dir = test::temp_dir("import-lammps");
  test::write_file(dir / "in.make",
                   "units lj\n"
                   "atom_style sphere\n"
                   "lattice fcc 0.8\n"
                   "region box block 0 5 0 4 0 4\n"
                   "create_box 1 box\n"
                   "create_atoms 1 box\n"
                   "set group all diameter 0.5\n"
                   "set group all density 1.5\n"
                   "velocity all create 1.5 4928459 loop geom\n"
                   "write_data fresh.data\n"
                   "write_dump all custom fresh.dump id type x y z vx vy vz mass radius "
                   "modify sort id format float %.17g\n");
  const std::string cmd = "cd '" + dir.string() + "' && lmp -in in.make -log none -screen none";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  const Scene data = imported((dir / "fresh.data").string());
  const Scene dump = imported((dir / "fresh.dump").string());
  expect_same_state(data, dump);
  ASSERT_EQ(data.system->size(), 320);  // 4 atoms per cell, 5 x 4 x 4 cells
  // Sphere style: radius = diameter / 2, mass = density pi d^3 / 6 (LAMMPS's).
  EXPECT_EQ(data.system->radii(), std::vector<double>(320, 0.25));
  EXPECT_NEAR(data.system->masses()[0], 1.5 * std::numbers::pi / 6.0 * 0.125, 1e-15);
  EXPECT_EQ(data.system->radii(), dump.system->radii());
}

struct BadFile {
  const char* name;
  const char* text;
  const char* extra;     // more keys of the particle entry
  const char* expected;  // the message, after the file's path
};

class BadImport : public ::testing::TestWithParam<BadFile> {};

TEST_P(BadImport, IsReportedAtItsLineAndColumn) {
  const BadFile& c = GetParam();
  const fs::path file = test::write_file(test::temp_dir("import-bad") / c.name, c.text);
  const std::string problems = test::load_problems(
      "simulation: { dt: 0.01, steps: 1 }\n"
      "particles:\n"
      "  - { file: " +
      file.string() + c.extra + " }\n");
  EXPECT_NE(problems.find(std::string(c.expected)), std::string::npos) << problems;
}

INSTANTIATE_TEST_SUITE_P(
    Files, BadImport,
    ::testing::Values(
        BadFile{"tilted.data",
                "title\n\n2 atoms\n1 atom types\n0 1 xlo xhi\n0 1 ylo yhi\n0 1 zlo zhi\n"
                "0.1 0 0 xy xz yz\n\nMasses\n\n1 1\n\nAtoms # atomic\n\n1 1 0 0 0\n2 1 .5 .5 .5\n",
                "", "tilted.data:8:9: the box is triclinic"},
        BadFile{"style.data", "title\n\n1 atoms\n\nAtoms # ellipsoid\n\n1 1 1 1 0 0 0\n", "",
                "style.data:5:9: atom style 'ellipsoid' is not one pdyn reads (expected one of "
                "atomic, charge, sphere, bond, angle, molecular, full)"},
        BadFile{"count.data",
                "title\n\n3 atoms\n\nMasses\n\n1 1\n\nAtoms # atomic\n\n1 1 0 0 0\n2 1 1 1 1\n", "",
                "count.data:9:1: the Atoms section has 2 rows but the header says 3 atoms"},
        BadFile{"number.data",
                "title\n\n1 atoms\n\nMasses\n\n1 1\n\nAtoms # atomic\n\n1 1 0 zero 0\n", "",
                "number.data:11:7: y: 'zero' is not a number (expected a real number, e.g. "
                "0.25)"},
        BadFile{"twice.dump",
                "ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n2\nITEM: BOX BOUNDS pp pp pp\n0 1\n0 "
                "1\n0 1\nITEM: ATOMS id type x y z\n7 1 0 0 0\n7 1 .5 .5 .5\n",
                ", mass: 1",
                "twice.dump:11:1: atom id 7 appears twice (expected unique ids; first "
                "at line 10)"},
        BadFile{"nomass.dump",
                "ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n1\nITEM: BOX BOUNDS pp pp pp\n0 1\n0 "
                "1\n0 1\nITEM: ATOMS id type x y z\n1 1 0 0 0\n",
                "", "particles[0].file: the file gives no masses (expected mass: KG beside file"},
        BadFile{"short.dump",
                "ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n1\nITEM: BOX BOUNDS pp pp pp\n0 1\n0 "
                "1\n0 1\nITEM: ATOMS id type x y z\n1 1 0 0\n",
                ", mass: 1", "short.dump:10:1: has 4 fields, ITEM: ATOMS names 5"},
        BadFile{"skew.xyz",
                "1\nLattice=\"1 0.5 0 0 1 0 0 0 1\" Properties=species:S:1:pos:R:3\nAr 0 0 0\n",
                ", mass: 1", "skew.xyz:2:1: Lattice is not 9 numbers of an orthogonal box"},
        BadFile{"heavy.xyz", "1\nProperties=species:S:1:pos:R:3:mass:R:1\nAr 0 0 0 -2\n", "",
                "heavy.xyz:3:10: mass: -2 is not positive (expected a mass > 0 kg)"},
        BadFile{"atoms.txt", "x,y,z,mass\n0,0,0,1\n", "",
                "particles[0].file: 'atoms.txt' has an extension that names no format "
                "(expected .csv, .data, .lmp, .dump, .lammpstrj, .xyz or .extxyz, or a format: "
                "key, one of csv, lammps_data, lammps_dump, extxyz)"},
        BadFile{"atoms.txt", "x,y,z,mass\n0,0,0,1\n", ", format: pdb",
                "particles[0].format: 'pdb' is not a format pdyn reads (expected one of csv, "
                "lammps_data, lammps_dump, extxyz)"},
        BadFile{"atoms.xyz", "1\nProperties=species:S:1:pos:R:3\nAr 0 0 0\n", ", mass: -1",
                "particles[0].mass: '-1' is not a mass (expected a number > 0, kg)"}));

// A CSV file under another extension, named by `format`, loads as CSV.
TEST(ImportFiles, FormatKeyOverridesTheExtension) {
  const fs::path file =
      test::write_file(test::temp_dir("import-format") / "atoms.txt", "x,y,z,mass\n0,0,1,2\n");
  const Scene s = test::load_text("simulation: { dt: 0.01, steps: 1 }\nparticles:\n  - { file: " +
                                  file.string() + ", format: csv }\n");
  ASSERT_EQ(s.system->size(), 1);
  EXPECT_EQ(s.system->masses()[0], 2.0);
}

// A box from a file that has none is refused at the key.
TEST(ImportFiles, ABoxFromAFileWithoutOneIsRefused) {
  const fs::path file =
      test::write_file(test::temp_dir("import-nobox") / "atoms.csv", "x,y,z,mass\n0,0,1,2\n");
  const std::string problems =
      test::load_problems("simulation: { dt: 0.01, steps: 1, box: { file: " + file.string() +
                          " } }\nparticles:\n  - { position: [0, 0, 1], mass: 1 }\n");
  EXPECT_NE(problems.find("simulation.box.file: the file has no box (expected a LAMMPS data or "
                          "dump file, or an extended XYZ file with a Lattice)"),
            std::string::npos)
      << problems;
}

}  // namespace
}  // namespace pdyn
