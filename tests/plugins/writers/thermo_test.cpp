// Temperature and pressure (pdyn/thermo.hpp, the energy writer's columns):
// on LAMMPS's own Lennard-Jones liquid (tests/scenes/thermo) pdyn's kT,
// pressure, potential, kinetic and total energy agree with LAMMPS's thermo
// temp, press, pe, ke and etotal to at least 10 significant digits at every
// tenth step from 0 to 100; an ideal gas has P V = 2 K / 3; a pair across a
// periodic face contributes r f(r) to the virial; a force without a
// virial makes the pressure an error naming it, never a wrong number.
#include "pdyn/thermo.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>

#include "host/resume_support.hpp"
#include "pdyn/system.hpp"
#include "support/lammps_thermo.hpp"
#include "support/physics_support.hpp"
#include "support/test_support.hpp"

namespace pdyn {
namespace {

namespace fs = std::filesystem;

TEST(Thermo, TheLjLiquidsTemperatureAndPressureAgreeWithLammpsToTenDigits) {
  // Every column at steps 0, 10, ..., 100 to 1e-10 relative.
  const auto ours = test::expect_lammps_thermo("thermo", {"thermo.yaml", "thermo_start.data"},
                                               "out/thermo-energy.csv", 1e-10, 0.0);
  EXPECT_EQ(ours.at("step").size(), 11u);
}

TEST(Thermo, AnIdealGasHasTheKineticPressure) {
  // No force: W = 0 and P = 2 K / (3 V) = N_f k_B T / V with N_f = 3 N - 3
  // in a 2 x 3 x 4 m box.
  Scene scene = test::load_text(
      "simulation: { dt: 0.01, steps: 1, box: { min: [0, 0, 0], max: [2, 3, 4], periodic: "
      "[true, true, true] } }\n"
      "particles:\n"
      "  - cloud: { n: 100, box: { min: [0, 0, 0], max: [2, 3, 4] }, mass: 2 }\n"
      "velocities: { kT: 0.5, seed: 4 }\n");
  const Thermo th = thermo(scene.system->view(), total_virial(*scene.system).value);
  EXPECT_EQ(th.volume, 24.0);
  EXPECT_NEAR(th.kT, 0.5, 1e-15);
  EXPECT_NEAR(th.pressure, 297 * 0.5 / (3 * 24.0), 1e-15);
}

TEST(Thermo, APairAcrossAPeriodicFaceAddsRTimesItsForce) {
  // Atoms 0 and 1 are 1.1 sigma apart through the face x = 0 of a 10 m box,
  // atoms 2 and 3 1.5 sigma apart inside it, and joined by a spring too:
  // each Lennard-Jones pair adds r f(r), f = 24 (2 r^-13 - r^-7) (epsilon =
  // sigma = 1), the spring (a bonded term) (x_3 - x_2) . f_3, gravity (from
  // outside) nothing.
  Scene scene = test::load_text(
      "simulation: { dt: 0.01, steps: 1, box: { min: [0, 0, 0], max: [10, 10, 10], periodic: "
      "[true, true, true] } }\n"
      "particles:\n"
      "  - { position: [0.55, 5, 5], mass: 1 }\n"
      "  - { position: [9.45, 5, 5], mass: 1 }\n"
      "  - { position: [5, 5, 5], mass: 1 }\n"
      "  - { position: [5, 5, 6.5], mass: 1 }\n"
      "forces:\n"
      "  - { type: lennard_jones, epsilon: 1, sigma: 1, cutoff: 2.5, skin: 0 }\n"
      "  - { type: spring, pairs: [[2, 3]], ks: 4, kd: 0, rest: 1 }\n"
      "  - { type: gravity }\n");
  auto w_pair = [](double r) { return r * 24 * (2 * std::pow(r, -13) - std::pow(r, -7)); };
  const double w_spring = 1.5 * (-4 * (1.5 - 1.0));  // pulled in: -ks (l - l0) l
  const double r01 = (0.55 - 9.45) + 10.0;           // the nearest image's separation, as rounded
  const double expected = w_pair(r01) + w_pair(1.5) + w_spring;
  const VirialSum w = total_virial(*scene.system);
  EXPECT_EQ(w.missing, "");
  EXPECT_NEAR(w.value, expected, 1e-14);  // a few ulps of the terms
  std::cout << "thermo: virial " << w.value << " J (pairs " << w_pair(r01) << " across the face, "
            << w_pair(1.5) << ", spring " << w_spring << ")\n";
}

TEST(Thermo, AForceWithoutAVirialMakesThePressureAnErrorNamingIt) {
  // nbody reports no virial: the pressure column is refused at the first
  // frame, naming the force, rather than written without it.
  const fs::path dir = test::temp_dir("thermo-missing");
  test::write_file(dir / "s.yaml",
                   "simulation: { dt: 0.01, steps: 2, box: { min: [0, 0, 0], max: [10, 10, 10], "
                   "periodic: [true, true, true] } }\n"
                   "particles:\n"
                   "  - { position: [1, 1, 1], mass: 1 }\n"
                   "  - { position: [2, 1, 1], mass: 1 }\n"
                   "forces:\n"
                   "  - { type: nbody }\n"
                   "output:\n"
                   "  - { type: energy, path: e.csv, columns: [t, pressure] }\n");
  const auto r = test::pdyn_in(dir, {"run", "s.yaml", "-q"});
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.err.find("e.csv: the pressure needs every force's virial, and nbody (s.yaml:6:5) "
                       "reports none (expected forces built with pdyn 0.8 or later, "
                       "pdyn/thermo.hpp)"),
            std::string::npos)
      << r.err;
  // What was written stops before the first frame: the header alone.
  EXPECT_EQ(test::read_bytes(dir / "e.csv"), "t,pressure\n");
}

}  // namespace
}  // namespace pdyn
