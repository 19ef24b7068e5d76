// verlet's reuse_forces: one force evaluation per step when the forces
// depend on positions only, with exactly the states of the two-evaluation
// form; a fresh a0 after a host moved particles; and none when a collider's velocity-dependent
// contact force takes part.
#include <gtest/gtest.h>

#include "pdyn/stepper.hpp"
#include "support/test_support.hpp"

namespace pdyn {
namespace {

// A Lennard-Jones cluster of 27 particles under gravity in open space (both
// forces depend on positions only), with or without a floor below it.
Scene cluster(bool reuse, bool floor) {
  std::string s = "simulation: { dt: 0.002, steps: 1, solver: { type: verlet, reuse_forces: " +
                  std::string(reuse ? "true" : "false") + " } }\nparticles:\n";
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b)
      for (int c = 0; c < 3; ++c)
        s += "  - { position: [" + std::to_string(1.12 * a) + ", " + std::to_string(1.12 * b) +
             ", " + std::to_string(1.12 * c + 0.05 * a) + "], mass: 1 }\n";
  s += "forces:\n  - { type: lennard_jones }\n  - { type: gravity, g: [0, 0, -9.81] }\n";
  if (floor) s += "colliders:\n  - { type: plane, point: [0, 0, -0.3], restitution: 0.5 }\n";
  return test::load_text(s);
}

std::uint64_t run(Scene& scene, int steps) {
  Stepper stepper(*scene.system, *scene.solver, scene.solver_label);
  for (int k = 1; k <= steps; ++k) EXPECT_TRUE(stepper.step_to(k * 0.002).has_value()) << k;
  return scene.system->force_evaluations();
}

TEST(VerletReuse, OneEvaluationPerStepAndTheSameStatesBitForBit) {
  Scene twice = cluster(false, false), once = cluster(true, false);
  EXPECT_EQ(run(twice, 200), 400u);
  EXPECT_EQ(run(once, 200), 201u);  // the first step has no a1 to reuse
  EXPECT_TRUE(once.system->state().cwiseEqual(twice.system->state()).all());
}

// A host that moves a particle between steps (the viewer's drag, a reset):
// the next step evaluates a0 at the new positions.
TEST(VerletReuse, PositionsChangedBetweenStepsAreEvaluatedAfresh) {
  Scene twice = cluster(false, false), once = cluster(true, false);
  Stepper a(*twice.system, *twice.solver, twice.solver_label);
  Stepper b(*once.system, *once.solver, once.solver_label);
  for (int k = 1; k <= 50; ++k) {
    if (k == 25) {
      twice.system->positions()(0, 3) += 0.01;
      once.system->positions()(0, 3) += 0.01;
    }
    ASSERT_TRUE(a.step_to(k * 0.002).has_value());
    ASSERT_TRUE(b.step_to(k * 0.002).has_value());
  }
  EXPECT_EQ(once.system->force_evaluations(), 52u);  // first step and step 25 evaluate a0
  EXPECT_TRUE(once.system->state().cwiseEqual(twice.system->state()).all());
}

// Colliders' contact forces depend on velocity: with one, every step
// evaluates a0, and the run is the two-evaluation run.
TEST(VerletReuse, AColliderSwitchesReuseOff) {
  Scene twice = cluster(false, true), once = cluster(true, true);
  EXPECT_EQ(run(twice, 300), 600u);
  EXPECT_EQ(run(once, 300), 600u);
  EXPECT_TRUE(once.system->state().cwiseEqual(twice.system->state()).all());
}

}  // namespace
}  // namespace pdyn
