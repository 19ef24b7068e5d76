// Selections (pdyn/selection.hpp): `group:` and `ids:` on per-particle
// forces. Gravity on a group moves only that group; on ids only those; with
// neither, every particle, bit-identically to before selections existed
// (f = m g computed the same way); both keys, an unknown group, repeated ids
// are refused at the offending key.
#include <gtest/gtest.h>

#include "pdyn/host/scene.hpp"
#include "plugins/forces/force_support.hpp"

namespace pdyn {
namespace {

const std::string kSelectionParticles = R"(simulation: { dt: 0.01, steps: 1 }
particles:
  - { position: [5, 0, 1], mass: 2 }
  - grid: { origin: [0, 0, 1], u: [0.1, 0, 0], v: [0, 0.1, 0], nx: 3, ny: 2, mass: 0.5, name: cloud }
  - { position: [6, 0, 1], mass: 1 }
forces:
)";

std::string SelectionMessage(const std::string& yaml) {
  try {
    test::load_text(yaml);
  } catch (const SceneError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(Selection, GravityOnAGroupMovesOnlyThatGroup) {
  Scene scene = test::load_text(kSelectionParticles + "  - { type: gravity, group: cloud }\n");
  // The group's potential only: 6 particles of 0.5 kg at z = 1 m.
  EXPECT_NEAR(scene.system->potential_energy(), 6 * 0.5 * 9.81 * 1.0, 1e-12);
  for (int s = 1; s <= 10; ++s) test::TakeStep(scene, s, 0.01);
  const auto& x = scene.system->positions();
  EXPECT_EQ(x(2, 0), 1.0);
  EXPECT_EQ(x(2, 7), 1.0);
  // rk4 is exact for constant acceleration: z = 1 - g t^2 / 2 at t = 0.1 s.
  for (Index i = 1; i <= 6; ++i) EXPECT_NEAR(x(2, i), 1.0 - 0.5 * 9.81 * 0.01, 1e-12) << i;
}

TEST(Selection, IdsSelectExactlyThoseParticles) {
  Scene scene = test::load_text(kSelectionParticles + "  - { type: drag, k: 1, ids: [0, 7] }\n" +
                                "  - { type: gravity, ids: [7] }\n");
  const Matrix3X g = test::ForcesOf(*scene.system, 1);
  EXPECT_EQ(Vec3(g.col(7)), Vec3(0, 0, -9.81));
  EXPECT_EQ(g.leftCols(7), Matrix3X::Zero(3, 7));
  EXPECT_NEAR(*scene.system->force_objects().at(1).force->potential_energy(scene.system->view()),
              9.81, 1e-15);
}

// A pair force on a group: only pairs of two members interact (the
// selection's mask, Selection::mask), others feel nothing.
TEST(Selection, APairForceOnAGroupJoinsOnlyItsMembers) {
  Scene scene =
      test::load_text(kSelectionParticles +
                      "  - { type: lennard_jones, sigma: 0.1, cutoff: 0.25, group: cloud }\n");
  const Matrix3X f = test::ForcesOf(*scene.system, 0);
  EXPECT_EQ(Vec3(f.col(0)), Vec3::Zero());
  EXPECT_EQ(Vec3(f.col(7)), Vec3::Zero());
  EXPECT_GT(f.middleCols(1, 6).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_LT(f.middleCols(1, 6).rowwise().sum().norm(),
            1e-12);  // Newton's third law within the group
}

TEST(Selection, WithoutGroupOrIdsEveryParticleAsBefore) {
  Scene scene =
      test::load_text(kSelectionParticles + "  - { type: gravity, g: [0.1, -0.2, -9.81] }\n");
  const System& sys = *scene.system;
  const Matrix3X f = test::ForcesOf(sys, 0);
  const Vec3 g(0.1, -0.2, -9.81);
  EXPECT_EQ(f, Matrix3X(g * sys.masses().transpose()));
}

TEST(Selection, RefusesBothKeysUnknownGroupsAndRepeatedIds) {
  EXPECT_NE(
      SelectionMessage(kSelectionParticles + "  - { type: gravity, group: cloud, ids: [0] }\n")
          .find("test.yaml:7:41: forces[0].ids: both 'group' and 'ids' are given (expected "
                "at most one of them)"),
      std::string::npos);
  EXPECT_EQ(SelectionMessage(kSelectionParticles + "  - { type: drag, group: clowd }\n"),
            "test.yaml:7:26: forces[0].group: unknown group 'clowd' (did you mean 'cloud'? "
            "expected one of: cloud)");
  EXPECT_EQ(SelectionMessage(kSelectionParticles + "  - { type: drag, ids: [0, 7, 0] }\n"),
            "test.yaml:7:31: forces[0].ids[2]: particle 0 is listed twice (expected each id once)");
  EXPECT_NE(
      SelectionMessage("simulation: { dt: 0.01, steps: 1 }\nparticles:\n  - { position: [0, 0, 0], "
                       "mass: 1 }\nforces:\n  - { type: gravity, group: cloud }\n")
          .find("the scene defines none"),
      std::string::npos);
}

}  // namespace
}  // namespace pdyn
