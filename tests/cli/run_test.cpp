// `pdyn run` and `pdyn validate` on the command line: what they print, and
// how they refuse bad options.
#include <gtest/gtest.h>

#include <algorithm>

#include "support/test_support.hpp"

namespace pdyn {
namespace {

namespace fs = std::filesystem;

fs::path ten_step_scene(const std::string& name) {
  const fs::path dir = test::temp_dir(name);
  return test::write_file(dir / "scene.yaml",
                          "simulation: { dt: 0.01, steps: 10 }\n"
                          "particles:\n"
                          "  - { position: [0, 0, 1], mass: 1 }\n");
}

// CLI11's NonNegativeNumber printed its upper bound, DBL_MAX, in 309 digits.
TEST(RunCommand, NegativeStepsAreRefusedWithAReadableBound) {
  const fs::path scene = ten_step_scene("steps-negative");
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
  const fs::path scene = ten_step_scene("plural");
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

// A stiff chain (w = sqrt(ks / m) = 1000 rad/s) under gravity: explicit
// Euler at dt = 0.01 s (w dt = 10) multiplies the energy by about 100 per
// step, so 100 steps reach ~1e200 J, finite all the way.
std::string stiff_chain(const std::string& solver, const std::string& extra_force = "") {
  return "simulation: { dt: 0.01, steps: 100, solver: { type: " + solver +
         " } }\n"
         "particles:\n"
         "  - chain: { from: [0, 0, 1], to: [1, 0, 1], n: 10, mass: 0.01, pin: [0],\n"
         "             springs: { ks: 10000, kd: 0 } }\n"
         "forces:\n"
         "  - { type: gravity }\n" +
         extra_force;
}

TEST(RunCommand, EnergyGrowingWithoutADrivingForceIsWarnedAbout) {
  const fs::path dir = test::temp_dir("energy-growth");
  const fs::path scene = test::write_file(dir / "chain.yaml", stiff_chain("euler"));
  const auto r = test::pdyn({"run", scene.string()});
  EXPECT_EQ(r.status, 0) << r.err;
  const std::string warning = "pdyn: warning: the total energy grew from 0.981 J to ";
  ASSERT_EQ(r.err.rfind(warning, 0), 0u) << r.err;
  EXPECT_NE(r.err.find("by step 64 (t = 0.64 s), more than 1e+06 times its initial scale of "
                       "0.981 J, with no force driving it: the solver 'euler' is probably "
                       "unstable at dt = 0.01 s. Try a smaller dt or a stable solver "
                       "(implicit_euler, verlet)\n"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << "warned once: " << r.err;
  // And in the run's summary.
  EXPECT_NE(r.out.find("\npdyn: warning: the total energy grew"), std::string::npos) << r.out;

  // --strict: the same run stops there with exit status 4.
  const auto strict = test::pdyn({"run", scene.string(), "--strict"});
  EXPECT_EQ(strict.status, 4) << strict.err;
  EXPECT_EQ(strict.err.rfind("pdyn: the total energy grew from 0.981 J to ", 0), 0u) << strict.err;
  EXPECT_NE(strict.err.find("(--strict: stopped here"), std::string::npos) << strict.err;
  EXPECT_EQ(strict.out, "");
}

TEST(RunCommand, NoEnergyWarningForAStableSolverOrADrivenScene) {
  const fs::path dir = test::temp_dir("energy-fine");
  const fs::path stable = test::write_file(dir / "stable.yaml", stiff_chain("implicit_euler"));
  const auto r = test::pdyn({"run", stable.string(), "--strict"});
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(r.err, "");
  // A field without a potential may inject energy: the check is off, and
  // the (diverging) run ends without a warning.
  const fs::path driven = test::write_file(
      dir / "driven.yaml",
      stiff_chain("euler", "  - { type: field, force: [\"0\", \"0.001*sin(t)\", \"0\"] }\n"));
  const auto d = test::pdyn({"run", driven.string(), "--strict"});
  EXPECT_EQ(d.status, 0) << d.err;
  EXPECT_EQ(d.err.find("energy"), std::string::npos) << d.err;
}

}  // namespace
}  // namespace pdyn
