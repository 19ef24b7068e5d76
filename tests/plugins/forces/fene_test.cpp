// fene, LAMMPS's bond_style fene (issue 44 item 2):
//  - one bond's energy and force from the formula (FENE plus the WCA
//    repulsion inside 2^(1/6) sigma, nothing outside);
//  - 20 bead-spring chains continued from LAMMPS's state for 200 velocity
//    Verlet steps (tests/scenes/fene, written by make_reference.lmp): every
//    thermo column at every 20th step as LAMMPS printed it, to 1e-10;
//  - a bond stretched to R0 stops the run with a message naming it.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>

#include "host/resume_support.hpp"
#include "pdyn/system.hpp"
#include "support/lammps_thermo.hpp"
#include "support/physics_support.hpp"
#include "support/test_support.hpp"

namespace pdyn {
namespace {

namespace fs = std::filesystem;

// One bond from particle 0 at the origin to particle 1 at (r, 0, 0):
// K = 30, R0 = 1.5, epsilon = 1.2, sigma = 0.9.
pdyn::Scene OneFeneBond(double r) {
  return test::load_text(
      "simulation: { dt: 0.001, steps: 1 }\nparticles:\n"
      "  - { position: [0, 0, 0], mass: 1 }\n  - { position: [" +
      test::Num(r) +
      ", 0, 0], mass: 1 }\nforces:\n"
      "  - { type: fene, pairs: [[0, 1]], k: 30, r0: 1.5, epsilon: 1.2, "
      "sigma: 0.9 }\n");
}

TEST(FeneBond, EnergyAndForceAreKremerGrestsWithTheWcaPartInsideItsRange) {
  const double k = 30, r0 = 1.5, eps = 1.2, sigma = 0.9;
  const double reach = std::pow(2.0, 1.0 / 6.0) * sigma;  // 1.0102 m
  for (const double r : {0.85, 0.97, 1.0, 1.2, 1.45}) {
    const pdyn::Scene s = OneFeneBond(r);
    const System& sys = *s.system;
    Matrix3X f = Matrix3X::Zero(3, 2);
    sys.force_objects().at(0).force->add_forces(sys.view(), f);
    // U = -K R0^2/2 ln(1 - (r/R0)^2) [+ 4 eps ((s/r)^12 - (s/r)^6) + eps];
    // the force on particle 1 is -dU/dr along +x.
    const double x = r / r0, sr6 = std::pow(sigma / r, 6);
    double u = -0.5 * k * r0 * r0 * std::log(1.0 - x * x);
    double du = k * r / (1.0 - x * x);
    if (r < reach) {
      u += 4.0 * eps * (sr6 * sr6 - sr6) + eps;
      du += 4.0 * eps * (-12.0 * sr6 * sr6 + 6.0 * sr6) / r;
    }
    EXPECT_NEAR(sys.potential_energy(), u, 1e-13 * std::abs(u)) << "r = " << r;
    EXPECT_NEAR(f(0, 1), -du, 1e-12 * std::abs(du)) << "r = " << r;
    EXPECT_EQ(f.col(0), Vec3(-f.col(1))) << "r = " << r;
    EXPECT_EQ(f(1, 1), 0.0);
    EXPECT_EQ(f(2, 1), 0.0);
  }
}

TEST(FeneBond, BeadSpringChainsFollowLammpsStepForStep) {
  // 200 beads in a box of 1000: the ideal gas's pressure N kT / V is 0.2.
  test::expect_lammps_thermo("fene", {"fene.yaml", "fene_start.data"}, "out/fene-energy.csv", 1e-10,
                             0.2);
}

TEST(FeneBond, ABondStretchedToR0StopsTheRunNamingIt) {
  // Particle 1 leaves at 30 m/s: the bond (R0 = 1.5 m) cannot hold it
  // within one step of 0.01 s from 1.45 m.
  const fs::path dir = test::temp_dir("fene-stretched");
  test::write_file(dir / "s.yaml",
                   "simulation: { dt: 0.01, steps: 5, solver: { type: verlet } }\nparticles:\n"
                   "  - { position: [0, 0, 0], mass: 1 }\n"
                   "  - { position: [1.45, 0, 0], velocity: [30, 0, 0], mass: 1 }\n"
                   "forces:\n  - { type: fene, pairs: [[0, 1]], k: 30, r0: 1.5, epsilon: 1, "
                   "sigma: 1 }\n");
  const auto run = test::pdyn_in(dir, {"run", "s.yaml", "-q"});
  EXPECT_NE(run.status, 0);
  // Verlet's first step takes it to 1.4500 + 0.01 * 30 - (drift back) = 1.6836 m.
  const std::string expected =
      "pdyn: plugin fene (s.yaml:6:5): add_forces threw: the FENE bond between particles 0 and "
      "1 is stretched to 1.683644 m at t = 0.010000 s, where the potential is infinite "
      "(expected every bond shorter than its r0: a smaller time step, or a start nearer rest; "
      "LAMMPS would clamp it with the warning 'FENE bond too long') at step 1 (library ";
  EXPECT_EQ(run.err.substr(0, expected.size()), expected) << run.err;
}

}  // namespace
}  // namespace pdyn
