// langevin (plugins/forces/langevin): a heat bath's drag and random force.
// An ideal gas relaxes to the stationary temperature that velocity Verlet's
// discretisation of the Ornstein-Uhlenbeck process has (exactly computable,
// within 1.1% of T at h / tau = 0.2), with Maxwell-Boltzmann velocities (a
// Kolmogorov-Smirnov test); a Lennard-Jones liquid started hotter holds the
// bath's temperature within its statistical error; the noise is the same
// bits for any thread count and across a resume; bad values get located
// errors.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

#include "host/resume_support.hpp"
#include "pdyn/host/stepper.hpp"
#include "pdyn/system.hpp"
#include "pdyn/thermo.hpp"
#include "support/physics_support.hpp"
#include "support/statistics.hpp"
#include "support/test_support.hpp"

namespace pdyn {
namespace {

// 2 x 10^3 free particles (masses 1 and 4 kg; clouds, which add no springs)
// and one nailed, at rest, in a bath at k_B T = 1 J: no other force.
std::string ideal_gas(double dt, double damp, const std::string& extra = "") {
  return "simulation: { dt: " + test::Num(dt) +
         ", steps: 200, solver: { type: verlet } }\n"
         "particles:\n"
         "  - cloud: { n: 1000, box: { min: [0, 0, 0], max: [10, 10, 10] }, mass: 1 }\n"
         "  - cloud: { n: 1000, box: { min: [0, 0, 50], max: [10, 10, 60] }, mass: 4 }\n"
         "  - { position: [0, 0, -5], mass: 1, fixed: true }\n"
         "forces:\n"
         "  - { type: langevin, kT: 1, damp: " +
         test::Num(damp) + ", seed: 5 }\n" + extra;
}

TEST(Langevin, AnIdealGasReachesTheSchemesStationaryTemperature) {
  // With a = -v / tau + r, r held over the step with variance 2 kT / (m tau
  // h), pdyn's verlet (a1 at the predictor v0 + h a0) maps v0 to c v0 + b r,
  // c = 1 - e + e^2 / 2, b = h (1 - e / 2), e = h / tau. Its stationary
  // variance b^2 var(r) / (1 - c^2) is kT / m times
  //   (1 - e + e^2 / 4) / (1 - e + e^2 / 2 - e^3 / 8),
  // 0.98901 at e = 0.2: T to first order in e, as the Euler-Maruyama scheme.
  const double h = 0.02, tau = 0.1, e = h / tau;
  const double expected = (1 - e + e * e / 4) / (1 - e + e * e / 2 - e * e * e / 8);
  Scene scene = test::load_text(ideal_gas(h, tau));
  const System& s = *scene.system;
  std::vector<double> kt;  // 2 K / (3 N), each step after the first 500 (100 tau)
  std::vector<double> z;   // v sqrt(m / (expected kT)), standard normal: every 50th step,
                           // when c^50 = 5e-5 of the last sample's velocity is left
  test::StepThrough(scene, 3500, [&](std::int64_t k) {
    if (k <= 500) return;
    kt.push_back(thermo(s.view(), 0.0, 0.0).kT);
    if (k % 50 != 0) return;
    for (Index i = 0; i + 1 < s.size(); ++i) {
      for (int a = 0; a < 3; ++a) {
        z.push_back(s.velocities()(a, i) * std::sqrt(s.masses()(i) / expected));
      }
    }
  });
  const test::MeanError m = test::block_average(kt);
  const double d = test::ks_normal(z);
  std::cout << "langevin, ideal gas: <kT> = " << m.mean << " +- " << m.error << " J; the scheme's "
            << expected << ", the bath's 1; KS D = " << d
            << " (critical at 1%: " << test::ks_critical_1percent(z.size()) << ")\n";
  EXPECT_LT(std::abs(m.mean - expected), 4 * m.error);
  EXPECT_LT(d, test::ks_critical_1percent(z.size()));
  EXPECT_EQ(s.velocities().col(s.size() - 1), Vec3::Zero());  // the nailed particle
}

TEST(Langevin, ALiquidStartedHotterHoldsTheBathsTemperature) {
  // LAMMPS's 256-atom melt at T* = 1.44 (tests/scenes/thermo), in a bath at
  // k_B T = 1 with tau = 100 steps: h / tau = 0.01, a bias of order 1e-4.
  Scene scene =
      test::LjLiquid("{ type: verlet }", "  - { type: langevin, kT: 1, damp: 0.5, seed: 9 }\n");
  const System& s = *scene.system;
  std::vector<double> kt;
  test::StepThrough(scene, 6000, [&](std::int64_t k) {
    if (k > 1000) kt.push_back(thermo(s.view(), 0.0).kT);
  });
  const test::MeanError m = test::block_average(kt);
  std::cout << "langevin, LJ liquid: <kT> = " << m.mean << " +- " << m.error << " J (bath 1)\n";
  EXPECT_LT(std::abs(m.mean - 1.0), 3 * m.error);
  EXPECT_LT(m.error, 0.01);
}

TEST(Langevin, TheNoiseIsTheSameBitsForAnyThreadCountAndAcrossAResume) {
  const test::fs::path dir = test::temp_dir("langevin-resume");
  test::write_file(dir / "gas.yaml", ideal_gas(0.01, 0.1,
                                               "output:\n  path: out/frames.csv\n  every: 200\n"
                                               "  checkpoint: { path: out/run.ckpt }\n"));
  auto whole = test::pdyn_in(dir, {"run", "gas.yaml", "--threads", "1", "-q"});
  ASSERT_EQ(whole.status, 0) << whole.err;
  const std::string reference = test::read_bytes(dir / "out/frames.csv");
  ASSERT_FALSE(reference.empty());
  auto two = test::pdyn_in(dir, {"run", "gas.yaml", "--threads", "2", "-q"});
  ASSERT_EQ(two.status, 0) << two.err;
  EXPECT_EQ(test::read_bytes(dir / "out/frames.csv"), reference);
  auto half = test::pdyn_in(dir, {"run", "gas.yaml", "--steps", "100", "-q"});
  ASSERT_EQ(half.status, 0) << half.err;
  auto rest = test::pdyn_in(dir, {"run", "gas.yaml", "--resume", "out/run.ckpt", "-q"});
  ASSERT_EQ(rest.status, 0) << rest.err;
  EXPECT_EQ(test::read_bytes(dir / "out/frames.csv"), reference);
  // Another seed, other numbers.
  auto other = test::pdyn_in(dir, {"run", "gas.yaml", "--set", "forces[0].seed=6", "-q"});
  ASSERT_EQ(other.status, 0) << other.err;
  EXPECT_NE(test::read_bytes(dir / "out/frames.csv"), reference);
}

TEST(Langevin, EachBadValueGetsItsLocatedError) {
  auto with = [](const std::string& force, const std::string& solver = "verlet") {
    return test::load_problems("simulation: { dt: 0.01, steps: 1, solver: { type: " + solver +
                               " } }\n"
                               "particles:\n"
                               "  - { position: [0, 0, 0], mass: 1 }\n"
                               "forces:\n"
                               "  - " +
                               force + "\n");
  };
  const std::string expected =
      "(expected temperature: T in K, or kT: k_B T in J for reduced units)";
  EXPECT_EQ(with("{ type: langevin, kT: 1, damp: 0 }"),
            "test.yaml:5:36: forces[0].damp: 0 is out of range (expected a number > 0 in s)");
  EXPECT_EQ(with("{ type: langevin, temperature: -3, damp: 1 }"),
            "test.yaml:5:36: forces[0].temperature: -3 is out of range (expected a number >= 0 "
            "in K)");
  EXPECT_EQ(with("{ type: langevin, damp: 1 }"),
            "test.yaml:5:5: forces[0].temperature: no temperature given " + expected);
  EXPECT_EQ(
      with("{ type: langevin, kT: 1, temperature: 1, damp: 1 }"),
      "test.yaml:5:27: forces[0].kT: given with temperature (expected one of temperature: T in "
      "K, or kT: k_B T in J for reduced units)");
  EXPECT_EQ(with("{ type: langevin, kT: 1, damp: 1, seed: 4294967296 }"),
            "test.yaml:5:45: forces[0].seed: 4294967296 is out of range (expected a whole "
            "number in [0, 4294967295])");
  EXPECT_EQ(with("{ type: langevin, kT: 1, damp: 1 }", "rk45"),
            "test.yaml:5:5: forces[0]: langevin draws a force held over each fixed step; rk45 "
            "chooses its own step lengths (expected a fixed-step solver: verlet, rk4, euler, "
            "...)");
}

}  // namespace
}  // namespace pdyn
