// The attractor plugin (softened central force per unit mass):
//  - a circular Kepler orbit (strength = G M = 1 m^3/s^2, r = 1 m, v = 1
//    m/s, no softening) under velocity Verlet, h = 0.01 s, for 10 periods:
//    the radius and the total energy stay within stated bounds;
//  - for several exponents (harmonic -1, constant 0, logarithmic 1, 1.5, 3)
//    with softening, f = -grad U of the closed-form potential it reports;
//  - a negative strength repels.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <numbers>

#include "plugins/forces/force_support.hpp"

namespace pdyn {
namespace {

TEST(AttractorForce, CircularOrbitKeepsItsRadiusAndEnergyUnderVerlet) {
  Scene scene = test::load_text(R"(
simulation: { dt: 0.01, steps: 1, solver: { type: verlet } }
particles:
  - { position: [1, 0, 0], velocity: [0, 1, 0], mass: 0.3 }
forces:
  - { type: attractor, center: [0, 0, 0], strength: 1, softening: 0, exponent: 2 }
)");
  System& sys = *scene.system;
  const double e0 = sys.kinetic_energy() + sys.potential_energy();
  EXPECT_NEAR(e0, -0.5 * 0.3, 1e-15) << "E = m (v^2/2 - GM/r)";
  const int steps = static_cast<int>(std::round(10 * 2 * std::numbers::pi / 0.01));
  double r_dev = 0.0, e_dev = 0.0;
  for (int s = 1; s <= steps; ++s) {
    test::TakeStep(scene, s, 0.01);
    r_dev = std::max(r_dev, std::abs(sys.positions().col(0).norm() - 1.0));
    e_dev = std::max(e_dev, std::abs(sys.kinetic_energy() + sys.potential_energy() - e0) / -e0);
  }
  std::cout << "attractor orbit, verlet h = 0.01 s, 10 periods: max |r - 1| = " << r_dev
            << " m, max |E - E0|/|E0| = " << e_dev << "\n";
  // Measured: 5.0e-5 m and 2.5e-9.
  EXPECT_LE(r_dev, 1e-4);
  EXPECT_LE(e_dev, 1e-7);
}

TEST(AttractorForce, ForceIsMinusTheGradientOfItsPotentialForEveryExponent) {
  for (double p : {-1.0, 0.0, 1.0, 1.5, 2.0, 3.0}) {
    test::Cloud cloud(6, 31);
    Scene scene = test::load_text(cloud.Yaml() +
                                  "forces:\n  - { type: attractor, center: [0.1, -0.2, 0.3], "
                                  "strength: 2.5, softening: 0.2, exponent: " +
                                  test::Num(p) + " }\n");
    System& sys = *scene.system;
    const Matrix3X f = test::ForcesOf(sys, 0);
    const double rel = test::MaxNorm(f - test::MinusGradient(sys, 0, 1e-6)) / test::MaxNorm(f);
    std::cout << "attractor exponent " << p << ": max |f + grad U| / max |f| = " << rel << "\n";
    EXPECT_LE(rel, 1e-6) << "exponent " << p;
  }
}

TEST(AttractorForce, NegativeStrengthRepels) {
  Scene scene = test::load_text(R"(
simulation: { dt: 0.01, steps: 1 }
particles:
  - { position: [2, 0, 0], mass: 3 }
forces:
  - { type: attractor, strength: -4, softening: 0 }
)");
  const Matrix3X f = test::ForcesOf(*scene.system, 0);
  EXPECT_NEAR((Vec3(f.col(0)) - Vec3(3.0, 0, 0)).norm(), 0.0, 1e-15) << "4 * 3 / 2^2 = 3 N outward";
}

}  // namespace
}  // namespace pdyn
