// A scene's particle files and a box from a file (host/src/scene_files.cpp,
// import_files.cpp): which format reads a file, the keys each format takes
// (format, frame, mass, masses, types, periodic), each refused value at its
// place in the scene, image counts, and `pdyn validate` on the shipped
// scenes of each format.
#include <gtest/gtest.h>

#include "host/import_support.hpp"

namespace pdyn {
namespace {

namespace fs = std::filesystem;
using test::import_sample;
using test::load_imported;
using test::scene_at;

const char* const kSceneHead = "simulation: { dt: 0.01, steps: 1 }\nparticles:\n  - { file: ";

// The problems of a scene whose particle entry is `{ file: FILE<rest> }`,
// and where `needle` is in it.
struct EntryProblems {
  std::string problems, scene;
  std::string at(const std::string& needle) const { return scene_at(scene, needle); }
};
EntryProblems entry_problems(const std::string& file, const std::string& rest) {
  const std::string scene = kSceneHead + file + rest + " }\n";
  return {test::load_problems(scene), scene};
}

// A CSV file under another extension, named by `format`, loads as CSV.
TEST(ImportFiles, FormatKeyOverridesTheExtension) {
  const fs::path file =
      test::write_file(test::temp_dir("import-format") / "atoms.txt", "x,y,z,mass\n0,0,1,2\n");
  const Scene s = test::load_text(kSceneHead + file.string() + ", format: csv }\n");
  ASSERT_EQ(s.system->size(), 1);
  EXPECT_EQ(s.system->masses()[0], 2.0);
}

TEST(ImportFiles, AFormatIsNamedOrElseTakenFromAKnownExtension) {
  const fs::path file =
      test::write_file(test::temp_dir("import-ext") / "atoms.txt", "x,y,z,mass\n0,0,0,1\n");
  const auto none = entry_problems(file.string(), "");
  EXPECT_EQ(none.problems,
            none.at(file.string()) +
                ": particles[0].file: 'atoms.txt' has an extension that names no format "
                "(expected .csv, .data, .lmp, .dump, .lammpstrj, .xyz or .extxyz, or a format: "
                "key, one of csv, lammps_data, lammps_dump, extxyz)");
  const auto pdb = entry_problems(file.string(), ", format: pdb");
  EXPECT_EQ(pdb.problems, pdb.at("pdb") +
                              ": particles[0].format: 'pdb' is not a format pdyn reads (expected "
                              "one of csv, lammps_data, lammps_dump, extxyz)");
}

// Each format takes its own keys: a data file has one frame and no species
// (and an atom style, which other formats do not).
TEST(ImportFiles, KeysAnotherFormatTakesAreRefusedWithTheFormatsOwn) {
  const auto p = entry_problems(import_sample("melt.data"), ", frame: 0, types: { Ar: 1 }");
  EXPECT_EQ(p.problems, p.at("frame") +
                            ": unknown key 'frame' in particles[0] (expected one of: file, "
                            "format, atom_style, mass, masses)\n" +
                            p.at("types") +
                            ": unknown key 'types' in particles[0] (expected one of: file, "
                            "format, atom_style, mass, masses)");
}

TEST(ImportFiles, AFrameMustBeOneOfTheFile) {
  const std::string file = import_sample("melt.lammpstrj");
  const auto past = entry_problems(file, ", mass: 1, frame: 3");
  EXPECT_EQ(past.problems, past.at("3 }") +
                               ": particles[0].frame: 3 is not a frame of 'melt.lammpstrj' "
                               "(expected 0..2, or -3..-1 counting from the end: the file has 3 "
                               "frames)");
  const auto word = entry_problems(file, ", mass: 1, frame: last");
  EXPECT_EQ(word.problems, word.at("last") +
                               ": particles[0].frame: 'last' is not a frame number (expected a "
                               "whole number: 0 the first frame, -1 the last)");
}

// `masses` per LAMMPS type replaces the data file's; every type of the
// file's particles needs one, and only the file's types may be named.
TEST(ImportFiles, MassesPerTypeReplaceTheFilesAndMustCoverEveryType) {
  const std::string data = import_sample("melt.data");
  const Scene argon = load_imported(data, ", masses: { 1: 39.948, 2: 83.798 }");
  const System& s = *argon.system;
  for (Index i = 0; i < s.size(); ++i) {
    EXPECT_EQ(s.masses()[i], s.types()[static_cast<std::size_t>(i)] == 1 ? 39.948 : 83.798);
  }
  const std::string dump = import_sample("melt.lammpstrj");
  const auto one = entry_problems(dump, ", masses: { 1: 1 }");
  EXPECT_EQ(one.problems, one.at("{ 1: 1 }") +
                              ": particles[0].masses: gives no mass for type 2 (expected one for "
                              "each type of the file's particles: 1, 2)");
  const auto three = entry_problems(dump, ", masses: { 1: 1, 2: 2, 3: 1 }");
  EXPECT_EQ(three.problems, three.at("3:") +
                                ": particles[0].masses: '3' is not a type of the file (expected "
                                "one of 1, 2)");
  const auto zero = entry_problems(dump, ", masses: { 1: 0, 2: 2 }");
  EXPECT_EQ(zero.problems, zero.at("0,") +
                               ": particles[0].masses.1: '0' is not a mass (expected a number > "
                               "0, kg)");
  const auto both = entry_problems(dump, ", mass: 1, masses: { 1: 1, 2: 2 }");
  EXPECT_EQ(both.problems,
            both.at("{ 1: 1, 2: 2 }") +
                ": particles[0].masses: is given beside mass (expected one of them)");
}

// A data file declares its types: masses may name a type no atom has.
TEST(ImportFiles, MassesMayNameADeclaredTypeNoAtomHas) {
  const auto file = test::write_file(test::temp_dir("import-types") / "two.data",
                                     "title\n\n1 atoms\n3 atom types\n\nAtoms\n\n1 2 0 0 0\n");
  const Scene s = load_imported(file.string(), ", masses: { 1: 1, 2: 4, 3: 9 }");
  EXPECT_EQ(s.system->masses()[0], 4.0);
  EXPECT_EQ(s.system->types()[0], 2);
  // read_data's default box, periodic: -0.5..0.5 along each axis.
  EXPECT_EQ(s.system->domain().min, Vec3::Constant(-0.5));
  EXPECT_EQ(s.system->domain().max, Vec3::Constant(0.5));
}

// The data file's image flags are the particles' image counts along the
// periodic axes of the scene's box; along an axis `periodic` makes open
// they are 0, as the kernel keeps them there.
TEST(ImportFiles, ImageFlagsBecomeImageCountsAlongPeriodicAxes) {
  const std::string data = import_sample("melt.data");
  const Scene all = load_imported(data);
  const Scene open_z = load_imported(data, "", ", periodic: [true, true, false]");
  EXPECT_EQ(open_z.system->domain().periodic, (std::array<bool, 3>{true, true, false}));
  const auto& a = all.system->images();
  const auto& b = open_z.system->images();
  ASSERT_EQ(a.size(), b.size());
  bool z_crossed = false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(b[i][0], a[i][0]);
    EXPECT_EQ(b[i][1], a[i][1]);
    EXPECT_EQ(b[i][2], 0);
    z_crossed = z_crossed || a[i][2] != 0;
  }
  EXPECT_TRUE(z_crossed);
  // Without a box there are no periodic axes: no image counts.
  const Scene no_box = test::load_text(kSceneHead + data + " }\n");
  EXPECT_EQ(no_box.system->images(), test::Images(108));
}

// A position outside a periodic box (an unwrapped coordinate) starts
// wrapped, with the box lengths it moved counted.
TEST(ImportFiles, APositionOutsideAPeriodicBoxIsWrappedAndCounted) {
  const auto file = test::write_file(
      test::temp_dir("import-wrap") / "out.dump",
      "ITEM: TIMESTEP\n7\nITEM: NUMBER OF ATOMS\n2\nITEM: BOX BOUNDS pp pp ff\n0 2\n0 2\n0 2\n"
      "ITEM: ATOMS id xu yu zu\n2 -0.5 5 1\n1 0.5 0.5 0.5\n");
  const Scene s = load_imported(file.string(), ", mass: 1");
  const System& sys = *s.system;
  EXPECT_EQ(sys.positions().col(1), Vec3(1.5, 1, 1));
  EXPECT_EQ(sys.images()[1], (std::array<std::int32_t, 3>{-1, 2, 0}));
  EXPECT_EQ(sys.images()[0], (std::array<std::int32_t, 3>{0, 0, 0}));
  EXPECT_EQ(sys.types(), (std::vector<std::int32_t>{1, 1}));  // no type column: LAMMPS's type 1
  EXPECT_EQ(sys.domain().periodic, (std::array<bool, 3>{true, true, false}));
}

// A box from a file that has none is refused at the key.
TEST(ImportFiles, ABoxFromAFileWithoutOneIsRefused) {
  const fs::path file =
      test::write_file(test::temp_dir("import-nobox") / "atoms.csv", "x,y,z,mass\n0,0,1,2\n");
  const std::string scene = "simulation: { dt: 0.01, steps: 1, box: { file: " + file.string() +
                            " } }\nparticles:\n  - { position: [0, 0, 1], mass: 1 }\n";
  EXPECT_EQ(test::load_problems(scene),
            scene_at(scene, file.string()) +
                ": simulation.box.file: the file has no box (expected a LAMMPS data or dump "
                "file, or an extended XYZ file with a Lattice)");
}

// A file that gives the box and the particles is read once: its problems
// are listed once.
TEST(ImportFiles, AFileGivingBoxAndParticlesHasItsProblemsListedOnce) {
  const auto file = test::write_file(test::temp_dir("import-once") / "bad.data",
                                     "title\n\n1 atoms\n\nAtoms\n\n1 1 0 0 zero\n");
  const std::string scene = "simulation: { dt: 0.01, steps: 1, box: { file: " + file.string() +
                            " } }\nparticles:\n  - { file: " + file.string() + ", mass: 1 }\n";
  EXPECT_EQ(test::load_problems(scene),
            file.string() + ":7:9: z: 'zero' is not a number (expected a real number, e.g. 0.25)");
}

// `pdyn validate` accepts the shipped scene of each format.
TEST(ImportFiles, ValidateAcceptsTheShippedSceneOfEachFormat) {
  for (const char* name : {"melt_data.yaml", "melt_dump.yaml", "melt_xyz.yaml"}) {
    const std::string scene = import_sample(name);
    const auto r = test::pdyn({"validate", scene});
    EXPECT_EQ(r.status, 0) << name << ": " << r.err;
    EXPECT_EQ(r.out, scene +
                         ": ok: 108 particles, 1 force object, 0 colliders, solver verlet, 10 "
                         "steps of 0.005 s\n");
  }
}

}  // namespace
}  // namespace pdyn
