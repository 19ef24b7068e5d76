// The scene's `special_bonds:` (host/src/scene_special_bonds.cpp, issue 44
// item 3), against LAMMPS and by its errors: the Kremer-Grest melt with
// `special_bonds fene` and a Lennard-Jones liquid of bonded chains with
// `special_bonds lj 0.2 0.5 0.25` follow LAMMPS's thermo (written by
// Debian 12's LAMMPS, tests/scenes/special) to 1e-10 over 200 steps; the
// same melt with every pair at full weight does not; a bond added to a
// loaded scene (add_plugin) changes the pairs as in a scene that had it;
// a warning for a scene with no bonds or no pair force; every bad value a
// located error with its exact text.
#include "pdyn/special_bonds.hpp"

#include <gtest/gtest.h>

#include "pdyn/host/scene.hpp"
#include "pdyn/pair.hpp"
#include "support/lammps_thermo.hpp"
#include "support/test_support.hpp"

namespace pdyn {
namespace {

TEST(SceneSpecialBonds, KremerGrestMeltFollowsLammpsStepForStep) {
  // 400 beads at density 0.8: N kT / V is about 0.8.
  test::expect_lammps_thermo("special", {"kg.yaml", "kg_start.data"}, "out/kg-energy.csv", 1e-10,
                             0.8, "kg.thermo");
}

TEST(SceneSpecialBonds, ScaledPairsFollowLammpsStepForStep) {
  test::expect_lammps_thermo("special", {"scaled.yaml", "scaled_start.data"},
                             "out/scaled-energy.csv", 1e-10, 0.8, "scaled.thermo");
}

TEST(SceneSpecialBonds, WithoutThemTheMeltIsAnotherMelt) {
  // The check above can fail: the bonded pairs' WCA counted twice moves the
  // potential energy by more than 5% at step 0.
  const fs::path dir = test::temp_dir("special-full-weight");
  for (const char* f : {"kg.yaml", "kg_start.data"}) {
    fs::copy_file(test::source_path(std::string("tests/scenes/special/") + f), dir / f);
  }
  Scene plain = load_scene(dir / "kg.yaml", test::shipped_plugins(),
                           {{"special_bonds", "{ lj: [1, 1, 1] }"}});
  Scene fene = load_scene(dir / "kg.yaml", test::shipped_plugins());
  const double u_plain = plain.system->potential_energy(), u_fene = fene.system->potential_energy();
  const auto lammps = test::csv_columns(test::source_path("tests/scenes/special/kg.thermo"));
  EXPECT_NEAR(u_fene, lammps.at("pe").at(0), 1e-12 * u_fene);
  EXPECT_GT(u_plain - u_fene, 0.05 * u_fene);
}

// The sum of the scene's forces at its initial state.
Matrix3X SpecialSceneForces(const Scene& s) {
  Matrix3X f = Matrix3X::Zero(3, s.system->size());
  for (const auto& entry : s.system->force_objects()) entry.force->add_forces(s.system->view(), f);
  return f;
}

// Four particles in a row, 1 m apart, and a Lennard-Jones force of cutoff 3.5.
std::string SpecialRow(const std::string& extra) {
  return "simulation: { dt: 0.001, steps: 1, solver: { type: verlet } }\n"
         "particles:\n"
         "  - { position: [0, 0, 0], mass: 1 }\n"
         "  - { position: [1.1, 0, 0], mass: 1 }\n"
         "  - { position: [2.2, 0, 0], mass: 1 }\n"
         "  - { position: [3.3, 0, 0], mass: 1 }\n"
         "forces:\n"
         "  - { type: lennard_jones, cutoff: 3.5 }\n" +
         extra;
}

TEST(SceneSpecialBonds, ABondAddedLaterWeighsThePairsAsInASceneThatHadIt) {
  const std::string spring = "{ type: spring, pairs: [[0, 1], [1, 2]], ks: 10, rest: 1.1 }";
  Scene later = test::load_text(SpecialRow("special_bonds: { lj: [0, 0.5, 1] }\n"));
  ASSERT_EQ(later.warnings.size(), 1u);
  EXPECT_EQ(later.warnings[0],
            "test.yaml:9:16: special_bonds: the scene has no bonds, so no pair is weighted (bonds "
            "are the `pairs:` of its forces and constraints)");
  add_plugin(later, test::shipped_plugins(), PluginKind::Force, spring, "python");
  Scene from_start =
      test::load_text(SpecialRow("  - " + spring + "\nspecial_bonds: { lj: [0, 0.5, 1] }\n"));
  EXPECT_TRUE(from_start.warnings.empty());
  const Matrix3X a = SpecialSceneForces(later), b = SpecialSceneForces(from_start);
  EXPECT_TRUE(a.cwiseEqual(b).all()) << a << "\n\n" << b;
  // And a pair force added later takes them too: its energy is the
  // weighted sum, 0.5 U(2.2) + U(2.2) + U(3.3) + U(1.1) for pairs 0-2 (1-3),
  // 1-3, 0-3 and 2-3 (particle 3 is bonded to none).
  Scene none =
      test::load_text(SpecialRow("  - " + spring + "\nspecial_bonds: { lj: [0, 0.5, 1] }\n"));
  add_plugin(none, test::shipped_plugins(), PluginKind::Force,
             "{ type: lennard_jones, cutoff: 3.5 }", "python2");
  const auto* lj =
      dynamic_cast<const SpecialBondsTarget*>(none.system->force_objects().back().force.get());
  ASSERT_NE(lj, nullptr);
  ASSERT_NE(lj->special_bonds(), nullptr);
  auto u = [](double r) { return 4 * (std::pow(r, -12) - std::pow(r, -6)); };
  EXPECT_NEAR(*none.system->force_objects().back().force->potential_energy(none.system->view()),
              1.5 * u(2.2) + u(3.3) + u(1.1), 1e-14);
}

TEST(SceneSpecialBonds, ASceneWithoutPairForcesIsWarned) {
  Scene s = test::load_text(
      "simulation: { dt: 0.001, steps: 1, solver: { type: verlet } }\n"
      "particles:\n  - { position: [0, 0, 0], mass: 1 }\n  - { position: [1, 0, 0], mass: 1 }\n"
      "forces:\n  - { type: spring, pairs: [[0, 1]], ks: 1 }\nspecial_bonds: fene\n");
  ASSERT_EQ(s.warnings.size(), 1u);
  EXPECT_EQ(s.warnings[0],
            "test.yaml:7:16: special_bonds: the scene has no pair force to weigh its pairs");
}

TEST(SceneSpecialBonds, BadValuesAreLocatedErrors) {
  EXPECT_EQ(test::load_problems(SpecialRow("special_bonds: lammps\n")),
            "test.yaml:9:16: special_bonds: 'lammps' is not a setting (expected fene, amber, "
            "charmm, dreiding, or { lj: [w12, w13, w14] } with each weight from 0 to 1)");
  EXPECT_EQ(test::load_problems(SpecialRow("special_bonds: { lj: [0, 0.5] }\n")),
            "test.yaml:9:22: special_bonds.lj: '[0, 0.5]' is not three weights (expected three "
            "weights [w12, w13, w14] of the pairs one, two and three bonds apart, each from 0 to "
            "1)");
  EXPECT_EQ(test::load_problems(SpecialRow("special_bonds: { lj: [0, 1.5, 1] }\n")),
            "test.yaml:9:22: special_bonds.lj: '[0, 1.5, 1]' is not three weights (expected three "
            "weights [w12, w13, w14] of the pairs one, two and three bonds apart, each from 0 to "
            "1)");
  EXPECT_EQ(test::load_problems(SpecialRow("special_bonds: { coul: [0, 0, 0] }\n")),
            "test.yaml:9:18: unknown key 'coul' in special_bonds (expected one of: lj)\n"
            "test.yaml:9:16: special_bonds.lj: is missing (expected three weights [w12, w13, "
            "w14] of the pairs one, two and three bonds apart, each from 0 to 1)");
}

}  // namespace
}  // namespace pdyn
