// Determinism across thread counts: a cloth stepped with 1, 2, 3 and 4
// threads ends in bit-identical states, for every shipped explicit solver
// that splits its updates over threads (pdyn/parallel.hpp, the spring
// plugin's blocks and boundary gather). The cloth, the shared hanging cloth
// of tests/scenes/shared/cloth.yaml, is made large enough (96 x 96
// particles: three spring blocks of 4096 particles, 54 000 springs) that
// every parallel path is taken, not its serial fallback.
#include <gtest/gtest.h>

#include <cstring>
#include <pdyn/host/threads.hpp>
#include <pdyn/parallel.hpp>

#include "support/test_support.hpp"

namespace pdyn::test {
namespace {

// The shared hanging cloth (tests/scenes/shared/cloth.yaml) at 96 x 96,
// with bend springs as well and a floor plane just below it.
Scene cloth(const std::string& solver, int steps, std::vector<Override> overrides = {}) {
  std::vector<Override> all = {
      {"simulation.steps", std::to_string(steps)},
      {"simulation.solver", "{ type: " + solver + " }"},
      {"particles[0].grid.nx", "96"},
      {"particles[0].grid.ny", "96"},
      {"particles[0].grid.springs.bend", "{ ks: 100, kd: 0.002 }"},
      {"colliders", "[{ type: plane, point: [0, 0, 0.99], normal: [0, 0, 1], restitution: 0.5 }]"}};
  all.insert(all.end(), overrides.begin(), overrides.end());
  return load_shared("cloth.yaml", all);
}

Eigen::VectorXd run_with(const std::string& solver, int threads, int steps = 8) {
  Scene scene = cloth(solver, steps);
  RunOptions options;
  options.threads = threads;
  const RunResult r = run_scene(scene, options);
  EXPECT_EQ(r.exit_code, 0) << r.message;
  EXPECT_EQ(max_threads(), threads);  // the count reached OpenMP
  return scene.system->state();
}

bool bit_identical(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return a.size() == b.size() &&
         std::memcmp(a.data(), b.data(), sizeof(double) * static_cast<std::size_t>(a.size())) == 0;
}

class Determinism : public ::testing::TestWithParam<std::string> {};

TEST_P(Determinism, SameBitsForOneToFourThreads) {
  const Eigen::VectorXd one = run_with(GetParam(), 1);
  const Scene initial = cloth(GetParam(), 1);
  ASSERT_FALSE(bit_identical(one, initial.system->state())) << "the cloth did not move";
  for (int threads : {2, 3, 4}) {
    const Eigen::VectorXd many = run_with(GetParam(), threads);
    ASSERT_TRUE(bit_identical(one, many))
        << threads << " threads differ from 1, max |diff| = " << (one - many).cwiseAbs().maxCoeff();
  }
}

INSTANTIATE_TEST_SUITE_P(ExplicitSolvers, Determinism,
                         ::testing::Values("rk4", "midpoint", "euler", "verlet",
                                           "symplectic_euler"));

TEST(Threads, SceneSettingIsUsedAndCommandLineWins) {
  Scene scene = load_text(
      "simulation: { dt: 0.01, steps: 2, threads: 3 }\n"
      "particles: [ { position: [0, 0, 1], mass: 1 } ]\n");
  EXPECT_EQ(scene.threads, 3);
  run_scene(scene);
  EXPECT_EQ(max_threads(), 3);
  RunOptions options;
  options.threads = 2;
  run_scene(scene, options);
  EXPECT_EQ(max_threads(), 2);
}

// The default: one thread per kParallelMinElements particles, at least 1,
// at most the cores other processes leave free.
TEST(Threads, DefaultFollowsTheParticleCountAndTheFreeCores) {
  Scene scene = load_text(
      "simulation: { dt: 0.01, steps: 2 }\n"
      "particles: [ { position: [0, 0, 1], mass: 1 } ]\n");
  run_scene(scene);
  EXPECT_EQ(max_threads(), 1);
  EXPECT_EQ(default_threads(2 * kParallelMinElements - 1), 1);
  const Index k = kParallelMinElements;
  EXPECT_EQ(threads_for(0, 4), 1);
  EXPECT_EQ(threads_for(k - 1, 4), 1);
  EXPECT_EQ(threads_for(2 * k - 1, 4), 1);
  EXPECT_EQ(threads_for(2 * k, 4), 2);
  EXPECT_EQ(threads_for(3 * k, 4), 3);
  EXPECT_EQ(threads_for(1000 * k, 4), 4);
  EXPECT_EQ(threads_for(1000 * k, 1), 1);  // the other cores are busy
  EXPECT_EQ(threads_for(1000 * k, 0), 1);  // every core is: still one
  // 9,216 particles: 2 threads where 2 cores are free (fewer when the
  // machine is busy, as under ctest -j).
  Scene big = cloth("rk4", 2);
  run_scene(big);
  EXPECT_GE(max_threads(), 1);
  EXPECT_LE(max_threads(), std::min(2, available_threads()));
}

TEST(Threads, ZeroIsRefusedWhereItIsWritten) {
  try {
    load_text(
        "simulation: { dt: 0.01, steps: 2, threads: 0 }\n"
        "particles: [ { position: [0, 0, 1], mass: 1 } ]\n");
    FAIL() << "threads: 0 was accepted";
  } catch (const SceneError& e) {
    ASSERT_EQ(e.diagnostics().size(), 1u);
    EXPECT_EQ(e.diagnostics()[0].location, "test.yaml:1:44");
    EXPECT_NE(e.diagnostics()[0].message.find("simulation.threads"), std::string::npos)
        << e.diagnostics()[0].message;
  }
}

TEST(Threads, ThreadCountIsNotPartOfTheSceneACheckpointMatches) {
  // Results do not depend on it, so a run may resume with another count.
  const Scene a = cloth("rk4", 20, {{"simulation.threads", "4"}});
  const Scene b = cloth("rk4", 20, {{"simulation.threads", "1"}});
  const Scene c = cloth("rk4", 20);
  EXPECT_EQ(a.canonical_text, b.canonical_text);
  EXPECT_EQ(a.canonical_text, c.canonical_text);
}

}  // namespace
}  // namespace pdyn::test
