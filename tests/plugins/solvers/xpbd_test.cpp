// The xpbd solver (plugins/solvers/xpbd) against exact answers: a compliant
// rod is a spring of stiffness 1/alpha whatever the step and the substeps
// (Macklin et al. 2016, the point of the "X"); a rigid rod keeps its length
// and swings with the pendulum's period; and a compliance that a solver
// would ignore is refused at its key.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <string>

#include "support/physics_support.hpp"
#include "support/test_support.hpp"

namespace pdyn {
namespace xpbd_test {

// A 0.1 kg bob on a 1 m rod of compliance alpha under a nailed pivot, at
// rest straight down, stepped for `seconds` (with drag to settle it).
std::string Hanging(double alpha, double dt, int substeps, const std::string& solver = "xpbd") {
  return "simulation: { dt: " + std::to_string(dt) + ", duration: 1, solver: { type: " + solver +
         (solver == "xpbd" ? ", substeps: " + std::to_string(substeps) : std::string()) +
         " } }\n"
         "particles:\n"
         "  - { position: [0, 0, 0], mass: 1, fixed: true }\n"
         "  - { position: [0, 0, -1], mass: 0.1 }\n"
         "forces:\n"
         "  - { type: gravity, g: [0, 0, -9.81] }\n"
         "  - { type: drag, k: 0.5 }\n"
         "constraints:\n"
         "  - { type: distance, pairs: [[0, 1]], compliance: " +
         std::to_string(alpha) + " }\n";
}

TEST(Xpbd, ACompliantRodStretchesByMassTimesGravityTimesComplianceAtAnyStep) {
  const double alpha = 1e-3;                   // m/N
  const double expected = 0.1 * 9.81 * alpha;  // m: 1/alpha = 1000 N/m under 0.981 N
  for (const auto& [dt, substeps] :
       {std::pair{0.01, 10}, std::pair{0.002, 1}, std::pair{0.02, 40}}) {
    Scene scene = test::load_text(Hanging(alpha, dt, substeps));
    test::StepThrough(scene, static_cast<std::int64_t>(std::lround(3.0 / dt)), [](std::int64_t) {});
    const double stretch = scene.system->positions().col(1).norm() - 1.0;
    std::cout << "xpbd: dt = " << dt << " s, " << substeps << " substeps: stretch " << stretch
              << " m (m g alpha = " << expected << " m)\n";
    EXPECT_NEAR(stretch, expected, 1e-3 * expected) << "dt = " << dt;
  }
}

TEST(Xpbd, ARigidPendulumKeepsItsLengthAndItsSmallAmplitudePeriod) {
  // 1 m rod, released at 0.05 rad: T = 2 pi sqrt(L/g) (1 + theta0^2/16).
  Scene scene = test::load_text(
      "simulation: { dt: 0.01, duration: 10, solver: { type: xpbd, substeps: 20 } }\n"
      "particles:\n"
      "  - { position: [0, 0, 0], mass: 1, fixed: true }\n"
      "  - { position: [0.04997916927067833, 0, -0.9987502603949663], mass: 0.1 }\n"
      "forces:\n"
      "  - { type: gravity, g: [0, 0, -9.81] }\n"
      "constraints:\n"
      "  - { type: distance, pairs: [[0, 1]] }\n");
  System& sys = *scene.system;
  double worst = 0.0, previous_x = sys.positions()(0, 1);
  std::vector<double> crossings;  // times x passes 0 going negative
  test::StepThrough(scene, 1000, [&](std::int64_t k) {
    const double x = sys.positions()(0, 1);
    worst = std::max(worst, std::abs(sys.positions().col(1).norm() - 1.0));
    if (previous_x > 0.0 && x <= 0.0) {
      const double f = previous_x / (previous_x - x);  // linear interpolation within the step
      crossings.push_back((static_cast<double>(k - 1) + f) * 0.01);
    }
    previous_x = x;
  });
  ASSERT_GE(crossings.size(), 5u);
  const double period =
      (crossings.back() - crossings.front()) / static_cast<double>(crossings.size() - 1);
  const double exact = 2 * M_PI * std::sqrt(1.0 / 9.81) * (1 + 0.05 * 0.05 / 16);
  std::cout << "xpbd pendulum: period " << period << " s, exact " << exact << " s, relative error "
            << period / exact - 1 << ", max | |x| - L | = " << worst << " m\n";
  EXPECT_NEAR(period / exact, 1.0, 1e-3);
  EXPECT_LE(worst, 1e-6);
}

TEST(Xpbd, ACompliantConstraintWithASolverThatIgnoresComplianceIsRefusedAtItsKey) {
  EXPECT_EQ(test::load_problems(Hanging(1e-3, 0.01, 1, "rk4")),
            "test.yaml:9:52: constraints[0].compliance: 0.001 is a compliant constraint, "
            "which solver 'rk4' treats as rigid (expected compliance 0, or a solver that "
            "honours it, e.g. solver: { type: xpbd })");
  EXPECT_EQ(test::load_problems(Hanging(-1.0, 0.01, 1)),
            "test.yaml:9:52: constraints[0].compliance: -1.000000 is not a compliance (expected a "
            "finite number >= 0, in the row's unit per newton; 0 = rigid)");
}

TEST(Verlet, ConstraintsOtherThanRattleOrForceAreRefused) {
  EXPECT_EQ(test::load_problems("simulation: { dt: 0.01, steps: 1, solver: { type: verlet, "
                                "constraints: shake } }\n"
                                "particles:\n  - { position: [0, 0, 0], mass: 1 }\n"),
            "test.yaml:1:72: simulation.solver.constraints: 'shake' is not a way to keep "
            "constraints (expected rattle or force)");
}

}  // namespace xpbd_test
}  // namespace pdyn
