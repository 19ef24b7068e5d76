// The bending constraint plugin (C = phi - phi0 on each hinge's dihedral
// angle, pdyn/dihedral.hpp):
//  - a hinge opened to a right angle, worked out by hand: C, J, and b of a
//    hinge turning at a constant rate;
//  - the default rest angles are the initial ones (C = 0 where it starts);
//  - J against central differences of C and b (by automatic
//    differentiation) against C's second derivative along x + v t, at a
//    random state;
//  - a collinear hinge gives finite values and cannot act;
//  - each bad parameter's located message;
//  - the grid builder's `rods: { bending }` puts one on every hinge.
#include <gtest/gtest.h>

#include <numbers>

#include "plugins/constraints/constraint_support.hpp"
#include "plugins/forces/force_support.hpp"

namespace pdyn {
namespace bending_test {

const char* kHeader = "simulation: { dt: 0.01, steps: 1 }\n";

// The edge j-k along z (j at the origin, k at (0, 0, 1)), i at (1, 0, 0)
// and l at (0, 1, 0): the two planes at a right angle, phi = +-pi/2. l
// turns about the edge at 2 rad/s (v_l = (-2, 0, 0)): phi changes at
// 2 rad/s through J_l . v_l, and since l moves on the circle of radius 1
// about the edge, phi'' along x + v t is the second derivative of
// atan2-of-a-straight-line motion: at s, l = (-2 s, 1, 0), phi_l =
// atan2(1, -2 s) - so d2/ds2 at 0 is 0 and b = 0 exactly.
TEST(BendingConstraint, ARightAngledHingeWorkedOutByHand) {
  Scene scene = test::load_text(std::string(kHeader) + R"(particles:
  - { position: [1, 0, 0], mass: 1 }
  - { position: [0, 0, 0], mass: 1 }
  - { position: [0, 0, 1], mass: 1 }
  - { position: [0, 1, 0], velocity: [-2, 0, 0], mass: 1 }
constraints:
  - { type: bending, quads: [[0, 1, 2, 3]], rest: 3.141592653589793 }
)");
  const Constraint& c = test::ConstraintOf(scene);
  const ConstraintValues v = test::EvaluateAt(c, *scene.system);
  // F = x_i - x_j = (1,0,0), G = x_j - x_k = (0,0,-1), H = x_l - x_k = (0,1,-1):
  // A = F x G = (0,1,0), B = H x G = (-1,0,0): phi = atan2((B x A).G/|G|, A.B)
  // = atan2(((0,0,-1).(0,0,-1)), 0) = atan2(1, 0) = pi/2; C = pi/2 - pi.
  EXPECT_NEAR(v.value[0], -std::numbers::pi / 2, 1e-15);
  // dphi/dx_i = -|G|/|A|^2 A = (0,-1,0); dphi/dx_l = |G|/|B|^2 B = (-1,0,0).
  EXPECT_NEAR((Vec3(v.jacobian.col(0)) - Vec3(0, -1, 0)).norm(), 0.0, 1e-15);
  EXPECT_NEAR((Vec3(v.jacobian.col(3)) - Vec3(-1, 0, 0)).norm(), 0.0, 1e-15);
  EXPECT_EQ(v.rate[0], 0.0);
  const Eigen::VectorXd cdot =
      test::DenseJacobian(c, v, 4) * test::Stacked(scene.system->velocities());
  EXPECT_NEAR(cdot[0], 2.0, 1e-15);
  // Along x + v t, l = (-2t, 1, 0): B = (H x G) = (-1, -2t, 0)... phi(t) =
  // atan2(1, -2t) + const, whose second derivative at t = 0 is 0.
  EXPECT_NEAR(v.bias[0], 0.0, 1e-14);
}

TEST(BendingConstraint, DefaultRestAnglesAreTheInitialOnes) {
  const test::Cloud cloud(4, 7);
  Scene scene = test::load_text(cloud.Yaml() +
                                "constraints:\n  - { type: bending, quads: [[0, 1, 2, 3]] }\n");
  EXPECT_EQ(test::EvaluateAt(test::ConstraintOf(scene), *scene.system).value[0], 0.0);
}

TEST(BendingConstraint, JacobianAndBiasAreTheDerivativesOfC) {
  const test::Cloud cloud(6, 13);
  Scene scene = test::load_text(
      cloud.Yaml() +
      "constraints:\n  - { type: bending, quads: [[0, 1, 2, 3], [4, 2, 1, 5], [3, 1, 2, 5]], "
      "rest: 2.5 }\n");
  const ConstraintValues v = test::ExpectDerivativesOfC(test::ConstraintOf(scene), *scene.system);
  EXPECT_GT(v.value.cwiseAbs().minCoeff(), 1e-3) << "a state off the constraint";
  EXPECT_GT(v.bias.cwiseAbs().minCoeff(), 1e-3) << "every hinge turning: b is not trivially 0";
}

TEST(BendingConstraint, ACollinearHingeIsFiniteAndCannotAct) {
  Scene scene = test::load_text(std::string(kHeader) + R"(particles:
  - { position: [0, 0, 2], velocity: [1, 2, 3], mass: 1 }
  - { position: [0, 0, 0], mass: 1 }
  - { position: [0, 0, 1], mass: 1 }
  - { position: [0, 1, 0], mass: 1 }
constraints:
  - { type: bending, quads: [[0, 1, 2, 3]], rest: 1 }
)");
  const ConstraintValues v = test::EvaluateAt(test::ConstraintOf(scene), *scene.system);
  EXPECT_TRUE(std::isfinite(v.value[0]));
  EXPECT_EQ(v.jacobian, Matrix3X::Zero(3, 4));
  EXPECT_EQ(v.bias[0], 0.0);
}

TEST(BendingConstraint, BadParametersAreRefusedAtTheirKeys) {
  const std::string particles = std::string(kHeader) + R"(particles:
  - { position: [1, 0, 0], mass: 1 }
  - { position: [0, 0, 0], mass: 1 }
  - { position: [0, 0, 1], mass: 1 }
  - { position: [0, 1, 0], mass: 1 }
constraints:
)";
  EXPECT_EQ(test::load_problems(particles + "  - { type: bending, quads: [] }\n"),
            "test.yaml:8:29: constraints[0].quads: is empty (expected at least one quadruple)");
  EXPECT_EQ(test::load_problems(particles + "  - { type: bending, quads: [[0, 1, 2, 4]] }\n"),
            "test.yaml:8:40: constraints[0].quads[0][3]: particle index 4 is out of range "
            "(expected 0..3: the scene has 4 particles)");
  EXPECT_EQ(
      test::load_problems(particles + "  - { type: bending, quads: [[0, 1, 2, 3]], rest: 4 }\n"),
      "test.yaml:8:51: constraints[0].rest: 4 is out of range (expected a number in "
      "[-3.141592653589793, 3.141592653589793] in rad)");
}

TEST(BendingConstraint, TheGridBuildersRodsPutOneOnEveryHinge) {
  Scene scene = test::load_text(R"(simulation: { dt: 0.01, steps: 1, solver: { type: xpbd } }
particles:
  - grid: { origin: [0, 0, 0], u: [1, 0, 0], v: [0, 1, 0], nx: 4, ny: 3, mass: 1,
            rods: { bending: { compliance: 0.5 } } }
)");
  const System& sys = *scene.system;
  ASSERT_EQ(sys.constraint_objects().size(), 1u);
  // 3 x 2 cells: 6 diagonals, 3 x 1 row edges, 2 x 2 column edges.
  EXPECT_EQ(sys.constraint_rows(), 6 + 3 + 4);
  const ConstraintRows& rows = sys.evaluate_constraint_rows();
  EXPECT_EQ(rows.value.cwiseAbs().maxCoeff(), 0.0);  // flat: at rest
  EXPECT_EQ(rows.compliance, Eigen::VectorXd::Constant(13, 0.5));
}

}  // namespace bending_test
}  // namespace pdyn
