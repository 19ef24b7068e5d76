// Plugin faults at run time, with the fixture plugins of tests/fixtures/
// (folder faults/, loaded with --plugin-path):
//   throwing_force     add_forces throws std::runtime_error after `after` calls
//   throwing_collider  respond throws after `after` calls
//   nan_force          adds a NaN force to particle `particle` after `after` calls
//   throwing_solver    explicit Euler whose step throws after `after` steps
//                      (std::runtime_error, or an int with non_standard: true)
//
// A throwing plugin stops the run with exit 3 and one line naming the
// plugin, its scene location (file:line:column) and the step; the last good
// state is the final frame and is checkpointed, bit-identical to the state
// a run without the faulty plugin reaches at that step. A NaN force stops
// the run with exit 4 naming the force (found by replaying the step with
// finite checks) and the particle. Checked for every shipped solver, with
// exact steps for rk4.
#include <gtest/gtest.h>

#include "host/resume_support.hpp"

namespace pdyn {
namespace {

namespace fs = std::filesystem;
using namespace pdyn::test;

constexpr int kFaultParticles = 36;
constexpr double kFaultDt = 0.001;

std::string faults_dir() { return (fs::path(PDYN_FIXTURE_DIR) / "faults").string(); }

// The sheet scene with `line` added at the end of its forces (or, for a
// collider, its colliders). Returns the scene and the 1-based line number of
// the added entry.
std::pair<std::string, int> scene_with(const std::string& solver, const std::string& line,
                                       bool collider = false) {
  std::string s = sheet_scene(solver, /*every=*/3, /*ckpt_every=*/0, kFaultDt);
  const std::string anchor = collider ? "restitution: 0.3 }\n" : "  - { type: drag, k: 0.001 }\n";
  const auto at = s.find(anchor);
  EXPECT_NE(at, std::string::npos);
  const std::size_t insert = at + anchor.size();
  const int line_no =
      static_cast<int>(std::count(s.begin(), s.begin() + static_cast<long>(insert), '\n')) + 1;
  s.insert(insert, line + "\n");
  return {s, line_no};
}

struct Fault {
  CommandResult result;
  fs::path dir;
};

Fault run_faulty(const std::string& name, const std::string& scene, std::int64_t steps = 200) {
  const fs::path dir = temp_dir("fault-" + name);
  write_file(dir / "scene.yaml", scene);
  auto r = pdyn_in(dir, {"run", "scene.yaml", "--steps", std::to_string(steps), "-q",
                         "--plugin-path", faults_dir()});
  return {r, dir};
}

// The checkpoint of a plain sheet run (no faulty plugin) stopped at `step`.
// `extra`: more arguments for `pdyn run` (--set overrides).
Checkpoint plain_state_at(const std::string& solver, std::int64_t step,
                          const std::vector<std::string>& extra = {}) {
  const fs::path dir = temp_dir("fault-plain-" + solver);
  write_file(dir / "scene.yaml", sheet_scene(solver, 3, 0, kFaultDt));
  std::vector<std::string> args = {"run", "scene.yaml", "--steps", std::to_string(step), "-q"};
  args.insert(args.end(), extra.begin(), extra.end());
  auto r = pdyn_in(dir, args);
  EXPECT_EQ(r.status, 0) << r.err;
  return read_checkpoint(dir / "out/run.ckpt");
}

// Exit 3: one line naming `plugin`, its location, its library and the step; returns the
// step, after checking the last good frame and the checkpoint.
std::int64_t expect_plugin_fault(const Fault& f, const std::string& plugin, int line,
                                 const std::string& hook) {
  const auto& r = f.result;
  EXPECT_EQ(r.status, 3) << r.err;
  const auto lines = lines_of(r.err);
  EXPECT_EQ(lines.size(), 1u) << r.err;
  EXPECT_TRUE(contains(r.err, "plugin " + plugin + " (scene.yaml:" + std::to_string(line) + ":"))
      << r.err;
  EXPECT_TRUE(contains(r.err, hook + " threw: fixture")) << r.err;
  // ... and the library it came from.
  EXPECT_TRUE(contains(r.err, "/faults/pdyn_")) << r.err;
  EXPECT_TRUE(contains(r.err, "_" + plugin + ".so)")) << r.err;
  EXPECT_TRUE(contains(r.err, "the last good frame and a checkpoint")) << r.err;
  const auto at = r.err.find(" at step ");
  if (at == std::string::npos) {
    ADD_FAILURE() << "no step in: " << r.err;
    return -1;
  }
  const std::int64_t step = std::stoll(r.err.substr(at + 9));
  // The last good frame (step - 1) ends the frames file; the checkpoint
  // holds that state.
  double last_t = -1;
  EXPECT_GT(check_frames_file(f.dir / "out/frames.csv", kFaultParticles, &last_t), 0);
  EXPECT_TRUE(fs::exists(f.dir / "out/run.ckpt"));
  const Checkpoint c = read_checkpoint(f.dir / "out/run.ckpt");
  EXPECT_EQ(c.step, step - 1);
  EXPECT_EQ(c.time, last_t);
  EXPECT_TRUE(c.state.allFinite());
  EXPECT_TRUE(contains(r.err, "(out/run.ckpt)")) << r.err;
  return step;
}

TEST(PluginFaults, ThrowingForceStopsWithExit3) {
  int tested = 0;
  for (const std::string& solver : shipped_solvers()) {
    SCOPED_TRACE("solver " + solver);
    const auto [scene, line] = scene_with(solver, "  - { type: throwing_force, after: 40 }");
    const Fault f = run_faulty("force-" + solver, scene);
    const std::int64_t step = expect_plugin_fault(f, "throwing_force", line, "add_forces");
    ASSERT_GT(step, 0);
    // The original failure is reported, even when a solver that called the
    // force directly (finite differences) made it look like its own.
    EXPECT_TRUE(contains(f.result.err, "fixture failure on call 41")) << f.result.err;
    if (solver == "rk4") {
      // Four evaluations a step: calls 1-40 are steps 1-10, call 41 is step 11.
      EXPECT_EQ(step, 11);
      double last_t = -1;
      EXPECT_EQ(check_frames_file(f.dir / "out/frames.csv", kFaultParticles, &last_t), 5)
          << "frames at steps 0, 3, 6, 9 and the last good one, 10";
      EXPECT_EQ(last_t, 10 * kFaultDt);
    }
    if (!solver_is_adaptive(solver)) {
      // The throwing force added nothing before it threw: the checkpointed
      // last good state is exactly the plain scene's at that step.
      // implicit_euler solves by CG when a force has no Jacobians, as the
      // throwing force has none (linear_solver: auto): so must the plain run.
      const Checkpoint c = read_checkpoint(f.dir / "out/run.ckpt");
      const std::vector<std::string> same_solve =
          solver == "implicit_euler"
              ? std::vector<std::string>{"--set", "simulation.solver.linear_solver=cg"}
              : std::vector<std::string>{};
      EXPECT_TRUE(same_bits(c.state, plain_state_at(solver, step - 1, same_solve).state));
    }
    ++tested;
  }
  EXPECT_GE(tested, 3);
}

TEST(PluginFaults, ThrowingColliderStopsWithExit3) {
  const auto [scene, line] =
      scene_with("rk4", "  - { type: throwing_collider, after: 5 }", /*collider=*/true);
  const Fault f = run_faulty("collider", scene);
  const std::int64_t step = expect_plugin_fault(f, "throwing_collider", line, "respond");
  EXPECT_EQ(step, 6);  // respond runs once a step
  EXPECT_TRUE(
      same_bits(read_checkpoint(f.dir / "out/run.ckpt").state, plain_state_at("rk4", 5).state));
}

TEST(PluginFaults, ThrowingSolverStopsWithExit3) {
  for (bool non_standard : {false, true}) {
    SCOPED_TRACE(non_standard ? "throws an int" : "throws std::runtime_error");
    std::string scene = sheet_scene("throwing_solver", 3, 0, kFaultDt);
    const std::string plain = "{ type: throwing_solver }";
    scene.replace(scene.find(plain), plain.size(),
                  std::string("{ type: throwing_solver, after: 5, non_standard: ") +
                      (non_standard ? "true" : "false") + " }");
    const Fault f = run_faulty(non_standard ? "solver-int" : "solver", scene);
    const auto& r = f.result;
    EXPECT_EQ(r.status, 3) << r.err;
    EXPECT_EQ(lines_of(r.err).size(), 1u) << r.err;
    EXPECT_TRUE(contains(r.err, "plugin throwing_solver (scene.yaml:4:")) << r.err;
    EXPECT_TRUE(contains(r.err, "/faults/pdyn_solver_throwing_solver.so)")) << r.err;
    EXPECT_TRUE(contains(r.err, non_standard ? "non-standard exception at step 6"
                                             : "step threw at step 6: fixture solver failure"))
        << r.err;
    double last_t = -1;
    EXPECT_EQ(check_frames_file(f.dir / "out/frames.csv", kFaultParticles, &last_t), 3)
        << "frames at steps 0 and 3 and the last good one, 5";
    EXPECT_EQ(last_t, 5 * kFaultDt);
    const Checkpoint c = read_checkpoint(f.dir / "out/run.ckpt");
    EXPECT_EQ(c.step, 5);
    EXPECT_EQ(c.time, 5 * kFaultDt);
  }
}

TEST(PluginFaults, NaNForceIsNamed) {
  int tested = 0;
  for (const std::string& solver : shipped_solvers()) {
    SCOPED_TRACE("solver " + solver);
    const auto [scene, line] =
        scene_with(solver, "  - { type: nan_force, after: 40, particle: 7 }");
    const Fault f = run_faulty("nan-" + solver, scene);
    const auto& r = f.result;
    EXPECT_EQ(r.status, 4) << r.err;
    EXPECT_EQ(lines_of(r.err).size(), 1u) << r.err;
    EXPECT_TRUE(contains(r.err, "non-finite")) << r.err;
    EXPECT_TRUE(contains(r.err, "nan_force (scene.yaml:" + std::to_string(line) + ":")) << r.err;
    EXPECT_TRUE(contains(r.err, "non-finite force on particle 7")) << r.err;
    // The last good state is the final frame, complete and finite.
    double last_t = -1;
    EXPECT_GT(check_frames_file(f.dir / "out/frames.csv", kFaultParticles, &last_t), 0);
    const auto frames = lines_of(read_bytes(f.dir / "out/frames.csv"));
    for (std::size_t i = frames.size() - kFaultParticles; i < frames.size(); ++i) {
      EXPECT_EQ(frames[i].find("nan"), std::string::npos) << frames[i];
    }
    if (solver == "rk4") {
      EXPECT_TRUE(contains(r.err, "at step 11")) << r.err;
      EXPECT_EQ(last_t, 10 * kFaultDt);
    }
    ++tested;
  }
  EXPECT_GE(tested, 3);
}

}  // namespace
}  // namespace pdyn
