// Extended XYZ as a scene's particles (host/src/import_xyz.cpp): the
// shipped melt.xyz, written from LAMMPS's files of the same run
// (tests/scenes/import/make_xyz.py), loads to their numbers; species become
// types by first appearance or by `types:`; the keys of the comment line
// (Properties, Lattice, Origin, pbc) are read as ASE and OVITO write them;
// every bad file gets its located message, word for word.
#include <gtest/gtest.h>

#include "host/import_support.hpp"

namespace pdyn {
namespace {

using test::import_problems;
using test::import_sample;
using test::load_imported;

// The last frame is the state of melt.data: with `types` naming LAMMPS's
// types, every number is the data file's (the XYZ file has no image flags).
TEST(ImportXyz, LastFrameIsTheStateLammpsWroteWithItsTypesByName) {
  const Scene xyz = load_imported(import_sample("melt.xyz"), ", types: { Ar: 1, Kr: 2 }");
  const Scene data = load_imported(import_sample("melt.data"));
  const System& s = *xyz.system;
  const System& t = *data.system;
  ASSERT_EQ(s.size(), 108);
  EXPECT_EQ(s.positions(), t.positions());
  EXPECT_EQ(s.velocities(), t.velocities());
  EXPECT_EQ(s.masses(), t.masses());
  EXPECT_EQ(s.types(), t.types());
  EXPECT_EQ(s.domain(), t.domain());  // Lattice with pbc="T T T"
  EXPECT_EQ(s.images(), test::Images(108));
}

// Without `types`, species are types 0, 1, ... in order of first
// appearance: atom 1 is Ar (type 1 in LAMMPS), so Ar is 0 and Kr 1.
TEST(ImportXyz, SpeciesAreTypesInOrderOfFirstAppearance) {
  const Scene xyz = load_imported(import_sample("melt.xyz"));
  const Scene data = load_imported(import_sample("melt.data"));
  std::vector<std::int32_t> lammps_minus_one = data.system->types();
  for (auto& t : lammps_minus_one) --t;
  EXPECT_EQ(xyz.system->types(), lammps_minus_one);
}

// Frame 0 (no masses in it: `masses` per species) is the first frame of
// LAMMPS's own dump, from which make_xyz.py copied it.
TEST(ImportXyz, FirstFrameIsTheDumpsFirstFrame) {
  test::expect_same_particles(
      load_imported(import_sample("melt.xyz"),
                    ", frame: 0, masses: { Ar: 1, Kr: 2 }, types: { Ar: 1, Kr: 2 }", ", frame: 0"),
      load_imported(import_sample("melt.lammpstrj"), ", frame: 0, masses: { 1: 1, 2: 2 }",
                    ", frame: 0"));
}

// OVITO's Origin, a pbc per axis, radii, and an id column: particles in id
// order, types by first appearance in the file.
TEST(ImportXyz, IdOriginPbcAndRadiusAreRead) {
  const auto file =
      test::write_file(test::temp_dir("import-xyz") / "three.extxyz",
                       "3\n"
                       "Lattice=\"2 0 0 0 3 0 0 0 4\" Origin=\"-1 -1.5 0\" pbc=\"T F T\" "
                       "Properties=id:I:1:species:S:1:pos:R:3:radius:R:1:mass:R:1\n"
                       "3 C 0.5 0.5 1 0.1 12\n"
                       "1 H 0 0 2 0.05 1.008\n"
                       "2 O -0.5 1 3 0.2 16\n");
  const Scene s = load_imported(file.string());
  const System& sys = *s.system;
  ASSERT_EQ(sys.size(), 3);
  EXPECT_EQ(sys.positions().col(0), Vec3(0, 0, 2));
  EXPECT_EQ(sys.positions().col(2), Vec3(0.5, 0.5, 1));
  EXPECT_EQ(sys.masses(), Eigen::Vector3d(1.008, 16, 12));
  EXPECT_EQ(sys.radii(), (std::vector<double>{0.05, 0.2, 0.1}));
  EXPECT_EQ(sys.types(), (std::vector<std::int32_t>{1, 2, 0}));  // C, H, O as they appear
  EXPECT_EQ(sys.domain().min, Vec3(-1, -1.5, 0));
  EXPECT_EQ(sys.domain().max, Vec3(1, 1.5, 4));
  EXPECT_EQ(sys.domain().periodic, (std::array<bool, 3>{true, false, true}));
}

TEST(ImportXyz, TypesMustNameEverySpeciesOfTheFileAndNoOther) {
  const std::string file = import_sample("melt.xyz");
  auto problems = [&](const std::string& types) {
    return test::load_problems("simulation: { dt: 0.01, steps: 1 }\nparticles:\n  - { file: " +
                               file + ", types: " + types + " }\n");
  };
  const std::string head = "simulation: { dt: 0.01, steps: 1 }\nparticles:\n  - { file: " + file;
  EXPECT_EQ(problems("{ Ar: 1 }"), test::scene_at(head + ", types: { Ar: 1 } }\n", "{ Ar: 1 }") +
                                       ": particles[0].types: gives no type for species Kr "
                                       "(expected one for each species of the file: Ar, Kr)");
  const std::string xe = head + ", types: { Ar: 1, Kr: 2, Xe: 3 } }\n";
  EXPECT_EQ(problems("{ Ar: 1, Kr: 2, Xe: 3 }"),
            test::scene_at(xe, "Xe") +
                ": particles[0].types: 'Xe' is not a species of the file (expected one of Ar, "
                "Kr)");
  const std::string minus = head + ", types: { Ar: -1, Kr: 2 } }\n";
  EXPECT_EQ(problems("{ Ar: -1, Kr: 2 }"),
            test::scene_at(minus, "-1") +
                ": particles[0].types.Ar: '-1' is not a particle type (expected a whole number "
                "in 0..2147483647)");
}

struct BadXyz {
  const char* name;
  const char* text;
  const char* expected;  // every problem, FILE standing for the file's path
};

class BadXyzFile : public ::testing::TestWithParam<BadXyz> {};

TEST_P(BadXyzFile, IsReportedAtItsLineAndColumn) {
  const BadXyz& c = GetParam();
  const auto bad = import_problems(c.name, c.text, ", mass: 1");
  EXPECT_EQ(bad.problems, test::with_file(c.expected, bad));
}

INSTANTIATE_TEST_SUITE_P(
    Files, BadXyzFile,
    ::testing::Values(
        BadXyz{"skew.xyz",
               "1\nLattice=\"1 0.5 0 0 1 0 0 0 1\" Properties=species:S:1:pos:R:3\nAr 0 0 0\n",
               "FILE:2:1: Lattice is not an orthogonal box (expected \"Lx 0 0 0 Ly 0 0 0 Lz\" "
               "with Lx, Ly, Lz > 0: pdyn's simulation box has no tilt)"},
        BadXyz{"eight.xyz", "1\nLattice=\"1 0 0 0 1 0 0 0\"\nAr 0 0 0\n",
               "FILE:2:1: '1 0 0 0 1 0 0 0' is not 9 finite numbers (expected Lattice=\"Lx 0 0 "
               "0 Ly 0 0 0 Lz\")"},
        BadXyz{"props.xyz", "1\npbc=\"F F F\" Properties=species:S:1:pos:R\nAr 0 0 0\n",
               "FILE:2:13: Properties is malformed at 'pos' (expected name:type:count triples, "
               "type S, R, I or L, e.g. species:S:1:pos:R:3)"},
        BadXyz{"nopos.xyz", "1\nProperties=species:S:1:position:R:3\nAr 0 0 0\n",
               "FILE:2:1: Properties has no pos:R:3 (expected the positions)"},
        BadXyz{"pbc.xyz", "1\nLattice=\"1 0 0 0 1 0 0 0 1\" pbc=\"T T\"\nAr 0 0 0\n",
               "FILE:2:29: pbc='T T' is not three of T and F (expected e.g. pbc=\"T T F\")"},
        BadXyz{"quote.xyz", "1\nLattice=\"1 0 0 0 1 0 0 0 1\nAr 0 0 0\n",
               "FILE:2:9: the value of Lattice opens a '\"' that is never closed (expected "
               "key=\"value\")"},
        BadXyz{"fields.xyz", "2\nProperties=species:S:1:pos:R:3\nAr 0 0 0\nAr 0 0\n",
               "FILE:4:1: has 3 fields, Properties gives 4 (expected one per column)"},
        BadXyz{"count.xyz", "two\nProperties=species:S:1:pos:R:3\nAr 0 0 0\n",
               "FILE:1:1: 'two' is not an atom count (expected a line with the number of atoms "
               "of frame 0: an extended XYZ file starts with it)"},
        BadXyz{"after.xyz", "1\nProperties=species:S:1:pos:R:3\nAr 0 0 0\nAr 1 1 1\n",
               "FILE:4:1: 'Ar 1 1 1' is not an atom count (expected a line with the number of "
               "atoms of frame 1)"},
        BadXyz{"ends.xyz", "3\nProperties=species:S:1:pos:R:3\nAr 0 0 0\n",
               "FILE:3:1: the file ends after 1 of the frame's 3 atoms (expected a row per "
               "atom)"},
        BadXyz{"nan.xyz", "1\nProperties=species:S:1:pos:R:3\nAr 0 NaN 0\n",
               "FILE:3:6: y: NaN is not finite (expected a finite number)"}));

// A mass in the file that is not positive (the scene gives no mass: key).
TEST(ImportXyz, AMassThatIsNotPositiveIsRefusedAtItsField) {
  const auto bad =
      import_problems("heavy.xyz", "1\nProperties=species:S:1:pos:R:3:mass:R:1\nAr 0 0 0 -2\n");
  EXPECT_EQ(bad.problems,
            bad.file.string() + ":3:10: mass: -2 is not positive (expected a mass > 0 kg)");
}

}  // namespace
}  // namespace pdyn
