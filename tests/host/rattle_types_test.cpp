// Rigid molecules from a data file's bond and angle types (issue 44 item
// 4), as LAMMPS's `fix rattle ... b 1 a 1`: `pairs: { file: X.data, types:
// [1] }` takes the Bonds of type 1, `triples:` the Angles, and the
// `distance` constraint holds each angle as the distance of its ends.
// Checked against LAMMPS (256 bent 3-bead molecules in a Lennard-Jones
// liquid, special_bonds lj 0 0 0, written by Debian 12's LAMMPS): thermo to
// 1e-10 over 200 steps. Then the selection by hand: only the terms of the
// listed types, with their own type's length; and the factory's refusals.
#include <gtest/gtest.h>

#include <string>

#include "pdyn/constraint.hpp"
#include "pdyn/system.hpp"
#include "support/lammps_thermo.hpp"
#include "support/test_support.hpp"

namespace pdyn {
namespace {

namespace fs = std::filesystem;

TEST(RattleTypes, RigidTrimersFollowLammpsFixRattleStepForStep) {
  // 768 beads in a box of 2560: N kT / V is 0.3.
  test::expect_lammps_thermo("trimers", {"trimers.yaml", "trimers_start.data"},
                             "out/trimers-energy.csv", 1e-10, 0.3);
}

// Five atoms: a chain 1-2-3 of bond type 1, a bond 3-4 of type 2, atom 5
// bonded to 4 by type 1; angles 1-2-3 (type 1) and 2-3-4 (type 2).
const char* const kTypedChain =
    "LAMMPS data file: typed bonds\n\n"
    "5 atoms\n4 bonds\n2 angles\n1 atom types\n2 bond types\n2 angle types\n\n"
    "-5 5 xlo xhi\n-5 5 ylo yhi\n-5 5 zlo zhi\n\n"
    "Masses\n\n1 1\n\n"
    "Atoms # molecular\n\n"
    "1 1 1 0 0 0\n2 1 1 1 0 0\n3 1 1 1 1 0\n4 1 1 2 1 0\n5 1 1 2 2 0\n\n"
    "Bonds\n\n1 1 1 2\n2 1 2 3\n3 2 3 4\n4 1 4 5\n\n"
    "Angles\n\n1 1 1 2 3\n2 2 2 3 4\n";

// The scene of kTypedChain's atoms with `constraints`, DATA standing for
// the file.
Scene TypedScene(std::string constraints) {
  const fs::path data =
      test::write_file(test::temp_dir("rattle-types") / "typed.data", kTypedChain);
  for (auto at = constraints.find("DATA"); at != std::string::npos; at = constraints.find("DATA")) {
    constraints.replace(at, 4, data.string());
  }
  return test::load_text(
      "simulation: { dt: 0.001, steps: 1, solver: { type: verlet } }\n"
      "particles:\n  - { file: " +
      data.string() + " }\nconstraints:\n" + constraints);
}

TEST(RattleTypes, TypesSelectTheTermsAndGiveEachItsLength) {
  Scene s = TypedScene(
      "  - { type: distance, pairs: { file: DATA, types: [1] }, length: [0.9, 5] }\n"
      "  - { type: distance, triples: { file: DATA, types: [2] } }\n");
  const auto& objects = s.system->constraint_objects();
  ASSERT_EQ(objects.size(), 2u);
  // Bonds of type 1: 1-2, 2-3, 4-5 (particles 0-1, 1-2, 3-4), each 0.9 long.
  const ConstraintPattern bonds = objects[0].constraint->pattern();
  EXPECT_EQ(bonds.particle, (std::vector<Index>{0, 1, 1, 2, 3, 4}));
  ConstraintValues v;
  v.value.resize(3);
  v.rate.resize(3);
  v.bias.resize(3);
  v.jacobian.resize(3, 6);
  objects[0].constraint->evaluate(s.system->view(), v);
  EXPECT_NEAR(v.value[0], 1.0 - 0.9, 1e-15);
  EXPECT_NEAR(v.value[2], 1.0 - 0.9, 1e-15);
  // The angle of type 2, 2-3-4: its ends, particles 1 and 3, at their
  // initial distance sqrt(2).
  const ConstraintPattern ends = objects[1].constraint->pattern();
  EXPECT_EQ(ends.particle, (std::vector<Index>{1, 3}));
}

TEST(RattleTypes, TheFactoryRefusesWhatCannotBeRods) {
  const fs::path data =
      test::write_file(test::temp_dir("rattle-types-bad") / "typed.data", kTypedChain);
  auto problems = [&](const std::string& constraints) {
    return test::load_problems(
        "simulation: { dt: 0.001, steps: 1, solver: { type: verlet } }\n"
        "particles:\n  - { file: " +
        data.string() + " }\nconstraints:\n" + constraints);
  };
  EXPECT_EQ(problems("  - { type: distance }\n"),
            "test.yaml:5:5: constraints[0].pairs: is missing (expected pairs, or triples whose "
            "ends are held)");
  EXPECT_EQ(problems("  - { type: distance, pairs: [[0, 1]], triples: [[0, 1, 2]] }\n"),
            "test.yaml:5:49: constraints[0].triples: is given beside pairs (expected one of the "
            "two)");
  EXPECT_EQ(problems("  - { type: distance, triples: [[0, 1, 2], [2, 1, 0]] }\n"),
            "test.yaml:5:44: constraints[0].triples[1]: joins particles 2 and 0 a second time "
            "(expected each rod once)");
}

}  // namespace
}  // namespace pdyn
