// The energies of LAMMPS's bonded styles that pdyn ships (issue 44 item
// 2), on one term whose angle is known exactly, and the values they refuse.
// Their forces are checked against their energies by `pdyn check`
// (bonded.gradient) and against LAMMPS by tests/host/data_topology_test.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>

#include "pdyn/system.hpp"
#include "support/test_support.hpp"

namespace pdyn {
namespace {

constexpr double kPi = std::numbers::pi;

// Four particles whose dihedral angle about the edge 1-2 (the x axis) is
// phi: particle 0 along +y, particle 3 turned by phi about x.
std::string Torsion(double phi, const std::string& force) {
  return "simulation: { dt: 0.001, steps: 1 }\nparticles:\n"
         "  - { position: [0, 1, 0], mass: 1 }\n  - { position: [0, 0, 0], mass: 1 }\n"
         "  - { position: [1.5, 0, 0], mass: 1 }\n  - { position: [1.5, " +
         std::to_string(std::cos(phi)) + ", " + std::to_string(std::sin(phi)) +
         "], mass: 1 }\nforces:\n  - " + force + "\n";
}

TEST(LammpsStyles, TorsionEnergiesAreLammpsFormulas) {
  for (const double phi : {0.3, 1.2, 2.5, kPi}) {
    const Scene opls = test::load_text(Torsion(
        phi,
        "{ type: dihedral_opls, quads: [[0, 1, 2, 3]], k1: 1.3, k2: -0.05, k3: 0.2, k4: 0.1 }"));
    const Scene periodic = test::load_text(
        Torsion(phi, "{ type: dihedral_harmonic, quads: [[0, 1, 2, 3]], k: 1.5, d: -1, n: 3 }"));
    // std::to_string's 6 decimals place particle 3 within 5e-7 of phi.
    const double u_opls = 0.5 * (1.3 * (1 + std::cos(phi)) - 0.05 * (1 - std::cos(2 * phi)) +
                                 0.2 * (1 + std::cos(3 * phi)) + 0.1 * (1 - std::cos(4 * phi)));
    const double u_periodic = 1.5 * (1 - std::cos(3 * phi));
    EXPECT_NEAR(opls.system->potential_energy(), u_opls, 3e-6) << "phi = " << phi;
    EXPECT_NEAR(periodic.system->potential_energy(), u_periodic, 3e-6) << "phi = " << phi;
  }
}

TEST(LammpsStyles, CosineSquaredEnergyIsKTimesTheCosinesDifferenceSquared) {
  // A right angle at particle 1: cos theta = 0; theta0 = 2 rad.
  const Scene s = test::load_text(
      "simulation: { dt: 0.001, steps: 1 }\nparticles:\n"
      "  - { position: [2, 0, 0], mass: 1 }\n  - { position: [0, 0, 0], mass: 1 }\n"
      "  - { position: [0, 3, 0], mass: 1 }\nforces:\n"
      "  - { type: angle_cosine_squared, triples: [[0, 1, 2]], k: 15, theta0: 2 }\n");
  const double d = 0.0 - std::cos(2.0);
  EXPECT_NEAR(s.system->potential_energy(), 15 * d * d, 1e-14);
  // f_0 = -2 K d dc/dx_0 = -2 K d (b/|b| - 0) / |a| = -2 K d (0, 1, 0) / 2.
  Matrix3X f = Matrix3X::Zero(3, 3);
  s.system->force_objects().at(0).force->add_forces(s.system->view(), f);
  EXPECT_NEAR((f.col(0) - Vec3(0, -15 * d, 0)).norm(), 0.0, 1e-14);
  EXPECT_NEAR((f.col(2) - Vec3(-2 * 15 * d / 3, 0, 0)).norm(), 0.0, 1e-14);
}

TEST(LammpsStyles, ATorsionsSignAndMultiplicityMustBeLammpss) {
  EXPECT_NE(test::load_problems(Torsion(1.0,
                                        "{ type: dihedral_harmonic, quads: [[0, 1, 2, 3]], "
                                        "k: 1, d: 0.5, n: 3 }"))
                .find("forces[0].d: is 0.500000 for type 0 (expected 1 or -1)"),
            std::string::npos);
  EXPECT_NE(test::load_problems(Torsion(1.0,
                                        "{ type: dihedral_harmonic, quads: [[0, 1, 2, 3]], "
                                        "k: 1, d: 1, n: 2.5 }"))
                .find("forces[0].n: is 2.500000 for type 0 (expected a whole number >= 0)"),
            std::string::npos);
}

}  // namespace
}  // namespace pdyn
