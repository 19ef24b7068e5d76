// The area plugin (U = k/2 (A - A0)^2 on the unsigned area of each
// triangle), checked on random configurations:
//  - undamped, f = -grad U to central-difference accuracy;
//  - zero net force and torque (A is invariant under rigid motions);
//  - the damping alone never does positive work;
//  - a 3-4-5 right triangle has the expected energy and corner forces;
//  - degenerate (zero-area) triangles give finite forces and energies.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

#include "plugins/forces/force_support.hpp"

namespace pdyn {
namespace {

using test::Cloud;

TEST(AreaForce, UndampedForceIsMinusTheGradientOfItsPotential) {
  for (unsigned seed : {21u, 22u, 23u}) {
    Cloud cloud(7, seed);
    Scene scene =
        test::load_text(cloud.Yaml() + "forces:\n  - { type: area, triples: " + cloud.Triples(9) +
                        ", k: 50, rest: [0.4] }\n");
    System& sys = *scene.system;
    const Matrix3X f = test::ForcesOf(sys, 0);
    ASSERT_GT(test::MaxNorm(f), 0.1);
    const double rel = test::MaxNorm(f - test::MinusGradient(sys, 0, 1e-6)) / test::MaxNorm(f);
    std::cout << "area, seed " << seed << ": max |f + grad U| / max |f| = " << rel << "\n";
    EXPECT_LE(rel, 1e-6) << "seed " << seed;
  }
}

TEST(AreaForce, ZeroNetForceAndTorque) {
  for (unsigned seed : {24u, 25u, 26u}) {
    Cloud cloud(7, seed);
    Scene scene =
        test::load_text(cloud.Yaml() + "forces:\n  - { type: area, triples: " + cloud.Triples(9) +
                        ", k: 50, kd: 3, rest: [0.05] }\n");
    const Matrix3X f = test::ForcesOf(*scene.system, 0);
    const auto b = test::NetForceAndTorque(*scene.system, f);
    std::cout << "area, seed " << seed << ": |sum f|/sum|f| = " << b.force
              << ", |sum x x f|/sum|x||f| = " << b.torque << "\n";
    EXPECT_LE(b.force, 1e-13) << "seed " << seed;
    EXPECT_LE(b.torque, 1e-13) << "seed " << seed;
  }
}

TEST(AreaForce, DampingAloneDoesNoPositiveWork) {
  for (unsigned seed : {27u, 28u}) {
    Cloud cloud(7, seed);
    Scene scene =
        test::load_text(cloud.Yaml() + "forces:\n  - { type: area, triples: " + cloud.Triples(9) +
                        ", k: 0, kd: 3 }\n");
    const Matrix3X f = test::ForcesOf(*scene.system, 0);
    const double power = (f.array() * scene.system->velocities().array()).sum();
    std::cout << "area damping, seed " << seed << ": sum f.v = " << power << " W\n";
    EXPECT_LT(power, 0.0);
  }
}

// Legs 3 m (along x) and 4 m (along y): A = 6 m^2; rest 5 m^2, k = 2:
// U = 1 J, and the force on the corner j at (3, 0, 0) is -k (A - A0) dA/dx_j
// with dA/dx_j = n x (x_i - x_k) / 2 = z x (0, -4, 0) / 2 = (2, 0, 0): it is
// pulled in along x, shrinking the too large triangle.
TEST(AreaForce, RightTriangleHasTheExpectedEnergyAndForce) {
  Scene scene = test::load_text(R"(
simulation: { dt: 0.001, steps: 1 }
particles:
  - { position: [0, 0, 0], mass: 1 }
  - { position: [3, 0, 0], mass: 1 }
  - { position: [0, 4, 0], mass: 1 }
forces:
  - { type: area, triples: [[0, 1, 2]], k: 2, rest: [5] }
)");
  EXPECT_NEAR(scene.system->potential_energy(), 1.0, 1e-14);
  const Matrix3X f = test::ForcesOf(*scene.system, 0);
  EXPECT_NEAR((f.col(1) - Vec3(-4.0, 0.0, 0.0)).norm(), 0.0, 1e-14);
}

TEST(AreaForce, DegenerateTrianglesStayFinite) {
  for (const char* rest : {"", ", rest: [0.5]"}) {
    Scene scene = test::load_text(std::string(R"(
simulation: { dt: 0.001, steps: 1, solver: { type: rk4 } }
particles:
  - { position: [0, 0, 0], mass: 1 }
  - { position: [1, 0, 0], velocity: [0, 0.1, 0], mass: 1 }
  - { position: [2, 0, 0], mass: 1 }
  - { position: [2, 0, 0], mass: 1 }
forces:
  - { type: area, triples: [[0, 1, 2], [1, 2, 3]], k: 5, kd: 0.5)") +
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
