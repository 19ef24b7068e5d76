// The distance constraint plugin (rigid rods, C = |x_i - x_j| - L):
//  - C, J, c_t and b at a state worked out by hand;
//  - the default lengths are the initial distances (C = 0 where the scene
//    starts); one length for all, or one per pair;
//  - J against central differences of C and b against C's second
//    derivative along x + v t, at a random state off the constraint;
//  - coincident ends give finite values; a rod across a periodic box's face;
//  - each bad parameter's located message.
#include <gtest/gtest.h>

#include "plugins/constraints/constraint_support.hpp"
#include "plugins/forces/force_support.hpp"

namespace pdyn {
namespace distance_test {

const char* kHeader = "simulation: { dt: 0.01, steps: 1 }\n";

// x_0 = 0, x_1 = (3, 4, 0) m: d = x_0 - x_1 = (-3, -4, 0), |d| = 5 m, n =
// (-0.6, -0.8, 0). L = 4 m: C = 1 m. w = v_0 - v_1 = (-1, 0, -2) m/s:
// n.w = 0.6 m/s = Cdot, |w|^2 = 5, b = (5 - 0.36) / 5 = 0.928 m/s^2.
TEST(DistanceConstraint, ValuesAtAStateWorkedOutByHand) {
  Scene scene = test::load_text(std::string(kHeader) + R"(particles:
  - { position: [0, 0, 0], mass: 1 }
  - { position: [3, 4, 0], velocity: [1, 0, 2], mass: 1 }
constraints:
  - { type: distance, pairs: [[0, 1]], length: 4 }
)");
  const Constraint& c = test::ConstraintOf(scene);
  const ConstraintPattern pattern = c.pattern();
  EXPECT_EQ(pattern.row_begin, (std::vector<Index>{0, 2}));
  EXPECT_EQ(pattern.particle, (std::vector<Index>{0, 1}));
  const ConstraintValues v = test::EvaluateAt(c, *scene.system);
  EXPECT_NEAR(v.value[0], 1.0, 1e-15);
  EXPECT_EQ(v.rate[0], 0.0);
  EXPECT_NEAR(v.bias[0], 0.928, 1e-15);
  EXPECT_NEAR((Vec3(v.jacobian.col(0)) - Vec3(-0.6, -0.8, 0)).norm(), 0.0, 1e-15);
  EXPECT_NEAR((Vec3(v.jacobian.col(1)) - Vec3(0.6, 0.8, 0)).norm(), 0.0, 1e-15);
  const Eigen::VectorXd cdot =
      test::DenseJacobian(c, v, 2) * test::Stacked(scene.system->velocities());
  EXPECT_NEAR(cdot[0], 0.6, 1e-15);
}

// Three particles at distances 1 m and 2 m: with no `length`, C = 0 exactly
// at the start; `length: 0.5` is one length for all, [1.5, 1] one per pair.
TEST(DistanceConstraint, DefaultLengthsAreTheInitialDistances) {
  const std::string particles = std::string(kHeader) + R"(particles:
  - { position: [0, 0, 1], mass: 1 }
  - { position: [0.6, 0.8, 1], mass: 1 }
  - { position: [0.6, 0.8, 3], mass: 1 }
constraints:
)";
  Scene defaults = test::load_text(particles + "  - { type: distance, pairs: [[0, 1], [1, 2]] }\n");
  EXPECT_EQ(test::EvaluateAt(test::ConstraintOf(defaults), *defaults.system).value,
            Eigen::Vector2d::Zero());
  Scene one =
      test::load_text(particles + "  - { type: distance, pairs: [[0, 1], [1, 2]], length: 0.5 }\n");
  EXPECT_NEAR(test::MaxDifference(test::EvaluateAt(test::ConstraintOf(one), *one.system).value,
                                  Eigen::Vector2d(0.5, 1.5)),
              0.0, 1e-15);
  Scene each = test::load_text(
      particles + "  - { type: distance, pairs: [[0, 1], [1, 2]], length: [1.5, 1] }\n");
  EXPECT_NEAR(test::MaxDifference(test::EvaluateAt(test::ConstraintOf(each), *each.system).value,
                                  Eigen::Vector2d(-0.5, 1.0)),
              0.0, 1e-15);
}

// At a random state (lengths 0.7 m, so C != 0): J is the derivative of C,
// J v + c_t its rate along the motion, and b its second derivative along
// x + v t (no acceleration).
TEST(DistanceConstraint, JacobianAndBiasAreTheDerivativesOfC) {
  const test::Cloud cloud(5, 11);
  Scene scene = test::load_text(
      cloud.Yaml() +
      "constraints:\n  - { type: distance, pairs: [[0, 1], [1, 2], [3, 1], [4, 0]], length: 0.7 "
      "}\n");
  const ConstraintValues v = test::ExpectDerivativesOfC(test::ConstraintOf(scene), *scene.system);
  EXPECT_GT(v.value.cwiseAbs().minCoeff(), 1e-3) << "a state off the constraint";
  EXPECT_GT(v.bias.cwiseAbs().minCoeff(), 0.05) << "every rod turning: b is not trivially 0";
}

// Coincident ends have no direction: C = -L, J = 0 and b = 0, all finite.
TEST(DistanceConstraint, CoincidentEndsGiveFiniteValues) {
  Scene scene = test::load_text(std::string(kHeader) + R"(particles:
  - { position: [1, 2, 3], velocity: [1, 0, 0], mass: 1 }
  - { position: [1, 2, 3], velocity: [0, 2, 0], mass: 1 }
constraints:
  - { type: distance, pairs: [[0, 1]], length: 0.25 }
)");
  const ConstraintValues v = test::EvaluateAt(test::ConstraintOf(scene), *scene.system);
  EXPECT_EQ(v.value[0], -0.25);
  EXPECT_EQ(v.rate[0], 0.0);
  EXPECT_EQ(v.bias[0], 0.0);
  EXPECT_EQ(v.jacobian, Matrix3X::Zero(3, 2));
}

// Along a periodic x axis of 10 m, particles at x = 0.5 and 9.5 m are 1 m
// apart through the face: the default length is 1 m and n = +x (x_0 - x_1
// = +1 m to the nearest image), not the 9 m across the box.
TEST(DistanceConstraint, ARodAcrossAPeriodicFaceMeasuresTheNearestImage) {
  Scene scene = test::load_text(R"(simulation:
  dt: 0.01
  steps: 1
  box: { min: [0, 0, 0], max: [10, 10, 10], periodic: [true, false, false] }
particles:
  - { position: [0.5, 5, 5], mass: 1 }
  - { position: [9.5, 5, 5], mass: 1 }
constraints:
  - { type: distance, pairs: [[0, 1]] }
)");
  System& sys = *scene.system;
  const Constraint& c = test::ConstraintOf(scene);
  EXPECT_EQ(test::EvaluateAt(c, sys).value[0], 0.0);
  sys.positions()(0, 0) = 0.75;  // 1.25 m from the other end's image
  const ConstraintValues v = test::EvaluateAt(c, sys);
  EXPECT_NEAR(v.value[0], 0.25, 1e-15);
  EXPECT_EQ(Vec3(v.jacobian.col(0)), Vec3(1, 0, 0));
  EXPECT_EQ(Vec3(v.jacobian.col(1)), Vec3(-1, 0, 0));
}

std::string Problems(const std::string& entry) {
  return test::load_problems(std::string(kHeader) + R"(particles:
  - { position: [0, 0, 0], mass: 1 }
  - { position: [1, 0, 0], mass: 1 }
  - { position: [1, 1, 0], mass: 1 }
constraints:
  - )" + entry + "\n");
}

TEST(DistanceConstraint, BadParametersAreRefusedWithTheirPlace) {
  EXPECT_EQ(Problems("{ type: distance, pairs: [[0, 1], [2, 2]] }"),
            "test.yaml:7:39: constraints[0].pairs[1]: joins particle 2 to itself (expected two "
            "different particles)");
  EXPECT_EQ(Problems("{ type: distance, pairs: [[0, 1], [1, 2], [1, 0]] }"),
            "test.yaml:7:47: constraints[0].pairs[2]: joins particles 1 and 0 a second time "
            "(expected each rod once)");
  EXPECT_EQ(Problems("{ type: distance, pairs: [[0, 1], [1, 2]], length: [1, 2, 3] }"),
            "test.yaml:7:56: constraints[0].length: has 3 values for 2 pairs (expected 1 value "
            "for all, or 2)");
  EXPECT_EQ(Problems("{ type: distance, pairs: [[0, 1], [1, 2]], length: [1, -0.5] }"),
            "test.yaml:7:60: constraints[0].length[1]: -0.5 is out of range (expected a number >= "
            "0 in m)");
  EXPECT_EQ(Problems("{ type: distance, pairs: [] }"),
            "test.yaml:7:30: constraints[0].pairs: is empty (expected at least one pair)");
  EXPECT_EQ(
      Problems("{ type: distance, pairs: [[0, 3]] }"),
      "test.yaml:7:35: constraints[0].pairs[0][1]: particle index 3 is out of range (expected "
      "0..2: the scene has 3 particles)");
}

}  // namespace distance_test
}  // namespace pdyn
