// The dihedral plugin (U = k/2 (phi - phi0)^2 on the angle between the
// planes (i, j, k) and (j, k, l) about the edge j-k), against exact answers:
//  - perpendicular planes: phi = pi/2, the energy and the force on l;
//  - a flat sheet (phi0 = pi) folded by +-delta has the same energy either
//    way, across atan2's wrap at +-pi;
//  - a flap on a fixed hinge oscillates at w = sqrt(k / (m r^2)) (measured
//    period against 2 pi / w);
//  - f = -grad U and zero net force and torque on random quadruples;
//  - per-type coefficients: `types` picks each term's k.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <numbers>

#include "plugins/forces/force_support.hpp"

namespace pdyn {
namespace {

using std::numbers::pi;

// Edge j-k along x; i in the (x, y) plane at y = 1, l at z = 1 above k.
constexpr const char* kPerpendicular = R"(
simulation: { dt: 0.001, steps: 1 }
particles:
  - { position: [0, 1, 0], mass: 1 }
  - { position: [0, 0, 0], mass: 1 }
  - { position: [1, 0, 0], mass: 1 }
  - { position: [1, 0, 1], mass: 1 }
forces:
)";

// F = x_i - x_j = (0, 1, 0), G = x_j - x_k = (-1, 0, 0), H = x_l - x_k =
// (0, 0, 1): A = F x G = (0, 0, 1), B = H x G = (0, -1, 0), A . B = 0 and
// (B x A) . G / |G| = 1, so phi = atan2(1, 0) = pi/2. With phi0 = pi and
// k = 2: U = k/2 (pi/2)^2 = pi^2/4, and the force on l is
// -k (phi - phi0) |G|/|B|^2 B = 2 (pi/2) (0, -1, 0) = (0, -pi, 0): l is
// pushed down towards the flat sheet.
TEST(DihedralForce, PerpendicularPlanesHaveTheExpectedEnergyAndForce) {
  Scene scene = test::load_text(std::string(kPerpendicular) +
                                "  - { type: dihedral, quads: [[0, 1, 2, 3]], k: 2, rest: "
                                "[3.141592653589793] }\n");
  EXPECT_NEAR(scene.system->potential_energy(), pi * pi / 4.0, 1e-14);
  const Matrix3X f = test::ForcesOf(*scene.system, 0);
  EXPECT_NEAR((f.col(3) - Vec3(0.0, -pi, 0.0)).norm(), 0.0, 1e-14);
  // The torque about the hinge balances: i is pushed the other way.
  EXPECT_NEAR((f.rowwise().sum()).norm(), 0.0, 1e-14);
}

// A flat sheet of two triangles, i at y = +1 and l at y = -1 (trans: phi =
// pi, the default rest angle), with l lifted to z = +-delta: phi = pi - a or
// -pi + a with a = atan(delta); folded into (-pi, pi] the deviation is -+a
// either way, U = k/2 a^2.
TEST(DihedralForce, FlatSheetFoldsAlikeBothWays) {
  for (const double delta : {1e-3, 0.1, 0.5}) {
    double energy[2];
    for (int side = 0; side < 2; ++side) {
      const double z = side == 0 ? delta : -delta;
      Scene scene = test::load_text(
          "simulation: { dt: 0.001, steps: 1 }\nparticles:\n"
          "  - { position: [0.5, 1, 0], mass: 1 }\n"
          "  - { position: [0, 0, 0], mass: 1 }\n"
          "  - { position: [1, 0, 0], mass: 1 }\n"
          "  - { position: [0.5, -1, " +
          test::Num(z) +
          "], mass: 1 }\n"
          "forces:\n  - { type: dihedral, quads: [[0, 1, 2, 3]], k: 3, rest: "
          "[3.141592653589793] }\n");
      energy[side] = scene.system->potential_energy();
    }
    const double a = std::atan(delta);
    EXPECT_NEAR(energy[0], 1.5 * a * a, 1e-13 * (1.0 + a * a)) << "delta " << delta;
    EXPECT_NEAR(energy[1], energy[0], 1e-15) << "delta " << delta;
  }
}

// i, j, k fixed; l (mass m) at distance r from the hinge axis, started
// flat with a small angular velocity. The dihedral force on l is
// -k (phi - phi0) / r along the circle about the axis (|grad_l phi| = 1/r),
// so for small angles m r^2 phi'' = -k (phi - phi0): w = sqrt(k / (m r^2)).
// The period is measured from the upward zero crossings of phi - phi0.
TEST(DihedralForce, FlapOnAHingeOscillatesAtTheBendingFrequency) {
  const double k = 0.5, m = 0.02, r = 0.8, amplitude = 1e-3;  // N m/rad, kg, m, rad
  const double w = std::sqrt(k / (m * r * r)), period = 2 * pi / w;
  const double dt = period / 2000;
  const int steps = static_cast<int>(std::ceil(3.2 * period / dt));
  Scene scene = test::load_text(
      "simulation: { dt: " + test::Num(dt) + ", steps: " + std::to_string(steps) +
      ", solver: { type: rk4 } }\nparticles:\n"
      "  - { position: [0.5, 1, 0], mass: 1, fixed: true }\n"
      "  - { position: [0, 0, 0], mass: 1, fixed: true }\n"
      "  - { position: [1, 0, 0], mass: 1, fixed: true }\n"
      "  - { position: [0.5, " +
      test::Num(-r) + ", 0], velocity: [0, 0, " + test::Num(amplitude * w * r) +
      "], mass: " + test::Num(m) +
      " }\nforces:\n  - { type: dihedral, quads: [[0, 1, 2, 3]], k: " + test::Num(k) + " }\n");
  System& sys = *scene.system;
  std::vector<double> crossings;
  double last = 0.0;
  for (int s = 1; s <= steps; ++s) {
    test::TakeStep(scene, s, dt);
    const double z = sys.positions()(2, 3);
    if (last < 0.0 && z >= 0.0) crossings.push_back((s - 1 + last / (last - z)) * dt);
    last = z;
  }
  ASSERT_GE(crossings.size(), 2u);
  const double measured =
      (crossings.back() - crossings.front()) / static_cast<double>(crossings.size() - 1);
  std::cout << "dihedral flap: period " << measured << " s, expected " << period << " s\n";
  EXPECT_NEAR(measured / period, 1.0, 1e-4);
}

TEST(DihedralForce, ForceIsMinusTheGradientAndInternal) {
  for (unsigned seed : {31u, 32u, 33u}) {
    test::Cloud cloud(8, seed);
    Scene scene = test::load_text(
        cloud.Yaml() +
        "forces:\n  - { type: dihedral, quads: [[0, 1, 2, 3], [1, 2, 3, 4], [4, 5, 6, 7], [7, 6, "
        "1, 0]], k: 2, rest: [0.3] }\n");
    System& sys = *scene.system;
    const Matrix3X f = test::ForcesOf(sys, 0);
    ASSERT_GT(test::MaxNorm(f), 0.1);
    const double rel = test::MaxNorm(f - test::MinusGradient(sys, 0, 1e-6)) / test::MaxNorm(f);
    const auto b = test::NetForceAndTorque(sys, f);
    std::cout << "dihedral, seed " << seed << ": |f + grad U| / |f| = " << rel << ", net force "
              << b.force << ", net torque " << b.torque << "\n";
    EXPECT_LE(rel, 1e-6);
    EXPECT_LE(b.force, 1e-13);
    EXPECT_LE(b.torque, 1e-13);
  }
}

// Two terms of the perpendicular configuration above, of types 0 and 1
// with k = [2, 6]: U = (2 + 6)/2 (pi/2)^2.
TEST(DihedralForce, TypesChooseEachTermsCoefficients) {
  Scene scene = test::load_text(std::string(kPerpendicular) +
                                "  - { type: dihedral, quads: [[0, 1, 2, 3], [3, 2, 1, 0]], types: "
                                "[0, 1], k: [2, 6], rest: [3.141592653589793] }\n");
  EXPECT_NEAR(scene.system->potential_energy(), 4.0 * pi * pi / 4.0, 1e-13);
}

TEST(DihedralForce, BadTypesAreRefusedWithTheirPlace) {
  const std::string base = kPerpendicular;
  EXPECT_EQ(test::load_problems(base + "  - { type: dihedral, quads: [[0, 1, 2, 3]], types: [2], "
                                       "k: [2, 6] }\n"),
            "test.yaml:9:54: forces[0].types[0]: 2 is not a term type (expected 0..1: k, kd give "
            "2 types)");
  EXPECT_EQ(test::load_problems(base + "  - { type: dihedral, quads: [[0, 1, 2, 1]] }\n"),
            "test.yaml:9:31: forces[0].quads[0]: [0, 1, 2, 1] repeats a particle (expected four "
            "different particles)");
  EXPECT_EQ(test::load_problems(base + "  - { type: dihedral, quads: [[0, 1, 2, 3]], k: [1, 2], "
                                       "kd: [1, 2, 3] }\n"),
            "test.yaml:9:49: forces[0].k: has 2 values (expected 1 value for all term types, or "
            "3, one per type, as the longest coefficient list gives)");
}

}  // namespace
}  // namespace pdyn
