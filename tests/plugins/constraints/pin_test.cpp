// The pin constraint plugin (C = x_i - (p + u (t - t0)), three rows per
// particle):
//  - C, J, c_t and b of a moving pin at a state worked out by hand, and the
//    default points (C = 0 where the scene starts);
//  - points given one for all and one per id;
//  - J, J v + c_t and b against differences of C at a random state;
//  - a pin added to a running system holds the particle where it is then;
//  - each bad parameter's located message.
#include <gtest/gtest.h>

#include "plugins/constraints/constraint_support.hpp"
#include "plugins/forces/force_support.hpp"

namespace pdyn {
namespace pin_test {

const char* kTwoParticles = R"(simulation: { dt: 0.01, steps: 1 }
particles:
  - { position: [1, 2, 3], velocity: [0.5, -1, 2], mass: 1 }
  - { position: [4, 5, 6], mass: 1 }
constraints:
)";

// Particle 0 pinned where it starts, the point moving at u = (0.1, 0.2,
// 0.3) m/s: C = 0 at t = 0; at t = 2 s with the particle not moved, C = -2 u
// = (-0.2, -0.4, -0.6) m, c_t = -u, b = 0, J = e_x, e_y, e_z, and Cdot =
// v - u = (0.4, -1.2, 1.7) m/s.
TEST(PinConstraint, AMovingPinWorkedOutByHand) {
  Scene scene = test::load_text(std::string(kTwoParticles) +
                                "  - { type: pin, ids: [0], velocity: [0.1, 0.2, 0.3] }\n");
  System& sys = *scene.system;
  const Constraint& c = test::ConstraintOf(scene);
  const ConstraintPattern pattern = c.pattern();
  EXPECT_EQ(pattern.row_begin, (std::vector<Index>{0, 1, 2, 3}));
  EXPECT_EQ(pattern.particle, (std::vector<Index>{0, 0, 0}));
  EXPECT_EQ(test::EvaluateAt(c, sys).value, Eigen::Vector3d::Zero()) << "at the start";
  sys.set_time(2.0);
  const ConstraintValues v = test::EvaluateAt(c, sys);
  EXPECT_NEAR(test::MaxDifference(v.value, Eigen::Vector3d(-0.2, -0.4, -0.6)), 0.0, 1e-15);
  EXPECT_EQ(v.rate, Eigen::Vector3d(-0.1, -0.2, -0.3));
  EXPECT_EQ(v.bias, Eigen::Vector3d::Zero());
  EXPECT_EQ(Eigen::Matrix3d(v.jacobian), Eigen::Matrix3d::Identity());
  const Eigen::VectorXd cdot =
      test::DenseJacobian(c, v, sys.size()) * test::Stacked(sys.velocities()) + v.rate;
  EXPECT_NEAR(test::MaxDifference(cdot, Eigen::Vector3d(0.4, -1.2, 1.7)), 0.0, 1e-15);
}

// One point for all ids, or one per id; a still pin (no velocity) has c_t = 0.
TEST(PinConstraint, PointsOneForAllOrOnePerId) {
  Scene all = test::load_text(std::string(kTwoParticles) +
                              "  - { type: pin, ids: [1, 0], points: [[1, 1, 1]] }\n");
  const ConstraintValues a = test::EvaluateAt(test::ConstraintOf(all), *all.system);
  Eigen::VectorXd want(6);
  want << 3, 4, 5, 0, 1, 2;  // x_1 - p, then x_0 - p
  EXPECT_EQ(a.value, want);
  EXPECT_EQ(a.rate, Eigen::VectorXd::Zero(6));
  EXPECT_EQ(test::ConstraintOf(all).pattern().particle, (std::vector<Index>{1, 1, 1, 0, 0, 0}));
  Scene each = test::load_text(std::string(kTwoParticles) +
                               "  - { type: pin, ids: [0, 1], points: [[0, 0, 0], [4, 5, 7]] }\n");
  want << 1, 2, 3, 0, 0, -1;
  EXPECT_EQ(test::EvaluateAt(test::ConstraintOf(each), *each.system).value, want);
}

// At a random state and time: J = dC/dx, J v + c_t = dC/dt along the
// motion (the point moving too), b = 0 = d2C/dt2.
TEST(PinConstraint, JacobianRateAndBiasAreTheDerivativesOfC) {
  const test::Cloud cloud(4, 5);
  Scene scene = test::load_text(cloud.Yaml() +
                                "constraints:\n  - { type: pin, ids: [2, 0], points: [[0.1, 0.2, "
                                "0.3], [-0.5, 0, 1]], velocity: [1.5, -0.5, 0.25] }\n");
  scene.system->set_time(0.7);
  const ConstraintValues v = test::ExpectDerivativesOfC(test::ConstraintOf(scene), *scene.system);
  EXPECT_GT(v.value.cwiseAbs().minCoeff(), 1e-3) << "a state off the constraint";
}

// Added to a system at t0 = 1.5 s (pdyn::add_plugin, as a program running
// the simulation does), a pin without points holds each particle where it
// is then: C = 0 at t0, and the point has moved by u (t - t0) at t = 2 s.
TEST(PinConstraint, APinAddedWhileRunningStartsWhereTheParticleIs) {
  Scene scene = test::load_text(std::string(kTwoParticles) + "  []\n");
  System& sys = *scene.system;
  sys.set_time(1.5);
  sys.positions().col(1) = Vec3(-1, 0.5, 2);
  add_plugin(scene, test::shipped_plugins(), PluginKind::Constraint,
             "{type: pin, ids: [1], velocity: [2, 0, -4]}", "pin_test");
  const Constraint& c = test::ConstraintOf(scene);
  EXPECT_EQ(test::EvaluateAt(c, sys).value, Eigen::Vector3d::Zero());
  sys.set_time(2.0);
  EXPECT_EQ(test::EvaluateAt(c, sys).value, Eigen::Vector3d(-1, 0, 2));
}

std::string Problems(const std::string& entry) {
  return test::load_problems(std::string(kTwoParticles) + "  - " + entry + "\n");
}

TEST(PinConstraint, BadParametersAreRefusedWithTheirPlace) {
  EXPECT_EQ(Problems("{ type: pin, ids: [0, 1, 0] }"),
            "test.yaml:6:30: constraints[0].ids[2]: particle 0 is pinned twice (expected each id "
            "once)");
  EXPECT_EQ(Problems("{ type: pin, ids: [0, 1], points: [[0, 0, 0], [1, 1, 1], [2, 2, 2]] }"),
            "test.yaml:6:39: constraints[0].points: has 3 points for 2 ids (expected 1 point for "
            "all, or 2)");
  EXPECT_EQ(Problems("{ type: pin, ids: [] }"),
            "test.yaml:6:23: constraints[0].ids: is empty (expected at least one particle)");
  EXPECT_EQ(Problems("{ type: pin, ids: [2] }"),
            "test.yaml:6:24: constraints[0].ids[0]: particle index 2 is out of range (expected "
            "0..1: the scene has 2 particles)");
}

}  // namespace pin_test
}  // namespace pdyn
