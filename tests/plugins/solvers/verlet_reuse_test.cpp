// verlet's one force evaluation per step (issue 17, item 5): the end-of-step
// accelerations are reused as the next step's a0 when every force declares
// that it does not read velocities (Force::dependence) and nothing but the
// kernel's step touched the System since (System::state_version). Each test
// compares with the same scene plus a force that adds nothing but keeps the
// default claim (it depends on velocity and time), which makes verlet
// evaluate a0 afresh every step, as it did before: the states must be the
// same bits, and only the evaluation counts differ.
#include <gtest/gtest.h>

#include <iostream>
#include <memory>

#include "pdyn/host/assembly.hpp"
#include "pdyn/host/stepper.hpp"
#include "pdyn/system.hpp"
#include "plugins/solvers/solver_support.hpp"
#include "support/physics_support.hpp"
#include "support/test_support.hpp"

namespace pdyn {
namespace {

void add_nothing(Scene& scene) {
  SystemAssembly(*scene.system).add_force(std::make_shared<test::Nothing>(), "nothing");
}

// A Lennard-Jones cluster of 27 particles under gravity (both forces depend
// on positions only), `extra` appended to the scene text (colliders, a
// periodic box, more forces, solver parameters).
Scene cluster(const std::string& solver = "{ type: verlet }", const std::string& extra = "") {
  return test::LjCluster(solver, extra);
}

std::uint64_t run(Scene& scene, int steps, double dt = 0.002) {
  Stepper stepper(*scene.system, *scene.solver, scene.solver_label);
  for (int k = 1; k <= steps; ++k) EXPECT_TRUE(stepper.step_to(k * dt).has_value()) << k;
  return scene.system->force_evaluations();
}

bool same_bits(const Scene& a, const Scene& b) {
  return a.system->state().cwiseEqual(b.system->state()).all() &&
         a.system->time() == b.system->time();
}

TEST(VerletReuse, OneEvaluationPerStepAndTheSameStatesBitForBit) {
  Scene twice = cluster(), once = cluster();
  add_nothing(twice);
  EXPECT_EQ(run(twice, 200), 400u);
  EXPECT_EQ(run(once, 200), 201u);  // the first step has no a1 to reuse
  EXPECT_TRUE(same_bits(once, twice));
}

// The cloth: undamped springs (kd = 0 declares no velocity
// dependence) and gravity, two pinned corners.
TEST(VerletReuse, UndampedClothOneEvaluationPerStep) {
  auto cloth = [] {
    return test::load_shared("cloth.yaml", {{"particles[0].grid.nx", "30"},
                                            {"particles[0].grid.ny", "30"},
                                            {"particles[0].grid.springs.structural.kd", "0"},
                                            {"particles[0].grid.springs.shear.kd", "0"},
                                            {"forces", "[{ type: gravity, g: [0, 0, -9.81] }]"},
                                            {"simulation.solver", "{ type: verlet }"}});
  };
  Scene twice = cloth(), once = cloth();
  add_nothing(twice);
  EXPECT_EQ(run(twice, 300, 0.0002), 600u);
  EXPECT_EQ(run(once, 300, 0.0002), 301u);
  EXPECT_TRUE(same_bits(once, twice));
  // Damped springs read velocities: every step evaluates a0.
  Scene damped = test::load_shared("cloth.yaml", {{"particles[0].grid.nx", "30"},
                                                  {"particles[0].grid.ny", "30"},
                                                  {"simulation.solver", "{ type: verlet }"}});
  EXPECT_EQ(run(damped, 10, 0.0002), 20u);
}

// A host that moves a particle between steps (the viewer's drag, a reset)
// through a writable view: the next step evaluates a0 at the new positions.
// A view kept from before is written through and then declared with touch().
TEST(VerletReuse, WritesBetweenStepsAreEvaluatedAfresh) {
  Scene twice = cluster(), once = cluster();
  add_nothing(twice);
  Stepper a(*twice.system, *twice.solver, twice.solver_label);
  Stepper b(*once.system, *once.solver, once.solver_label);
  auto kept = once.system->positions();
  for (int k = 1; k <= 50; ++k) {
    if (k == 20) {
      twice.system->positions()(0, 3) += 0.01;
      once.system->positions()(0, 3) += 0.01;
    }
    if (k == 30) {
      twice.system->positions()(1, 5) -= 0.01;
      kept(1, 5) -= 0.01;
      once.system->touch();
    }
    ASSERT_TRUE(a.step_to(k * 0.002).has_value());
    ASSERT_TRUE(b.step_to(k * 0.002).has_value());
  }
  EXPECT_EQ(once.system->force_evaluations(), 53u);  // steps 1, 20 and 30 evaluate a0
  EXPECT_TRUE(same_bits(once, twice));
}

// Colliders' contact forces depend on velocity: with one, every step
// evaluates a0, and the run is the two-evaluation run.
TEST(VerletReuse, AColliderSwitchesReuseOff) {
  const std::string floor =
      "colliders:\n  - { type: plane, point: [0, 0, -0.3], restitution: 0.5 }\n";
  Scene twice = cluster("{ type: verlet }", floor), once = cluster("{ type: verlet }", floor);
  add_nothing(twice);
  EXPECT_EQ(run(twice, 300), 600u);
  EXPECT_EQ(run(once, 300), 600u);
  EXPECT_TRUE(same_bits(once, twice));
}

// A force that adds nothing, reads positions only (so it does not stop the
// reuse), and is not periodic-invariant (like a spring across a face).
class PositionsOnlyNothing final : public Force {
 public:
  void add_forces(const ParticleView&, Eigen::Ref<Matrix3X>) override {}
  StateDependence dependence() const override { return {false, false}; }
};

// In a periodic box the kernel wraps particles after a step. Lennard-Jones
// and gravity are periodic-invariant (pdyn/periodic_invariant.hpp): the
// forces evaluated before a wrap are kept, one evaluation per step, and the
// run differs from one that evaluates afresh by rounding only. With a force
// that is not invariant, a wrap that moved a particle makes the next step
// evaluate again, and the run is the afresh run's bits.
TEST(VerletReuse, AWrapKeepsTheForcesOnlyWhenEveryForceIsPeriodicInvariant) {
  const std::string solver =
      "{ type: verlet }, box: { min: [-0.6, -0.6, -0.6], max: [5.2, 5.2, 5.2], periodic: "
      "[true, true, true] }";
  Scene twice = cluster(solver), once = cluster(solver), mixed = cluster(solver);
  add_nothing(twice);
  SystemAssembly(*mixed.system).add_force(std::make_shared<PositionsOnlyNothing>(), "positions");
  EXPECT_EQ(run(twice, 400), 800u);
  EXPECT_EQ(run(once, 400), 401u);  // the wraps cost nothing
  const std::uint64_t evaluations = run(mixed, 400);
  EXPECT_GT(evaluations, 401u);  // some steps wrapped a particle (it falls)
  EXPECT_LT(evaluations, 500u);  // most did not
  EXPECT_TRUE(same_bits(mixed, twice));
  const double apart = (once.system->state() - twice.system->state()).cwiseAbs().maxCoeff();
  std::cout << "verlet across wraps: 401 evaluations, max |state - afresh| = " << apart << "\n";
  EXPECT_LE(apart, 1e-9);
  bool wrapped = false;
  for (const auto& im : once.system->images()) wrapped = wrapped || im[2] != 0;
  EXPECT_TRUE(wrapped);
}

// Bonded terms are measured at their particles' nearest images, so a
// BondedForce is periodic-invariant too (pdyn/bonded_force.hpp): the
// Kremer-Grest melt of tests/scenes/special (WCA pairs, FENE bonds across
// the faces of its periodic box) evaluates once per step although beads
// cross the faces, and still follows LAMMPS (tests/host/special_bonds_test.cpp).
TEST(VerletReuse, BondedTermsAcrossWrapsKeepTheForces) {
  Scene melt = load_scene(test::source_path("tests/scenes/special/kg.yaml"),
                          test::shipped_plugins(), {{"output", "[]"}});
  const auto images = melt.system->images();
  EXPECT_EQ(run(melt, 100, 0.005), 101u);
  EXPECT_NE(melt.system->images(), images);  // some bead crossed a face
}

// A force of time but not velocity: a1 is reused only if the next step
// starts at exactly the time it was evaluated at. (The Stepper's step times
// always match: t + (k dt - t) is k dt exactly when t is (k - 1) dt, by
// Sterbenz's lemma.) A host that sets the time between steps is seen;
// forces of neither velocity nor time do not mind.
TEST(VerletReuse, TimeDependentForcesNeedTheSameTime) {
  auto load = [] {
    return test::load_text(
        "simulation: { dt: 0.1, steps: 1, solver: { type: verlet } }\n"
        "particles:\n  - { position: [0, 0, 0], mass: 2 }\n  - { position: [1, 0, 0], mass: 1 }\n"
        "forces:\n  - { type: field, force: ['-x + sin(t)', '-y', '-z'] }\n");
  };
  auto run_with_jump = [](Scene& scene) {
    Stepper stepper(*scene.system, *scene.solver, scene.solver_label);
    for (int k = 1; k <= 100; ++k) {
      const double jump = k > 40 ? 0.05 : 0.0;
      if (k == 41) scene.system->set_time(scene.system->time() + jump);
      EXPECT_TRUE(stepper.step_to(k * 0.1 + jump).has_value()) << k;
    }
    return scene.system->force_evaluations();
  };
  Scene twice = load(), once = load();
  add_nothing(twice);
  EXPECT_EQ(run_with_jump(twice), 200u);
  EXPECT_EQ(run_with_jump(once), 102u);  // steps 1 and 41 evaluate a0
  EXPECT_TRUE(same_bits(once, twice));
  Scene timeless = cluster();
  EXPECT_EQ(run_with_jump(timeless), 101u);
}

// reuse_forces: true is the scene's promise for forces that do not declare:
// one evaluation per step although `Nothing` claims velocity dependence.
TEST(VerletReuse, ThePromiseCoversUndeclaredForces) {
  Scene promised = cluster("{ type: verlet, reuse_forces: true }");
  add_nothing(promised);
  Scene twice = cluster();
  add_nothing(twice);
  EXPECT_EQ(run(promised, 200), 201u);
  EXPECT_EQ(run(twice, 200), 400u);
  EXPECT_TRUE(same_bits(promised, twice));
}

// `pdyn run` with writers, energy output and checkpoints: reading the state
// for output does not count as a write, so the run still evaluates once per
// step.
TEST(VerletReuse, ARunWithOutputEvaluatesOncePerStep) {
  const auto dir = test::temp_dir("verlet_reuse_run");
  Scene scene = test::load_shared(
      "cloth.yaml", {{"particles[0].grid.nx", "20"},
                     {"particles[0].grid.ny", "20"},
                     {"particles[0].grid.springs.structural.kd", "0"},
                     {"particles[0].grid.springs.shear.kd", "0"},
                     {"forces", "[{ type: gravity, g: [0, 0, -9.81] }]"},
                     {"simulation.solver", "{ type: verlet }"},
                     {"simulation.steps", "200"},
                     {"output", "[{ type: vtk, path: " + (dir / "run.pvd").string() +
                                    ", every: 10 }, { type: energy, path: " +
                                    (dir / "energy.csv").string() + ", every: 5 }]"},
                     {"checkpoint", "{ path: " + (dir / "run.ckpt").string() + ", every: 50 }"}});
  const RunResult r = run_scene(scene);
  ASSERT_EQ(r.exit_code, 0) << r.message;
  EXPECT_EQ(r.steps_done, 200);
  EXPECT_EQ(scene.system->force_evaluations(), 201u);
}

}  // namespace
}  // namespace pdyn
