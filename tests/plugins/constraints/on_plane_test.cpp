// The on_plane constraint plugin (C = n.x_i - d, n the unit normal):
//  - C, J, c_t and b with a given offset, worked out by hand;
//  - the default offsets: each particle on the plane through its start
//    (C = 0 there), with a normal that is not a unit vector;
//  - J, J v + c_t and b against differences of C at a random state;
//  - each bad parameter's located message.
#include <gtest/gtest.h>

#include "plugins/constraints/constraint_support.hpp"
#include "plugins/forces/force_support.hpp"

namespace pdyn {
namespace on_plane_test {

const char* kParticles = R"(simulation: { dt: 0.01, steps: 1 }
particles:
  - { position: [1, 2, 3], velocity: [1, -2, 0.5], mass: 1 }
  - { position: [-1, 0.5, 0], mass: 1 }
constraints:
)";

// normal [0, 0, 2] is n = +z; the plane z = 2.5: C = 3 - 2.5 = 0.5 m for
// particle 0 and -2.5 m for particle 1; J = n, b = 0, c_t = 0; Cdot = n.v
// = 0.5 m/s.
TEST(OnPlaneConstraint, ValuesWithAGivenOffsetWorkedOutByHand) {
  Scene scene = test::load_text(std::string(kParticles) +
                                "  - { type: on_plane, ids: [0, 1], normal: [0, 0, 2], offset: "
                                "2.5 }\n");
  const Constraint& c = test::ConstraintOf(scene);
  EXPECT_EQ(c.pattern().row_begin, (std::vector<Index>{0, 1, 2}));
  EXPECT_EQ(c.pattern().particle, (std::vector<Index>{0, 1}));
  const ConstraintValues v = test::EvaluateAt(c, *scene.system);
  EXPECT_EQ(v.value, Eigen::Vector2d(0.5, -2.5));
  EXPECT_EQ(v.rate, Eigen::Vector2d::Zero());
  EXPECT_EQ(v.bias, Eigen::Vector2d::Zero());
  EXPECT_EQ(Vec3(v.jacobian.col(0)), Vec3(0, 0, 1));
  EXPECT_EQ(Vec3(v.jacobian.col(1)), Vec3(0, 0, 1));
  const Eigen::VectorXd cdot =
      test::DenseJacobian(c, v, scene.system->size()) * test::Stacked(scene.system->velocities());
  EXPECT_EQ(cdot[0], 0.5);
}

// With no offset each particle keeps to the plane through its start: C = 0
// there for both, although n.x differs (3/sqrt(2) and -1/(2 sqrt(2)) m for
// n = (1, 1, 0)/sqrt(2)). Moving particle 0 by 0.3 m along n gives C = 0.3 m;
// moving it within the plane gives C = 0.
TEST(OnPlaneConstraint, DefaultOffsetsAreEachParticlesPlaneAtTheStart) {
  Scene scene = test::load_text(std::string(kParticles) +
                                "  - { type: on_plane, ids: [0, 1], normal: [1, 1, 0] }\n");
  System& sys = *scene.system;
  const Constraint& c = test::ConstraintOf(scene);
  const ConstraintValues v = test::EvaluateAt(c, sys);
  EXPECT_EQ(v.value, Eigen::Vector2d::Zero());
  const Vec3 n = Vec3(1, 1, 0) / std::sqrt(2.0);
  EXPECT_NEAR((Vec3(v.jacobian.col(0)) - n).norm(), 0.0, 1e-16);
  sys.positions().col(0) += 0.3 * n;
  EXPECT_NEAR(test::EvaluateAt(c, sys).value[0], 0.3, 1e-15);
  sys.positions().col(0) += Vec3(2, -2, 7);  // within the plane
  EXPECT_NEAR(test::EvaluateAt(c, sys).value[0], 0.3, 1e-15);
}

// At a random state: J = dC/dx, J v + c_t = dC/dt along the motion, b = 0.
TEST(OnPlaneConstraint, JacobianRateAndBiasAreTheDerivativesOfC) {
  const test::Cloud cloud(4, 7);
  Scene scene = test::load_text(cloud.Yaml() +
                                "constraints:\n  - { type: on_plane, ids: [3, 1, 0], normal: "
                                "[0.3, -1, 2], offset: 0.4 }\n");
  const ConstraintValues v = test::ExpectDerivativesOfC(test::ConstraintOf(scene), *scene.system);
  EXPECT_GT(v.value.cwiseAbs().minCoeff(), 1e-3) << "a state off the constraint";
}

std::string Problems(const std::string& entry) {
  return test::load_problems(std::string(kParticles) + "  - " + entry + "\n");
}

TEST(OnPlaneConstraint, BadParametersAreRefusedWithTheirPlace) {
  EXPECT_EQ(Problems("{ type: on_plane, ids: [1, 0, 1], normal: [0, 0, 1] }"),
            "test.yaml:6:35: constraints[0].ids[2]: particle 1 is listed twice (expected each "
            "id once)");
  EXPECT_EQ(Problems("{ type: on_plane, ids: [], normal: [0, 0, 1] }"),
            "test.yaml:6:28: constraints[0].ids: is empty (expected at least one particle)");
  EXPECT_EQ(Problems("{ type: on_plane, ids: [0], normal: [0, 0, 0] }"),
            "test.yaml:6:41: constraints[0].normal: is the zero vector (expected a vector [x, y, "
            "z], not zero)");
  EXPECT_EQ(Problems("{ type: on_plane, ids: [0] }"),
            "test.yaml:6:5: constraints[0]: missing required key 'normal' (expected a vector [x, "
            "y, z], not zero: the plane's normal (normalised))");
}

}  // namespace on_plane_test
}  // namespace pdyn
