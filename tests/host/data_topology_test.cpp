// A data file's topology as term lists (issue 44 item 1): `pairs: { file:
// X.data }` takes its Bonds, `triples:` its Angles, `quads:` its Dihedrals
// (or `section: Impropers`), atom ids turned into the scene's particle
// indices and LAMMPS's type t into term type t - 1. Checked against the
// same terms written by hand (the same forces to the last bit), against
// LAMMPS (20 chains with harmonic bonds and angles and OPLS dihedrals, all
// from the data file, thermo to 1e-8 over 200 steps), the warnings for
// sections no force takes, and each bad input's message.
#include <gtest/gtest.h>

#include <string>

#include "pdyn/system.hpp"
#include "support/lammps_thermo.hpp"
#include "support/test_support.hpp"

namespace pdyn {
namespace {

namespace fs = std::filesystem;

// Four atoms of one chain, listed out of id order (10, 3, 7, 5), with two
// bond types; line numbers are quoted by the tests below.
const char* const kChain =
    "LAMMPS data file: a chain of four atoms\n"  // 1
    "\n"
    "4 atoms\n"  // 3
    "3 bonds\n"
    "2 angles\n"  // 5
    "1 dihedrals\n"
    "1 atom types\n"  // 7
    "2 bond types\n"
    "1 angle types\n"  // 9
    "1 dihedral types\n"
    "\n"  // 11
    "-5 5 xlo xhi\n"
    "-5 5 ylo yhi\n"  // 13
    "-5 5 zlo zhi\n"
    "\n"  // 15
    "Masses\n"
    "\n"  // 17
    "1 1.5\n"
    "\n"  // 19
    "Atoms # molecular\n"
    "\n"  // 21
    "10 1 1 1.9 1.2 0.8\n"
    "3 1 1 0 0 0\n"  // 23
    "7 1 1 1.6 0.9 0\n"
    "5 1 1 1.1 0 0\n"  // 25
    "\n"
    "Bonds\n"  // 27
    "\n"
    "1 1 3 5\n"  // 29
    "2 2 5 7\n"
    "3 1 7 10\n"  // 31
    "\n"
    "Angles\n"  // 33
    "\n"
    "1 1 3 5 7\n"  // 35
    "2 1 5 7 10\n"
    "\n"  // 37
    "Dihedrals\n"
    "\n"  // 39
    "1 1 3 5 7 10\n";

// A folder holding chain.data (with `edit` applied: {from, to} replaced).
fs::path ChainFile(const std::string& name, const std::string& from = "",
                   const std::string& to = "") {
  std::string text = kChain;
  if (!from.empty()) text.replace(text.find(from), from.size(), to);
  return test::write_file(test::temp_dir("data-topology-" + name) / "chain.data", text);
}

// One free particle first, so that the file's atoms are particles 1..4.
std::string SceneText(const fs::path& data, const std::string& forces,
                      const std::string& extra = "") {
  return "simulation: { dt: 0.001, steps: 1 }\nparticles:\n"
         "  - { position: [4, 4, 4], mass: 2 }\n  - { file: " +
         data.string() + " }\n" + extra + "forces:\n" + forces;
}

Matrix3X TopologyForcesOf(const System& sys, std::size_t index) {
  Matrix3X f = Matrix3X::Zero(3, sys.size());
  sys.force_objects().at(index).force->add_forces(sys.view(), f);
  return f;
}

TEST(DataTopology, BondsAnglesAndDihedralsAreTheTermsWrittenByHand) {
  const fs::path data = ChainFile("same");
  const std::string d = data.string();
  const pdyn::Scene from_file =
      test::load_text(SceneText(data, "  - { type: spring, pairs: { file: " + d +
                                          " }, ks: [100, 200], rest: [1.0] }\n"
                                          "  - { type: angle, triples: { file: " +
                                          d +
                                          " }, k: 3, rest: [2.0] }\n"
                                          "  - { type: dihedral, quads: { file: " +
                                          d + " }, k: 2, rest: [0.5] }\n"));
  // Atom ids 3, 5, 7, 10 are particles 1, 2, 3, 4; bond types 1, 2, 1 are
  // term types 0, 1, 0.
  const pdyn::Scene by_hand = test::load_text(
      "simulation: { dt: 0.001, steps: 1 }\nparticles:\n"
      "  - { position: [4, 4, 4], mass: 2 }\n"
      "  - { position: [0, 0, 0], mass: 1.5 }\n"
      "  - { position: [1.1, 0, 0], mass: 1.5 }\n"
      "  - { position: [1.6, 0.9, 0], mass: 1.5 }\n"
      "  - { position: [1.9, 1.2, 0.8], mass: 1.5 }\n"
      "forces:\n"
      "  - { type: spring, pairs: [[1, 2], [2, 3], [3, 4]], types: [0, 1, 0], ks: [100, 200], "
      "rest: [1.0] }\n"
      "  - { type: angle, triples: [[1, 2, 3], [2, 3, 4]], k: 3, rest: [2.0] }\n"
      "  - { type: dihedral, quads: [[1, 2, 3, 4]], k: 2, rest: [0.5] }\n");
  ASSERT_EQ(from_file.system->positions(), by_hand.system->positions());
  for (std::size_t k = 0; k < 3; ++k) {
    const Matrix3X f = TopologyForcesOf(*from_file.system, k);
    EXPECT_GT(f.norm(), 0.1) << "force " << k << " should act";
    EXPECT_EQ(f, TopologyForcesOf(*by_hand.system, k)) << "force " << k;
  }
  EXPECT_EQ(from_file.system->potential_energy(), by_hand.system->potential_energy());
  EXPECT_TRUE(from_file.warnings.empty()) << from_file.warnings.front();
}

TEST(DataTopology, ChainsWithBondsAnglesAndOplsDihedralsFollowLammps) {
  // tests/scenes/molecular: every term from molecular_start.data, LAMMPS's
  // state at step 0. The runs agree to about 1e-14 up to step 160 and part
  // at about 1e-11 by step 180 (LAMMPS's dihedral and angle codes clamp
  // sin phi and sin theta near 0; pdyn's formulas have no such floor).
  // 200 beads in a box of 1000: N kT / V is 0.2.
  test::expect_lammps_thermo("molecular", {"molecular.yaml", "molecular_start.data"},
                             "out/molecular-energy.csv", 1e-8, 0.2);
}

TEST(DataTopology, ChainsWithCosineSquaredAnglesAndHarmonicDihedralsFollowLammps) {
  // The same chains with LAMMPS's angle_style cosine/squared and
  // dihedral_style harmonic (make_reference_cosine.lmp): about 1e-13.
  test::expect_lammps_thermo("molecular", {"cosine.yaml", "cosine_start.data"},
                             "out/cosine-energy.csv", 1e-10, 0.2, "cosine.thermo");
}

TEST(DataTopology, ChainsWithHarmonicImpropersFollowLammps) {
  // The chains with LAMMPS's improper_style harmonic in place of dihedrals
  // (make_reference_improper.lmp), the impropers taken with `section:
  // Impropers`: about 1e-13.
  test::expect_lammps_thermo("molecular", {"improper.yaml", "improper_start.data"},
                             "out/improper-energy.csv", 1e-10, 0.2, "improper.thermo");
}

TEST(DataTopology, SectionsNoForceTakesAreNamedInAWarning) {
  const fs::path data = ChainFile("warn");
  const pdyn::Scene s = test::load_text(SceneText(
      data, "  - { type: spring, pairs: { file: " + data.string() + " }, ks: [1, 2] }\n"));
  EXPECT_EQ(s.warnings,
            std::vector<std::string>{
                data.string() +
                ":33:1: Angles (2 rows), Dihedrals (1 row) are not read: no force or constraint "
                "of the scene takes them, so these particles run without those terms (give the "
                "scene the forces or constraints they stand for, e.g. pairs: { file: chain.data "
                "} for the Bonds)"});
}

TEST(DataTopology, EachBadInputIsRefusedWhereItIsWritten) {
  struct Case {
    const char* name;
    const char* from;  // edit of the data file
    const char* to;
    std::string forces;    // with DATA for the file
    std::string expected;  // with FILE for the data file, SCENE for "test.yaml"
  };
  const std::string spring = "  - { type: spring, pairs: { file: DATA }, ks: [1, 2] }\n";
  const Case cases[] = {
      {"missing-atom", "2 2 5 7", "2 2 5 4", spring,
       "FILE:30:7: Bonds names atom 4, which Atoms does not have (expected the ids of Atoms)"},
      {"type-above", "2 2 5 7", "2 3 5 7", spring,
       "FILE:30:3: bond type 3 is above the header's 2 bond types (expected 1..2)"},
      {"twice", "3 1 7 10", "3 1 7 7", spring,
       "FILE:31:7: Bonds names atom 7 twice in one term (expected 2 distinct atoms)"},
      {"no-types-line", "1 dihedral types\n", "", spring,
       "FILE:37:1: the header has no 'N dihedral types' line (expected one before the "
       "Dihedrals section)"},
      {"short-row", "1 1 3 5 7\n", "1 1 3 5\n", spring,
       "FILE:35:1: the row has 4 fields (expected 5 in Angles: id, type and 3 atom ids)"},
      // (Keys after the file's name on lines of their own: their columns do
      // not depend on the temporary folder's name.)
      {"types-beside", "", "",
       "  - { type: spring, pairs: { file: DATA },\n      types: [0], ks: 1 }\n",
       "SCENE:7:14: forces[0].types: is given beside pairs from 'chain.data' (expected no types: "
       "the file gives each term its type, LAMMPS type t being term type t - 1)"},
      {"wrong-section", "", "",
       "  - { type: spring, pairs: { section: Angles, file: DATA }, ks: [1, 2] }\n",
       "SCENE:6:39: forces[0].pairs.section: 'Angles' is not a section of 2-particle terms "
       "(expected Bonds)"},
      {"constraint-types", "", "",
       "  - { type: gravity }\nconstraints:\n  - { type: distance, pairs: { file: DATA, types: "
       "[3] } }\n",
       "constraints[0].pairs.types[0]: '3' is not a type of the Bonds of 'chain.data' (expected "
       "a list of the LAMMPS types of its Bonds: 1, 2)"},
      {"types-not-list", "", "", "  - { type: spring, ks: 1, pairs: { file: DATA, types: 2 } }\n",
       "forces[0].pairs.types: '2' is not a list of types (expected a list of the LAMMPS types "
       "of its Bonds: 1, 2)"},
  };
  for (const Case& c : cases) {
    const fs::path data = ChainFile(c.name, c.from, c.to);
    std::string forces = c.forces;
    forces.replace(forces.find("DATA"), 4, data.string());
    std::string expected = c.expected;
    if (expected.rfind("FILE", 0) == 0) expected.replace(0, 4, data.string());
    if (expected.rfind("SCENE", 0) == 0) expected.replace(0, 5, "test.yaml");
    const std::string got = test::load_problems(SceneText(data, forces));
    EXPECT_NE(got.find(expected), std::string::npos)
        << c.name << ":\n  got      " << got << "\n  expected " << expected;
  }
}

TEST(DataTopology, AFileThatGivesNoParticlesIsRefused) {
  const fs::path data = ChainFile("foreign");
  const std::string got = test::load_problems(
      "simulation: { dt: 0.001, steps: 1 }\nparticles:\n  - { position: [0, 0, 0], mass: 1 }\n"
      "  - { position: [1, 0, 0], mass: 1 }\nforces:\n  - { type: spring, pairs: { file: " +
      data.string() + " } }\n");
  EXPECT_NE(got.find("forces[0].pairs.file: 'chain.data' gives none of the scene's particles "
                     "(expected the data file of one `particles: - file:` entry: the terms name "
                     "its atoms)"),
            std::string::npos)
      << got;
}

}  // namespace
}  // namespace pdyn
