// `pdyn run` and `pdyn validate` on the command line: what they print, and
// how they refuse bad options.
#include <gtest/gtest.h>

#include <algorithm>

#include "support/test_support.hpp"

namespace pdyn {
namespace {

namespace fs = std::filesystem;

fs::path small_scene(const std::string& name) {
  const fs::path dir = test::temp_dir(name);
  return test::write_file(dir / "scene.yaml",
                          "simulation: { dt: 0.01, steps: 10 }\n"
                          "particles:\n"
                          "  - { position: [0, 0, 1], mass: 1 }\n");
}

// CLI11's NonNegativeNumber printed its upper bound, DBL_MAX, in 309 digits.
TEST(RunCommand, NegativeStepsAreRefusedWithAReadableBound) {
  const fs::path scene = small_scene("steps-negative");
  const auto r = test::pdyn({"run", scene.string(), "--steps", "-5"});
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(r.err, "pdyn: --steps: -5 is out of range (expected at least 0) (see pdyn --help)\n");
  const auto d = test::pdyn({"run", scene.string(), "--duration", "-0.5"});
  EXPECT_EQ(d.status, 2);
  EXPECT_EQ(d.err,
            "pdyn: --duration: -0.5 is out of range (expected at least 0) (see pdyn --help)\n");
}

// Counts in the summaries read "1 particle", not "1 particles".
TEST(RunCommand, SummariesPluraliseTheirCounts) {
  const fs::path scene = small_scene("plural");
  const auto v = test::pdyn({"validate", scene.string()});
  EXPECT_EQ(v.status, 0) << v.err;
  EXPECT_EQ(v.out, scene.string() +
                       ": ok: 1 particle, 0 force objects, 0 colliders, solver rk4, 10 steps "
                       "of 0.01 s\n");
  const auto one = test::pdyn({"validate", scene.string(), "--steps", "1"});
  EXPECT_EQ(one.status, 2) << "validate has no --steps";
  const auto r = test::pdyn({"run", scene.string(), "--steps", "1"});
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(r.out.rfind("pdyn: 1 step of 1 particle with rk4 to t = 0.01 s in ", 0), 0u) << r.out;
}

// `run` prints every file it wrote, the checkpoint too; a resumed run says
// how many steps it took itself and how many there are in all.
TEST(RunCommand, PrintsTheCheckpointAndTheStepsOfAResumedRun) {
  const fs::path dir = test::temp_dir("run-checkpoint");
  const fs::path ckpt = dir / "run.ckpt";
  const fs::path scene = test::write_file(dir / "scene.yaml",
                                          "simulation: { dt: 0.01, steps: 10 }\n"
                                          "particles:\n"
                                          "  - { position: [0, 0, 1], mass: 1 }\n"
                                          "output:\n"
                                          "  checkpoint: { path: " +
                                              ckpt.string() + " }\n");
  const auto first = test::pdyn({"run", scene.string()});
  EXPECT_EQ(first.status, 0) << first.err;
  EXPECT_NE(first.out.find("\npdyn: checkpoint written to " + ckpt.string() + "\n"),
            std::string::npos)
      << first.out;
  EXPECT_EQ(first.out.rfind("pdyn: 10 steps of 1 particle with rk4 to t = 0.1 s in ", 0), 0u)
      << first.out;
  const auto resumed =
      test::pdyn({"run", scene.string(), "--steps", "25", "--resume", ckpt.string()});
  EXPECT_EQ(resumed.status, 0) << resumed.err;
  EXPECT_EQ(resumed.out.rfind("pdyn: 15 steps (resumed at step 10; 25 in all) of 1 particle with "
                              "rk4 to t = 0.25 s in ",
                              0),
            0u)
      << resumed.out;
}

}  // namespace
}  // namespace pdyn
