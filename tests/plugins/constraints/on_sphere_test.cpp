// The on_sphere constraint plugin (C = |x - c| - R):
//  - C, J, c_t and b at a state worked out by hand, with a given radius;
//  - the default radii: each particle's initial distance from the centre
//    (C = 0 where the scene starts);
//  - J, J v + c_t and b against differences of C at a random state;
//  - a particle at the centre gives finite values;
//  - each bad parameter's located message.
#include <gtest/gtest.h>

#include "plugins/constraints/constraint_support.hpp"
#include "plugins/forces/force_support.hpp"

namespace pdyn {
namespace on_sphere_test {

// c = (1, 1, 1), x = c + (0, 3, 4): r = 5 m, u = (0, 0.6, 0.8). R = 4 m:
// C = 1 m. v = (2, 0, 5) m/s: u.v = 4 m/s = Cdot, |v|^2 = 29, b = (29 -
// 16) / 5 = 2.6 m/s^2.
const char* kParticles = R"(simulation: { dt: 0.01, steps: 1 }
particles:
  - { position: [1, 4, 5], velocity: [2, 0, 5], mass: 1 }
  - { position: [0, 1, 1], velocity: [0, 1, 0], mass: 1 }
constraints:
)";

TEST(OnSphereConstraint, ValuesAtAStateWorkedOutByHand) {
  Scene scene =
      test::load_text(std::string(kParticles) +
                      "  - { type: on_sphere, ids: [0], center: [1, 1, 1], radius: 4 }\n");
  const Constraint& c = test::ConstraintOf(scene);
  EXPECT_EQ(c.pattern().row_begin, (std::vector<Index>{0, 1}));
  EXPECT_EQ(c.pattern().particle, (std::vector<Index>{0}));
  const ConstraintValues v = test::EvaluateAt(c, *scene.system);
  EXPECT_EQ(v.value[0], 1.0);
  EXPECT_EQ(v.rate[0], 0.0);
  EXPECT_NEAR(v.bias[0], 2.6, 1e-15);
  EXPECT_NEAR((Vec3(v.jacobian.col(0)) - Vec3(0, 0.6, 0.8)).norm(), 0.0, 1e-16);
  const Eigen::VectorXd cdot =
      test::DenseJacobian(c, v, scene.system->size()) * test::Stacked(scene.system->velocities());
  EXPECT_NEAR(cdot[0], 4.0, 1e-15);
}

// With no radius each particle keeps its initial distance from the centre
// (5 m and 1 m): C = 0 for both; the particle moving along the sphere
// (particle 1 at 1 m from c, moving at 1 m/s across the radius) has b =
// v^2 / r = 1 m/s^2.
TEST(OnSphereConstraint, DefaultRadiiAreTheInitialDistances) {
  Scene scene = test::load_text(std::string(kParticles) +
                                "  - { type: on_sphere, ids: [1, 0], center: [1, 1, 1] }\n");
  const ConstraintValues v = test::EvaluateAt(test::ConstraintOf(scene), *scene.system);
  EXPECT_EQ(v.value, Eigen::Vector2d::Zero());
  EXPECT_EQ(v.bias[0], 1.0);
  EXPECT_EQ(Vec3(v.jacobian.col(0)), Vec3(-1, 0, 0));
}

// At a random state (radius 0.8 m about (0.1, -0.2, 0.3)): J = dC/dx,
// J v + c_t = dC/dt along the motion, b = d2C/dt2.
TEST(OnSphereConstraint, JacobianRateAndBiasAreTheDerivativesOfC) {
  const test::Cloud cloud(5, 17);
  Scene scene = test::load_text(cloud.Yaml() +
                                "constraints:\n  - { type: on_sphere, ids: [4, 2, 0, 1], center: "
                                "[0.1, -0.2, 0.3], radius: 0.8 }\n");
  const ConstraintValues v = test::ExpectDerivativesOfC(test::ConstraintOf(scene), *scene.system);
  EXPECT_GT(v.value.cwiseAbs().minCoeff(), 1e-3) << "a state off the constraint";
  EXPECT_GT(v.bias.minCoeff(), 1e-3) << "every particle moving across its radius";
}

// At the centre the radial direction is undefined: with a given radius,
// C = -R, J = 0 and b = 0, all finite.
TEST(OnSphereConstraint, AParticleAtTheCentreGivesFiniteValues) {
  Scene scene =
      test::load_text(std::string(kParticles) +
                      "  - { type: on_sphere, ids: [1], center: [0, 1, 1], radius: 2 }\n");
  const ConstraintValues v = test::EvaluateAt(test::ConstraintOf(scene), *scene.system);
  EXPECT_EQ(v.value[0], -2.0);
  EXPECT_EQ(v.bias[0], 0.0);
  EXPECT_EQ(Vec3(v.jacobian.col(0)), Vec3::Zero());
}

std::string Problems(const std::string& entry) {
  return test::load_problems(std::string(kParticles) + "  - " + entry + "\n");
}

TEST(OnSphereConstraint, BadParametersAreRefusedWithTheirPlace) {
  EXPECT_EQ(Problems("{ type: on_sphere, ids: [0, 1], center: [0, 1, 1] }"),
            "test.yaml:6:33: constraints[0].ids[1]: particle 1 is at the sphere's centre (expected "
            "it away from center: the radius is its initial distance from the centre)");
  EXPECT_EQ(Problems("{ type: on_sphere, ids: [1, 1] }"),
            "test.yaml:6:33: constraints[0].ids[1]: particle 1 is listed twice (expected each id "
            "once)");
  EXPECT_EQ(Problems("{ type: on_sphere, ids: [] }"),
            "test.yaml:6:29: constraints[0].ids: is empty (expected at least one particle)");
  EXPECT_EQ(Problems("{ type: on_sphere, ids: [0], radius: -1 }"),
            "test.yaml:6:42: constraints[0].radius: -1 is out of range (expected a number > 0 in "
            "m)");
  EXPECT_EQ(Problems("{ type: on_sphere, ids: [0], radius: 0 }"),
            "test.yaml:6:42: constraints[0].radius: 0 is out of range (expected a number > 0 in "
            "m)");
}

}  // namespace on_sphere_test
}  // namespace pdyn
