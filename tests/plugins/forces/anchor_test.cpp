// The anchor plugin (damped springs to points in space) and its
// MovableTargets interface (pdyn/targets.hpp):
//  - a host finds the interface with dynamic_cast across the plugin
//    boundary and moves a target while the simulation runs: the particle is
//    pulled towards the new point and, damped, settles there;
//  - save_state()/restore_state() carry the moved targets: a system
//    restored from them continues bit-identically, and without them it
//    would not; the same through a checkpoint file written by the runner;
//  - the force law on one particle with a known stretch.
#include <gtest/gtest.h>

#include <iostream>

#include "pdyn/host/runner.hpp"
#include "pdyn/targets.hpp"
#include "plugins/forces/force_support.hpp"

namespace pdyn {
namespace {

const char* kScene = R"(
simulation: { dt: 0.01, steps: 1, solver: { type: rk4 } }
particles:
  - { position: [0, 0, 0], mass: 1 }
  - { position: [0, 1, 0], mass: 1 }
forces:
  - { type: anchor, ids: [0, 1], points: [[0, 0, 0], [0, 1, 0]], ks: 40, kd: 8 }
)";

MovableTargets& TargetsOf(Scene& scene) {
  MovableTargets* t = movable_targets(*scene.system->force_objects().at(0).force);
  if (!t) throw std::logic_error("anchor does not expose MovableTargets");
  return *t;
}

TEST(AnchorForce, MovedTargetPullsTheParticleThere) {
  Scene scene = test::load_text(kScene);
  MovableTargets& targets = TargetsOf(scene);
  ASSERT_EQ(targets.target_count(), 2u);
  EXPECT_EQ(targets.target(1), Vec3(0, 1, 0));
  for (int s = 1; s <= 10; ++s) test::TakeStep(scene, s, 0.01);
  EXPECT_EQ(Vec3(scene.system->positions().col(0)), Vec3(0, 0, 0))
      << "at its target and at rest, the particle stays";
  targets.set_target(0, Vec3(0.5, 0, 0));  // the "mouse" moves
  test::TakeStep(scene, 11, 0.01);
  const double x_after_one = scene.system->positions()(0, 0);
  EXPECT_GT(x_after_one, 0.0) << "pulled towards +x";
  // Critically damped (kd = 2 sqrt(ks m) = 12.6 > 8: slightly under):
  // after 3 s it has settled at the new target; the other one never moved.
  for (int s = 12; s <= 310; ++s) test::TakeStep(scene, s, 0.01);
  const double miss = (Vec3(scene.system->positions().col(0)) - Vec3(0.5, 0, 0)).norm();
  std::cout << "anchor: after moving the target by 0.5 m, |x - target| at 3 s = " << miss << " m\n";
  EXPECT_LE(miss, 1e-4);
  EXPECT_EQ(Vec3(scene.system->positions().col(1)), Vec3(0, 1, 0));
  EXPECT_THROW(targets.set_target(2, Vec3::Zero()), Error);
  EXPECT_THROW(targets.set_target(0, Vec3(std::nan(""), 0, 0)), Error);
}

TEST(AnchorForce, SaveAndRestoreCarryMovedTargets) {
  Scene a = test::load_text(kScene), b = test::load_text(kScene), c = test::load_text(kScene);
  TargetsOf(a).set_target(0, Vec3(0.3, -0.2, 0.1));
  TargetsOf(a).set_target(1, Vec3(-1, 2, 0.5));
  for (int s = 1; s <= 20; ++s) test::TakeStep(a, s, 0.01);
  // b and c get a's particle state and time; only b gets its force's state.
  const auto bytes = a.system->force_objects().at(0).force->save_state();
  EXPECT_EQ(bytes.size(), 2u * 3u * sizeof(double));
  for (Scene* s : {&b, &c}) {
    s->system->set_state(a.system->state());
    s->system->set_time(a.system->time());
  }
  b.system->force_objects().at(0).force->restore_state(bytes);
  EXPECT_EQ(TargetsOf(b).target(1), Vec3(-1, 2, 0.5));
  for (int s = 21; s <= 40; ++s) {
    test::TakeStep(a, s, 0.01);
    test::TakeStep(b, s, 0.01);
    test::TakeStep(c, s, 0.01);
  }
  EXPECT_EQ(a.system->state(), b.system->state()) << "restored: bit-identical";
  EXPECT_NE(a.system->state(), c.system->state()) << "without the targets it would differ";
  const std::vector<std::uint8_t> short_bytes(bytes.begin(), bytes.end() - 1);
  EXPECT_THROW(b.system->force_objects().at(0).force->restore_state(short_bytes), Error);
}

// The runner writes the anchor's moved targets into its checkpoint; a fresh
// scene restored from the file has them and continues exactly like a run
// that was never stopped.
TEST(AnchorForce, CheckpointCarriesMovedTargets) {
  const auto dir = test::temp_dir("anchor-checkpoint");
  const std::string ckpt = (dir / "run.ckpt").string();
  const std::vector<Override> first = {{"simulation.steps", "20"},
                                       {"output", "{checkpoint: {path: " + ckpt + "}}"}};
  Scene a = test::load_text(kScene, first);
  TargetsOf(a).set_target(0, Vec3(0.3, -0.2, 0.1));
  ASSERT_EQ(run_scene(a).exit_code, 0);
  Scene whole = test::load_text(kScene);  // the uninterrupted run
  TargetsOf(whole).set_target(0, Vec3(0.3, -0.2, 0.1));
  for (int s = 1; s <= 40; ++s) test::TakeStep(whole, s, 0.01);
  Scene b = test::load_text(
      kScene, {{"simulation.steps", "40"}, {"output", "{checkpoint: {path: " + ckpt + "}}"}});
  restore_checkpoint(b, read_checkpoint(ckpt), false);
  EXPECT_EQ(TargetsOf(b).target(0), Vec3(0.3, -0.2, 0.1));
  EXPECT_EQ(b.system->time(), 0.2);
  for (int s = 21; s <= 40; ++s) test::TakeStep(b, s, 0.01);
  EXPECT_EQ(b.system->state(), whole.system->state()) << "resumed: bit-identical";
}

// d = (3, 4, 0) m from the target, rest 1 m, ks = 2 N/m: |f| = ks (5 - 1) =
// 8 N towards the target; U = 16 J; with velocity (1, 0, 0), kd = 0.5 adds
// -0.5 N along x.
TEST(AnchorForce, ForceLawOnAKnownStretch) {
  Scene scene = test::load_text(R"(
simulation: { dt: 0.01, steps: 1 }
particles:
  - { position: [4, 5, 1], velocity: [1, 0, 0], mass: 1 }
forces:
  - { type: anchor, ids: [0], points: [[1, 1, 1]], ks: 2, kd: 0.5, rest: 1 }
)");
  const Matrix3X f = test::ForcesOf(*scene.system, 0);
  EXPECT_NEAR((Vec3(f.col(0)) - Vec3(-4.8 - 0.5, -6.4, 0)).norm(), 0.0, 1e-14);
  EXPECT_NEAR(scene.system->potential_energy(), 16.0, 1e-14);
}

}  // namespace
}  // namespace pdyn
