// The angle plugin (bending spring U = k/2 (theta - theta0)^2 at the middle
// particle of each triple), checked on random configurations:
//  - undamped, f = -grad U to central-difference accuracy;
//  - damped or not, zero net force and torque (theta is invariant under
//    rigid motions, so the force is internal);
//  - the damping alone never does positive work (f . v = -kd theta'^2);
//  - collinear and coincident triples (theta = 0 or pi, where grad theta
//    has no direction) give finite forces and energies, and a solver steps on;
//  - the angle is measured as expected on a right angle.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <numbers>

#include "plugins/forces/force_support.hpp"

namespace pdyn {
namespace {

using test::Cloud;

TEST(AngleForce, UndampedForceIsMinusTheGradientOfItsPotential) {
  for (unsigned seed : {11u, 12u, 13u}) {
    Cloud cloud(7, seed);
    // Rest angles away from the initial ones: a stretched, loaded state.
    Scene scene =
        test::load_text(cloud.Yaml() + "forces:\n  - { type: angle, triples: " + cloud.Triples(9) +
                        ", k: 5, rest: [1.1] }\n");
    System& sys = *scene.system;
    const Matrix3X f = test::ForcesOf(sys, 0);
    ASSERT_GT(test::MaxNorm(f), 0.1);
    const double rel = test::MaxNorm(f - test::MinusGradient(sys, 0, 1e-6)) / test::MaxNorm(f);
    std::cout << "angle, seed " << seed << ": max |f + grad U| / max |f| = " << rel << "\n";
    EXPECT_LE(rel, 1e-6) << "seed " << seed;
  }
}

TEST(AngleForce, ZeroNetForceAndTorque) {
  for (unsigned seed : {14u, 15u, 16u}) {
    Cloud cloud(7, seed);
    Scene scene =
        test::load_text(cloud.Yaml() + "forces:\n  - { type: angle, triples: " + cloud.Triples(9) +
                        ", k: 5, kd: 0.7, rest: [2.0] }\n");
    const Matrix3X f = test::ForcesOf(*scene.system, 0);
    const auto b = test::NetForceAndTorque(*scene.system, f);
    std::cout << "angle, seed " << seed << ": |sum f|/sum|f| = " << b.force
              << ", |sum x x f|/sum|x||f| = " << b.torque << "\n";
    EXPECT_LE(b.force, 1e-13) << "seed " << seed;
    EXPECT_LE(b.torque, 1e-13) << "seed " << seed;
  }
}

TEST(AngleForce, DampingAloneDoesNoPositiveWork) {
  for (unsigned seed : {17u, 18u}) {
    Cloud cloud(7, seed);
    Scene scene =
        test::load_text(cloud.Yaml() + "forces:\n  - { type: angle, triples: " + cloud.Triples(9) +
                        ", k: 0, kd: 0.7 }\n");
    const Matrix3X f = test::ForcesOf(*scene.system, 0);
    const double power = (f.array() * scene.system->velocities().array()).sum();
    std::cout << "angle damping, seed " << seed << ": sum f.v = " << power << " W\n";
    EXPECT_LT(power, 0.0) << "random velocities bend the triples, so damping must remove energy";
  }
}

// theta = pi/2 at particle 1; rest pi/3 and k = 2: U = (pi/6)^2 J. Particle 0
// sits 2 m from the corner, so |f_0| = k (theta - theta0) / 2 m, pushing it
// towards particle 2 (closing the angle).
TEST(AngleForce, RightAngleHasTheExpectedEnergyAndForce) {
  Scene scene = test::load_text(R"(
simulation: { dt: 0.001, steps: 1 }
particles:
  - { position: [2, 0, 0], mass: 1 }
  - { position: [0, 0, 0], mass: 1 }
  - { position: [0, 3, 0], mass: 1 }
forces:
  - { type: angle, triples: [[0, 1, 2]], k: 2, rest: [1.0471975511965976] }
)");
  const double excess = std::numbers::pi / 2 - std::numbers::pi / 3;
  EXPECT_NEAR(scene.system->potential_energy(), excess * excess, 1e-15);
  const Matrix3X f = test::ForcesOf(*scene.system, 0);
  EXPECT_NEAR((f.col(0) - Vec3(0, 2 * excess / 2, 0)).norm(), 0.0, 1e-14);
  EXPECT_NEAR((f.col(2) - Vec3(2 * excess / 3, 0, 0)).norm(), 0.0, 1e-14);
}

// Straight (theta = pi), folded (theta = 0) and coincident triples: theta's
// gradient has no direction there, the force must stay finite (it is zero),
// and an rk4 run must stay finite as the configuration leaves the cone tip.
TEST(AngleForce, DegenerateTriplesStayFinite) {
  for (const char* rest : {"", ", rest: [1.5]"}) {
    Scene scene = test::load_text(std::string(R"(
simulation: { dt: 0.001, steps: 1, solver: { type: rk4 } }
particles:
  - { position: [0, 0, 0], mass: 1 }
  - { position: [1, 0, 0], velocity: [0, 0.1, 0], mass: 1 }
  - { position: [2, 0, 0], mass: 1 }
  - { position: [3, 0, 0], mass: 1 }
  - { position: [3, 0, 0], mass: 1 }
forces:
  - { type: angle, triples: [[0, 1, 2], [0, 2, 1], [2, 3, 4], [3, 2, 4]], k: 5, kd: 0.5)") +
                                  rest + " }\n");
    System& sys = *scene.system;
    const Matrix3X f = test::ForcesOf(sys, 0);
    EXPECT_TRUE(f.allFinite()) << rest;
    EXPECT_TRUE(std::isfinite(sys.potential_energy())) << rest;
    for (int k = 0; k < 50; ++k) scene.solver->step(sys, 0.001);
    EXPECT_TRUE(sys.state().allFinite()) << rest;
  }
}

}  // namespace
}  // namespace pdyn
