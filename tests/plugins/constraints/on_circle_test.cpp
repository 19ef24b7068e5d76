// The on_circle constraint plugin, Witkin's bead on a wire (C1 = n.(x - c),
// C2 = |P (x - c)| - R, two rows per bead):
//  - a bead at 30 degrees on a circle of radius 2 m moving along the wire
//    at 3 m/s: C = 0 (the default radius), J = n and the unit radial, b2 =
//    v^2 / R = 4.5 m/s^2; velocity along the normal or the radius leaves b2
//    as it is; a given radius;
//  - J, J v + c_t and b against differences of C, at a random state off a
//    tilted wire;
//  - a bead off the circle's plane, within rounding and beyond;
//  - each bad parameter's located message.
#include <gtest/gtest.h>

#include <cmath>

#include "plugins/constraints/constraint_support.hpp"
#include "plugins/forces/force_support.hpp"

namespace pdyn {
namespace on_circle_test {

// Centre c = (1, -1, 0.5), normal +z; the bead at c + 2 (cos 30, sin 30, 0)
// = (1 + sqrt 3, 0, 0.5) m with velocity 3 (-sin 30, cos 30, 0) m/s.
const char* kBead = R"(simulation: { dt: 0.01, steps: 1 }
particles:
  - { position: [2.7320508075688772, 0, 0.5], velocity: [-1.5, 2.598076211353316, 0], mass: 1 }
constraints:
)";

TEST(OnCircleConstraint, WitkinsBeadWorkedOutByHand) {
  Scene scene = test::load_text(std::string(kBead) +
                                "  - { type: on_circle, ids: [0], center: [1, -1, 0.5] }\n");
  System& sys = *scene.system;
  const Constraint& c = test::ConstraintOf(scene);
  EXPECT_EQ(c.pattern().row_begin, (std::vector<Index>{0, 1, 2}));
  EXPECT_EQ(c.pattern().particle, (std::vector<Index>{0, 0}));
  ConstraintValues v = test::EvaluateAt(c, sys);
  EXPECT_EQ(v.value, Eigen::Vector2d::Zero()) << "on the wire: the default radius is 2 m";
  EXPECT_EQ(v.rate, Eigen::Vector2d::Zero());
  EXPECT_EQ(v.bias[0], 0.0);
  EXPECT_NEAR(v.bias[1], 4.5, 1e-14) << "v^2 / R";
  EXPECT_EQ(Vec3(v.jacobian.col(0)), Vec3(0, 0, 1));
  EXPECT_NEAR((Vec3(v.jacobian.col(1)) - Vec3(std::sqrt(3.0) / 2, 0.5, 0)).norm(), 0.0, 1e-15);
  // Adding 1.5 m/s along the normal and 0.7 m/s along the radius: P v
  // keeps the 3 m/s along the wire, whose centripetal term alone is b2.
  sys.velocities().col(0) += Vec3(0, 0, 1.5) + 0.7 * Vec3(std::sqrt(3.0) / 2, 0.5, 0);
  v = test::EvaluateAt(c, sys);
  EXPECT_NEAR(v.bias[1], 4.5, 1e-14);
  EXPECT_EQ(v.bias[0], 0.0);
}

TEST(OnCircleConstraint, AGivenRadius) {
  Scene scene = test::load_text(std::string(kBead) +
                                "  - { type: on_circle, ids: [0], center: [1, -1, 0.5], radius: "
                                "2.5 }\n");
  const ConstraintValues v = test::EvaluateAt(test::ConstraintOf(scene), *scene.system);
  EXPECT_EQ(v.value[0], 0.0);
  EXPECT_NEAR(v.value[1], -0.5, 1e-15);
  EXPECT_NEAR(v.bias[1], 4.5, 1e-14) << "b2 = v_t^2 / rho, rho = 2 m where the bead is";
}

// Three beads on a tilted wire (normal (0, 1, 1), centre (0.2, 0, 0)), then
// moved to a random state off it: J = dC/dx, J v + c_t = dC/dt along the
// motion and b = d2C/dt2 for both rows of every bead.
TEST(OnCircleConstraint, JacobianRateAndBiasAreTheDerivativesOfC) {
  Scene scene = test::load_text(R"(simulation: { dt: 0.01, steps: 1 }
particles:
  - { position: [1.2, 0, 0], mass: 1 }
  - { position: [0.2, 1, -1], mass: 1 }
  - { position: [-0.5, -0.5, 0.5], mass: 1 }
constraints:
  - { type: on_circle, ids: [0, 1, 2], center: [0.2, 0, 0], normal: [0, 1, 1] }
)");
  System& sys = *scene.system;
  const Constraint& c = test::ConstraintOf(scene);
  EXPECT_NEAR(test::EvaluateAt(c, sys).value.cwiseAbs().maxCoeff(), 0.0, 1e-15)
      << "the defaults put every bead on a circle of its own";
  const test::Cloud cloud(3, 23);
  for (Index i = 0; i < 3; ++i) {
    sys.positions().col(i) = cloud.x[static_cast<std::size_t>(i)];
    sys.velocities().col(i) = cloud.v[static_cast<std::size_t>(i)];
  }
  const ConstraintValues v = test::ExpectDerivativesOfC(c, sys);
  EXPECT_GT(v.value.cwiseAbs().minCoeff(), 1e-3) << "a state off the constraint";
  for (Index k = 0; k < 3; ++k) EXPECT_GT(v.bias[2 * k + 1], 0.05) << "bead " << k;
}

// On the axis the radial direction is undefined: with a given radius, a
// bead at the centre has C2 = -R, J2 = 0 and b2 = 0, all finite.
TEST(OnCircleConstraint, ABeadOnTheAxisGivesFiniteValues) {
  Scene scene = test::load_text(R"(simulation: { dt: 0.01, steps: 1 }
particles:
  - { position: [0, 0, 0], velocity: [1, 2, 0], mass: 1 }
constraints:
  - { type: on_circle, ids: [0], radius: 1.5 }
)");
  const ConstraintValues v = test::EvaluateAt(test::ConstraintOf(scene), *scene.system);
  EXPECT_EQ(v.value, Eigen::Vector2d(0, -1.5));
  EXPECT_EQ(v.bias, Eigen::Vector2d::Zero());
  EXPECT_EQ(Vec3(v.jacobian.col(1)), Vec3::Zero());
}

std::string Problems(const std::string& particle, const std::string& entry) {
  return test::load_problems(
      "simulation: { dt: 0.01, steps: 1 }\nparticles:\n"
      "  - { position: [2, 0, 0.5], mass: 1 }\n" +
      particle + "constraints:\n  - " + entry + "\n");
}

// The default plane row needs every bead in the plane: 1e-12 m off it (a
// rounding error of the scene) is let through and reported as C1, 0.25 m is
// refused.
TEST(OnCircleConstraint, BeadsMustStartInTheCirclesPlane) {
  Scene scene = test::load_text(R"(simulation: { dt: 0.01, steps: 1 }
particles:
  - { position: [2, 0, 0.500000000001], mass: 1 }
constraints:
  - { type: on_circle, ids: [0], center: [0, 0, 0.5] }
)");
  EXPECT_NEAR(test::EvaluateAt(test::ConstraintOf(scene), *scene.system).value[0], 1e-12, 1e-15);
  EXPECT_EQ(Problems("  - { position: [1, 1, 0.75], mass: 1 }\n",
                     "{ type: on_circle, ids: [0, 1], center: [0, 0, 0.5] }"),
            "test.yaml:6:33: constraints[0].ids[1]: particle 1 is not in the circle's plane: it "
            "is 0.25 m from it (expected it on the wire: n.(x - center) = 0, n the unit normal)");
}

// Without `center`, each bead's circle is about the axis through the
// origin along n, at the height of its start: beads at different heights
// and radii start with C = 0 and keep their own planes.
TEST(OnCircleConstraint, WithoutACentreEachBeadHasItsOwnCoaxialCircle) {
  Scene scene = test::load_text(R"(simulation: { dt: 0.01, steps: 1 }
particles:
  - { position: [2, 0, 0.7], mass: 1 }
  - { position: [0, -3, -1.5], mass: 1 }
constraints:
  - { type: on_circle, ids: [0, 1] }
)");
  System& sys = *scene.system;
  const ConstraintValues at_start = test::EvaluateAt(test::ConstraintOf(scene), sys);
  EXPECT_EQ(at_start.value, Eigen::Vector4d::Zero());
  sys.positions().col(0) = Vec3(0, 2.5, 0.9);  // 0.2 m above its plane, 0.5 m further out
  sys.positions().col(1) = Vec3(3, 0, -1.5);   // moved along its own circle
  const ConstraintValues moved = test::EvaluateAt(test::ConstraintOf(scene), sys);
  EXPECT_NEAR(moved.value[0], 0.2, 1e-15);
  EXPECT_NEAR(moved.value[1], 0.5, 1e-15);
  EXPECT_EQ(moved.value[2], 0.0);
  EXPECT_EQ(moved.value[3], 0.0);
}

TEST(OnCircleConstraint, BadParametersAreRefusedWithTheirPlace) {
  EXPECT_EQ(Problems("  - { position: [0, 0, 0.5], mass: 1 }\n",
                     "{ type: on_circle, ids: [0, 1], center: [0, 0, 0.5] }"),
            "test.yaml:6:33: constraints[0].ids[1]: particle 1 is at the circle's centre "
            "(expected it away from center: the radius is its initial distance from the centre)");
  EXPECT_EQ(Problems("", "{ type: on_circle, ids: [0, 0], center: [0, 0, 0.5] }"),
            "test.yaml:5:33: constraints[0].ids[1]: particle 0 is threaded on the wire twice "
            "(expected each id once)");
  EXPECT_EQ(Problems("", "{ type: on_circle, ids: [], center: [0, 0, 0.5] }"),
            "test.yaml:5:29: constraints[0].ids: is empty (expected at least one particle)");
  EXPECT_EQ(Problems("", "{ type: on_circle, ids: [0], normal: [0, 0, 0] }"),
            "test.yaml:5:42: constraints[0].normal: is the zero vector (expected a vector [x, y, "
            "z], not zero)");
  EXPECT_EQ(Problems("", "{ type: on_circle, ids: [0], radius: 0 }"),
            "test.yaml:5:42: constraints[0].radius: 0 is out of range (expected a number > 0 in "
            "m)");
}

}  // namespace on_circle_test
}  // namespace pdyn
