// LAMMPS data files and dumps as a scene's particles (host/src/
// import_lammps_data.cpp, import_lammps_dump.cpp): the files of one state
// that LAMMPS itself wrote (tests/scenes/import/make_samples.lmp) load to
// the numbers an independent reader finds in them, the same from the data
// file and the dumps; where `lmp` is installed, a state it writes now loads
// the same way; every bad file gets its located message, word for word.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <numbers>

#include "host/import_support.hpp"

namespace pdyn {
namespace {

namespace fs = std::filesystem;
using test::import_problems;
using test::import_sample;
using test::load_imported;

TEST(ImportLammps, DataFileAndDumpOfOneStateGiveWhatLammpsWrote) {
  const Scene data = load_imported(import_sample("melt.data"));
  const Scene dump = load_imported(import_sample("melt.dump"));
  test::expect_same_particles(data, dump);

  // Against the dump as an independent reader sees it: particle k is LAMMPS
  // atom k + 1, its type LAMMPS's, every number the same double.
  const auto frames = test::read_dump(import_sample("melt.dump"));
  ASSERT_EQ(frames.size(), 1u);
  const auto& rows = frames[0].rows;
  const System& s = *data.system;
  ASSERT_EQ(s.size(), 108);  // 4 atoms per fcc cell, 3 x 3 x 3 cells
  ASSERT_EQ(rows.size(), 108u);
  int heavy = 0, crossed = 0;
  for (const auto& [id, r] : rows) {
    const auto k = static_cast<std::size_t>(id - 1);
    const Index i = static_cast<Index>(k);
    EXPECT_EQ(s.types()[k], static_cast<int>(r.at("type")));
    EXPECT_EQ(s.positions().col(i), Vec3(r.at("x"), r.at("y"), r.at("z")));
    EXPECT_EQ(s.velocities().col(i), Vec3(r.at("vx"), r.at("vy"), r.at("vz")));
    EXPECT_EQ(s.masses()[i], r.at("mass"));  // the data file's Masses: 1 for type 1, 2 for type 2
    EXPECT_EQ(s.masses()[i], r.at("type"));
    const std::array<std::int32_t, 3> image{static_cast<std::int32_t>(r.at("ix")),
                                            static_cast<std::int32_t>(r.at("iy")),
                                            static_cast<std::int32_t>(r.at("iz"))};
    EXPECT_EQ(s.images()[k], image) << "atom " << id;
    heavy += r.at("type") == 2;
    crossed += image != std::array<std::int32_t, 3>{};
  }
  EXPECT_EQ(heavy, 27);    // set type 1 type/fraction 2 0.3 12345: 27 of 108 drawn
  EXPECT_EQ(crossed, 24);  // atoms that left the box in 50 steps
  // The box: lattice fcc 0.8442 in lj units, 3 cells a side: 3 (4 / 0.8442)^(1/3).
  EXPECT_EQ(s.domain().min, Vec3::Zero());
  EXPECT_EQ(s.domain().max, frames[0].hi);
  EXPECT_NEAR(s.domain().max.x(), 3.0 * std::cbrt(4.0 / 0.8442), 1e-14);
  EXPECT_EQ(s.domain().periodic, (std::array<bool, 3>{true, true, true}));
}

// melt.lammpstrj holds steps 0, 25 and 50 with unwrapped positions, in the
// order LAMMPS's spatial sort left its atoms: sorted by id, wrapped into the
// box with their crossings counted, its last frame is the data file's state.
TEST(ImportLammps, UnwrappedDumpInLammpsOrderGivesTheSameStateAndImages) {
  const Scene data = load_imported(import_sample("melt.data"));
  const Scene last = load_imported(import_sample("melt.lammpstrj"), ", masses: { 1: 1, 2: 2 }");
  const System& s = *data.system;
  const System& t = *last.system;
  ASSERT_EQ(t.size(), s.size());
  EXPECT_EQ(t.velocities(), s.velocities());  // printed with 17 digits by both
  EXPECT_EQ(t.masses(), s.masses());
  EXPECT_EQ(t.types(), s.types());
  EXPECT_EQ(t.images(), s.images());
  EXPECT_EQ(t.domain(), s.domain());
  // x = xu - n L: LAMMPS's wrapped position to rounding.
  EXPECT_LT((t.positions() - s.positions()).cwiseAbs().maxCoeff(), 1e-14);

  const auto frames = test::read_dump(import_sample("melt.lammpstrj"));
  ASSERT_EQ(frames.size(), 3u);
  const auto& rows = frames[2].rows;
  for (Index i = 0; i < t.size(); ++i) {
    const auto& r = rows.at(i + 1);
    const Vec3 xu(r.at("xu"), r.at("yu"), r.at("zu"));
    const auto& n = t.images()[static_cast<std::size_t>(i)];
    const Vec3 unwrapped = t.positions().col(i) + Vec3(n[0], n[1], n[2]).cwiseProduct(frames[2].hi);
    EXPECT_LT((unwrapped - xu).cwiseAbs().maxCoeff(), 1e-14) << "atom " << i + 1;
  }
}

// `frame: 0` is the start: every atom on its fcc lattice site (a multiple of
// half the cell edge), no crossings yet; frame -2 is frame 1.
TEST(ImportLammps, FrameChoosesAStepOfTheDump) {
  const std::string file = import_sample("melt.lammpstrj");
  const Scene first = load_imported(file, ", mass: 1, frame: 0", ", frame: 0");
  const System& s = *first.system;
  const double half = std::cbrt(4.0 / 0.8442) / 2.0;
  for (Index i = 0; i < s.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      const double q = s.positions()(k, i) / half;
      EXPECT_NEAR(q, std::round(q), 1e-13) << "atom " << i + 1;
    }
  }
  EXPECT_EQ(s.images(), test::Images(108));
  const auto frames = test::read_dump(file);
  EXPECT_EQ(s.velocities().col(0),
            Vec3(frames[0].rows.at(1).at("vx"), frames[0].rows.at(1).at("vy"),
                 frames[0].rows.at(1).at("vz")));
  test::expect_same_particles(load_imported(file, ", mass: 1, frame: 1"),
                              load_imported(file, ", mass: 1, frame: -2"));
}

// Atom style sphere: radius = diameter / 2, mass = density 4 pi r^3 / 3 as
// LAMMPS computes it (the dump's mass column is LAMMPS's own number), and
// Velocities rows with the angular velocity too.
TEST(ImportLammps, SphereStyleGivesRadiiAndMassesAsLammpsComputesThem) {
  const Scene data = load_imported(import_sample("sphere.data"));
  const Scene dump = load_imported(import_sample("sphere.dump"));
  test::expect_same_particles(data, dump);
  const System& s = *data.system;
  ASSERT_EQ(s.size(), 32);
  const auto rows = test::read_dump(import_sample("sphere.dump"))[0].rows;
  int small = 0;
  for (const auto& [id, r] : rows) {
    const Index i = static_cast<Index>(id - 1);
    EXPECT_EQ(s.radii()[static_cast<std::size_t>(i)], r.at("radius"));
    EXPECT_EQ(s.masses()[i], r.at("mass"));
    EXPECT_EQ(s.types()[static_cast<std::size_t>(i)], static_cast<int>(r.at("type")));
    small += r.at("type") == 2;
  }
  EXPECT_EQ(small, 17);          // set type 1 type/fraction 2 0.5 2468: 17 of 32 drawn
  EXPECT_EQ(s.radii()[0], 0.4);  // set type 1 diameter 0.8
  EXPECT_NEAR(s.masses()[0], 1.5 * std::numbers::pi / 6.0 * 0.8 * 0.8 * 0.8, 1e-15);
}

// A data file need not say its atom style (LAMMPS's read_data takes the
// input script's): `atom_style:` gives it, as pdyn convert writes it for a
// script's atom_style, and the topology of a file without a .data name is
// read from the particles' entry. A style the title contradicts, or one
// pdyn does not read, is refused.
TEST(ImportLammps, AtomStyleReadsAFileWhoseTitleDoesNotSayIt) {
  const auto dir = test::temp_dir("import-atom-style");
  test::write_file(dir / "data.pair",
                   "LAMMPS data file\n\n2 atoms\n1 bonds\n1 atom types\n1 bond types\n"
                   "0 4 xlo xhi\n0 4 ylo yhi\n0 4 zlo zhi\n\nMasses\n\n1 2\n\n"
                   "Atoms\n\n1 7 1 0.5 1 1 0 0 0\n2 7 1 1.5 1 1 0 0 0\n\nBonds\n\n1 1 1 2\n");
  const std::string entry = "{ file: " + (dir / "data.pair").string() + ", format: lammps_data";
  const std::string scene = "simulation: { dt: 0.01, steps: 1 }\nparticles:\n  - " + entry +
                            ", atom_style: bond }\nforces:\n  - { type: spring, pairs: { file: " +
                            (dir / "data.pair").string() + " }, ks: 1, rest: 1 }\n";
  const Scene loaded = test::load_text(scene);
  ASSERT_EQ(loaded.system->size(), 2);
  EXPECT_EQ(loaded.system->positions().col(1), Vec3(1.5, 1, 1));
  EXPECT_EQ(loaded.system->masses()[0], 2.0);
  const std::string bad = "simulation: { dt: 0.01, steps: 1 }\nparticles:\n  - " + entry +
                          ", atom_style: ellipsoid }\n";
  EXPECT_EQ(test::load_problems(bad),
            test::scene_at(bad, "ellipsoid") +
                ": particles[0].atom_style: 'ellipsoid' is not an atom style pdyn reads (expected "
                "one of atomic, charge, sphere, bond, angle, molecular, full)");
}

// Sections pdyn does not need are skipped by their counts: a molecular
// file (style full) with bonds, angles and coefficients loads its atoms,
// and topology that no force of the scene takes is named in one warning at
// the first such section's title (issue 42: never a molecule run as free
// atoms without a word); coefficient sections are not named.
TEST(ImportLammps, OtherSectionsAreSkippedByTheirCounts) {
  const auto file = test::write_file(test::temp_dir("import-full") / "water.data",
                                     "LAMMPS data file: one water molecule\n\n"
                                     "3 atoms\n2 bonds\n1 angles\n2 atom types\n1 bond types\n"
                                     "1 angle types\n\n"
                                     "-5 5 xlo xhi\n-5 5 ylo yhi\n-5 5 zlo zhi\n\n"
                                     "Masses\n\n1 15.9994\n2 1.008\n\n"
                                     "Pair Coeffs # lj/cut/coul/long\n\n1 0.1553 3.166\n2 0 0\n\n"
                                     "Bond Coeffs # harmonic\n\n1 554.1349 1.0\n\n"
                                     "Angle Coeffs # harmonic\n\n1 45.7696 109.47\n\n"
                                     "Atoms # full\n\n"
                                     "1 1 1 -0.8476 0 0 0\n"
                                     "2 1 2 0.4238 0.8164904 0.5773590 0\n"
                                     "3 1 2 0.4238 -0.8164904 0.5773590 0\n\n"
                                     "Bonds\n\n1 1 1 2\n2 1 1 3\n\n"
                                     "Angles\n\n1 1 2 1 3\n");
  const Scene s = load_imported(file.string());
  const System& sys = *s.system;
  ASSERT_EQ(sys.size(), 3);
  EXPECT_EQ(sys.positions().col(1), Vec3(0.8164904, 0.5773590, 0));
  EXPECT_EQ(sys.types(), (std::vector<std::int32_t>{1, 2, 2}));
  EXPECT_EQ(sys.masses()[0], 15.9994);
  EXPECT_EQ(sys.masses()[2], 1.008);
  EXPECT_EQ(sys.velocities(), Matrix3X::Zero(3, 3));  // no Velocities section
  EXPECT_EQ(sys.domain().min, Vec3::Constant(-5.0));
  EXPECT_EQ(s.warnings,
            std::vector<std::string>{
                file.string() +
                ":38:1: Bonds (2 rows), Angles (1 row) are not read: no force or constraint of "
                "the scene takes them, so these particles run without those terms (give the "
                "scene the forces or constraints they stand for, e.g. pairs: { file: water.data "
                "} for the Bonds)"});
  // pdyn validate and pdyn run say it too, on stderr, even with --quiet.
  for (const char* command : {"validate", "run"}) {
    const fs::path scene = test::write_file(
        test::temp_dir(std::string("import-full-") + command) / "water.yaml",
        "simulation: { dt: 0.001, steps: 2, box: { file: " + file.string() +
            " }, solver: { type: verlet } }\nparticles:\n  - { file: " + file.string() + " }\n");
    const auto r = test::pdyn({command, scene.string(), "--quiet"});
    EXPECT_EQ(r.status, 0) << r.err;
    EXPECT_EQ(r.err, "pdyn: warning: " + s.warnings[0] + "\n") << command;
  }
}

// A file of atoms only gives no warning.
TEST(ImportLammps, AtomsOnlyGiveNoWarning) {
  const Scene s = load_imported(import_sample("melt.data"));
  EXPECT_TRUE(s.warnings.empty());
}

// Where LAMMPS is installed: it writes a fresh state (another seed and
// size, atoms that crossed faces), and pdyn reads its data file and its
// dump to the same bits and image counts.
TEST(ImportLammps, WhatLammpsWritesNowLoadsTheSameFromItsDataAndDumpFiles) {
  if (std::system("command -v lmp >/dev/null 2>&1") != 0) {
    GTEST_SKIP() << "lmp (Debian's lammps) is not on PATH: the shipped samples it wrote are "
                    "checked instead (ImportLammps.DataFileAndDumpOfOneStateGiveWhatLammpsWrote)";
  }
  const fs::path dir = test::temp_dir("import-lammps-live");
  test::write_file(dir / "in.make",
                   "units lj\n"
                   "atom_style atomic\n"
                   "lattice fcc 0.8\n"
                   "region box block 0 4 0 3 0 3\n"
                   "create_box 3 box\n"
                   "create_atoms 1 box\n"
                   "set type 1 type/fraction 3 0.2 777\n"
                   "mass * 1.5\n"
                   "velocity all create 2.0 4928459 loop geom\n"
                   "pair_style lj/cut 2.5\n"
                   "pair_coeff * * 1.0 1.0\n"
                   "fix 1 all nve\n"
                   "run 40\n"
                   "write_data fresh.data\n"
                   "write_dump all custom fresh.dump id type x y z ix iy iz vx vy vz "
                   "modify sort id format float %.17g\n");
  const std::string cmd = "cd '" + dir.string() + "' && lmp -in in.make -log none -screen none";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  const Scene data = load_imported((dir / "fresh.data").string());
  const Scene dump = load_imported((dir / "fresh.dump").string(), ", mass: 1.5");
  test::expect_same_particles(data, dump);
  const System& s = *data.system;
  ASSERT_EQ(s.size(), 144);  // 4 atoms per cell, 4 x 3 x 3 cells
  EXPECT_EQ(s.masses(), Eigen::VectorXd::Constant(144, 1.5));
  const auto rows = test::read_dump((dir / "fresh.dump").string())[0].rows;
  bool crossed = false;
  for (const auto& [id, r] : rows) {
    const auto k = static_cast<std::size_t>(id - 1);
    EXPECT_EQ(s.positions().col(static_cast<Index>(k)), Vec3(r.at("x"), r.at("y"), r.at("z")));
    EXPECT_EQ(s.types()[k], static_cast<int>(r.at("type")));
    EXPECT_EQ(s.images()[k][0], static_cast<int>(r.at("ix")));
    crossed = crossed || s.images()[k] != std::array<std::int32_t, 3>{};
  }
  EXPECT_TRUE(crossed) << "no atom crossed a face: the image counts were not exercised";
}

struct BadLammps {
  const char* name;
  const char* text;
  const char* extra;     // more keys of the particle entry
  const char* expected;  // every problem, FILE standing for the file's path
};

class BadLammpsFile : public ::testing::TestWithParam<BadLammps> {};

TEST_P(BadLammpsFile, IsReportedAtItsLineAndColumn) {
  const BadLammps& c = GetParam();
  const auto bad = import_problems(c.name, c.text, c.extra);
  EXPECT_EQ(bad.problems, test::with_file(c.expected, bad));
}

// A data file's header and box, for the cases below.
#define HEADER "title\n\n2 atoms\n1 atom types\n0 1 xlo xhi\n0 1 ylo yhi\n0 1 zlo zhi\n\n"
#define MASSES "Masses\n\n1 1\n\n"

INSTANTIATE_TEST_SUITE_P(
    DataFiles, BadLammpsFile,
    ::testing::Values(
        BadLammps{"tilted.data",
                  "title\n\n2 atoms\n1 atom types\n0 1 xlo xhi\n0 1 ylo yhi\n0 1 zlo zhi\n"
                  "0.1 0 0 xy xz yz\n\n" MASSES "Atoms # atomic\n\n1 1 0 0 0\n2 1 .5 .5 .5\n",
                  "",
                  "FILE:8:9: the box is triclinic (xy xz yz tilt factors) (expected an orthogonal "
                  "box: pdyn's simulation box has no tilt)"},
        BadLammps{
            "style.data", HEADER MASSES "Atoms # ellipsoid\n\n1 1 1 1 0 0 0\n2 1 1 1 0 0 0\n", "",
            "FILE:13:9: atom style 'ellipsoid' is not one pdyn reads (expected one of "
            "atomic, charge, sphere, bond, angle, molecular, full, or the scene's atom_style: "
            "beside file)"},
        BadLammps{"mismatch.data",
                  HEADER MASSES "Atoms # full\n\n1 1 1 0 0 0 0\n2 1 1 0 .5 .5 .5\n",
                  ", atom_style: bond",
                  "FILE:13:9: the title says atom style full but the scene's atom_style is bond, "
                  "whose columns differ (expected the style the file was written in)"},
        BadLammps{"count.data", HEADER MASSES "Atoms # atomic\n\n1 1 0 0 0\n", "",
                  "FILE:13:1: the Atoms section has 1 row but the header says 2 atoms (expected "
                  "a row per atom)"},
        BadLammps{"velocities.data",
                  HEADER MASSES "Atoms # atomic\n\n1 1 0 0 0\n2 1 .5 .5 .5\n\nVelocities\n\n1 0 0 "
                                "0\n2 0 0 0\n3 0 0 0\n",
                  "",
                  "FILE:18:1: the Velocities section has 3 rows but the header says 2 atoms "
                  "(expected a row per atom)\n"
                  "FILE:22:1: Velocities gives atom 3, which Atoms does not have (expected the "
                  "ids of Atoms)"},
        BadLammps{"masses.data", HEADER "Masses\n\n1 0\n\nAtoms\n\n1 1 0 0 0\n2 1 .5 .5 .5\n", "",
                  "FILE:11:3: mass: 0 is not positive (expected a mass > 0 kg)"},
        BadLammps{"number.data", HEADER MASSES "Atoms # atomic\n\n1 1 0 zero 0\n2 1 .5 nan .5\n",
                  "",
                  "FILE:15:7: y: 'zero' is not a number (expected a real number, e.g. 0.25)\n"
                  "FILE:16:8: y: nan is not finite (expected a finite number)"},
        BadLammps{"fields.data", HEADER MASSES "Atoms # full\n\n1 1 1 0 0 0 0\n2 1 1 0 .5 .5\n", "",
                  "FILE:16:1: an Atoms row of style full has 6 fields (expected 7, or 10 with "
                  "image flags)"},
        BadLammps{"type.data", HEADER MASSES "Atoms # atomic\n\n1 1 0 0 0\n2 3 .5 .5 .5\n", "",
                  "FILE:16:3: type: 3 is above the header's 1 atom type (expected 1..1)"},
        BadLammps{"twice.data", HEADER MASSES "Atoms # atomic\n\n7 1 0 0 0\n7 1 .5 .5 .5\n", "",
                  "FILE:16:1: atom id 7 appears twice (expected unique ids; first at line 15)"},
        BadLammps{"image.data",
                  HEADER MASSES "Atoms # atomic\n\n1 1 0 0 0 0 0 0\n2 1 0 0 0 1 a 0\n", "",
                  "FILE:16:13: image flag y: 'a' is not a whole number (expected the count of "
                  "box lengths the atom has crossed along y)"},
        BadLammps{"section.data", HEADER MASSES "Atom\n\n1 1 0 0 0\n2 1 .5 .5 .5\n", "",
                  "FILE:13:1: unknown section 'Atom' (expected a section of LAMMPS's read_data: "
                  "Atoms, Velocities, Masses, Bonds, Pair Coeffs, ...)"},
        BadLammps{"bonds.data",
                  HEADER MASSES "Atoms\n\n1 1 0 0 0\n2 1 .5 .5 .5\n\nBonds\n\n1 1 1 2\n", "",
                  "FILE:18:1: the header has no 'N bonds' line (expected one before the Bonds "
                  "section)"},
        BadLammps{"noatoms.data", HEADER MASSES, "",
                  "FILE:3:1: the header says 2 atoms but the file has no Atoms section (expected "
                  "one)"},
        BadLammps{"noheader.data", "title\n\nAtoms\n\n1 1 0 0 0\n", ", mass: 1",
                  "FILE:2:1: the header has no 'N atoms' line (expected a LAMMPS data file, "
                  "whose header counts its atoms)"},
        BadLammps{"nomass.data",
                  "title\n\n2 atoms\n2 atom types\n\n" MASSES
                  "Atoms # atomic\n\n1 1 0 0 0\n2 2 .5 .5 .5\n",
                  "",
                  "FILE:6:1: the Masses section has 1 row but the header says 2 atom types "
                  "(expected a row per atom type)\n"
                  "FILE:13:1: atom 2 has type 2, which the Masses section does not give "
                  "(expected a mass for every type)"},
        BadLammps{"sphere.data", HEADER "Atoms # sphere\n\n1 1 1 1 0 0 0\n2 1 -1 0 .5 .5 .5\n", "",
                  "FILE:12:5: diameter: -1 is negative (expected a diameter >= 0 m)\n"
                  "FILE:12:8: density: 0 is not positive (expected a density > 0 kg/m^3, or the "
                  "mass in kg of a particle of diameter 0)"},
        BadLammps{"flat.data", "title\n\n1 atoms\n1 1 xlo xhi\n\nAtoms\n\n1 1 0 0 0\n", ", mass: 1",
                  "FILE:4:3: xhi 1 is not above xlo 1 (expected hi > lo)"}));

INSTANTIATE_TEST_SUITE_P(
    Dumps, BadLammpsFile,
    ::testing::Values(
        BadLammps{"twice.dump",
                  "ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n2\nITEM: BOX BOUNDS pp pp pp\n0 1\n0 "
                  "1\n0 1\nITEM: ATOMS id type x y z\n7 1 0 0 0\n7 1 .5 .5 .5\n",
                  ", mass: 1",
                  "FILE:11:1: atom id 7 appears twice (expected unique ids; first at line 10)"},
        BadLammps{"short.dump",
                  "ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n1\nITEM: BOX BOUNDS pp pp pp\n0 1\n0 "
                  "1\n0 1\nITEM: ATOMS id type x y z\n1 1 0 0\n",
                  ", mass: 1",
                  "FILE:10:1: has 4 fields, ITEM: ATOMS names 5 (expected one per column)"},
        BadLammps{"count.dump",
                  "ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n3\nITEM: BOX BOUNDS pp pp pp\n0 1\n0 "
                  "1\n0 1\nITEM: ATOMS id type x y z\n1 1 0 0 0\n2 1 .5 .5 .5\n",
                  ", mass: 1",
                  "FILE:9:1: the frame has 2 atom rows but NUMBER OF ATOMS says 3 (expected a row "
                  "per atom)"},
        BadLammps{"tilted.dump",
                  "ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n1\nITEM: BOX BOUNDS xy xz yz pp pp "
                  "pp\n0 1 0\n0 1 0\n0 1 0\nITEM: ATOMS id type x y z\n1 1 0 0 0\n",
                  ", mass: 1",
                  "FILE:5:18: the box is triclinic (tilt factors) (expected an orthogonal box: "
                  "pdyn's simulation box has no tilt)"},
        BadLammps{"flags.dump",
                  "ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n1\nITEM: BOX BOUNDS pp pf ff\n0 1\n0 "
                  "1\n0 1\nITEM: ATOMS id type x y z\n1 1 0 0 0\n",
                  ", mass: 1",
                  "FILE:5:21: boundary flags 'pf' are not LAMMPS's (expected pp, or two of f, s, "
                  "m: ff, fs, sm, ...)"},
        BadLammps{"columns.dump",
                  "ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n1\nITEM: BOX BOUNDS pp pp pp\n0 1\n0 "
                  "1\n0 1\nITEM: ATOMS type x y z\n1 0 0 0\n",
                  ", mass: 1",
                  "FILE:9:1: the ATOMS columns lack id or a position (expected id and x y z, xu "
                  "yu zu, xs ys zs or xsu ysu zsu)"},
        BadLammps{"mass.dump",
                  "ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n2\nITEM: BOX BOUNDS pp pp pp\n0 1\n0 "
                  "1\n0 1\nITEM: ATOMS id type x y z mass\n1 1 0 0 0 -1\n2 1 .5 .5 inf 1\n",
                  "",
                  "FILE:10:11: mass: -1 is not positive (expected a mass > 0 kg)\n"
                  "FILE:11:11: z: inf is not finite (expected a finite number)"},
        BadLammps{"image.dump",
                  "ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n1\nITEM: BOX BOUNDS pp pp pp\n0 1\n0 "
                  "1\n0 1\nITEM: ATOMS id x y z ix iy iz\n1 0 0 0 0 1.5 0\n",
                  ", mass: 1",
                  "FILE:10:11: image flag y: '1.5' is not a whole number (expected the count of "
                  "box lengths the atom has crossed along y)"},
        BadLammps{"empty.dump", "\n", ", mass: 1",
                  "FILE:1:1: no 'ITEM: TIMESTEP' line (expected a LAMMPS text dump)"},
        BadLammps{"nomass.dump",
                  "ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n1\nITEM: BOX BOUNDS pp pp pp\n0 1\n0 "
                  "1\n0 1\nITEM: ATOMS id type x y z\n1 1 0 0 0\n",
                  "",
                  "test.yaml:3:13: particles[0].file: the file gives no masses (expected mass: "
                  "KG or masses: { TYPE: KG, ... } beside file, or masses in the file)"}));

// At most 20 problems of one file are listed, then how many more there are.
TEST(ImportLammps, AFileWithManyProblemsListsTwentyAndCountsTheRest) {
  std::string text = "title\n\n25 atoms\n\nAtoms # atomic\n\n";
  for (int i = 1; i <= 25; ++i) text += std::to_string(i) + " 1 0 0 x\n";
  const auto bad = import_problems("many.data", text, ", mass: 1");
  const auto lines = test::split_lines(bad.problems);
  ASSERT_EQ(lines.size(), 21u) << bad.problems;
  EXPECT_EQ(lines[0],
            bad.file.string() + ":7:9: z: 'x' is not a number (expected a real number, e.g. 0.25)");
  EXPECT_EQ(lines[19], bad.file.string() +
                           ":26:10: z: 'x' is not a number (expected a real number, e.g. 0.25)");
  EXPECT_EQ(lines[20], bad.file.string() + ": 5 more problems not shown (expected a valid file)");
}

}  // namespace
}  // namespace pdyn
