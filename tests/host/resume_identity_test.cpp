// Resume bit-identity, for every shipped solver (the list is read from the
// registry at run time, so solvers added to plugins/ are covered too):
//
//  * SplitRunEqualsWholeRun (fixed-step solvers): `pdyn run --steps 2N`
//    against `--steps N` with a checkpoint, then `--steps 2N --resume`. The
//    final checkpoints (state, time, step, every plugin's state, output
//    marks) and the frames and energy files must be byte-identical, whether
//    or not step N falls on a regular frame.
//  * KilledRunResumesExactly (every solver, adaptive ones included, whose
//    steps are accepted steps): a child `pdyn` writing a checkpoint every 20
//    steps is killed with SIGKILL mid-run; the run is resumed from its last
//    periodic checkpoint, continuing the output files from the temporary
//    files the killed process left, and must end byte-identical to an
//    uninterrupted run. The same checkpoint is then resumed where the
//    uninterrupted run's complete (longer) output files already exist.
//  * ResumingAtTheEndRewritesTheSameFiles: resuming a finished run with
//    nothing left to do reproduces its files, final frame included.
//  * AdaptiveCheckpointPastScheduledSteps: an adaptive solver taking more
//    accepted steps than the scene's nominal steps can still be resumed.
//  * PeriodicBoxSplitRunEqualsWholeRun, PeriodicBoxKilledRunResumesExactly:
//    the same two in a periodic box that the particles cross many times,
//    with the unwrapped columns in the frames: the checkpoint carries the
//    image counts, so the resumed files are byte-identical.
#include <gtest/gtest.h>

#include <cmath>
#include <optional>

#include "host/resume_support.hpp"
#include "pdyn/output_file.hpp"

namespace pdyn {
namespace {

namespace fs = std::filesystem;
using namespace pdyn::test;

constexpr int kResumeParticles = 36;

// Asserts two files are byte-identical (with a hint where they first differ).
void expect_same_file(const fs::path& a, const fs::path& b) {
  ASSERT_TRUE(fs::exists(a)) << a;
  ASSERT_TRUE(fs::exists(b)) << b;
  const std::string x = read_bytes(a), y = read_bytes(b);
  if (x == y) return;
  std::size_t i = 0;
  while (i < x.size() && i < y.size() && x[i] == y[i]) ++i;
  const std::size_t from = x.rfind('\n', i) == std::string::npos ? 0 : x.rfind('\n', i) + 1;
  ADD_FAILURE() << a << " (" << x.size() << " bytes) and " << b << " (" << y.size()
                << " bytes) differ from byte " << i << ":\n  "
                << x.substr(from, x.find('\n', i) - from) << "\n  "
                << y.substr(from, y.find('\n', i) - from);
}

// Asserts two checkpoints hold bit-identical simulation states.
void expect_same_state(const fs::path& a, const fs::path& b) {
  const Checkpoint x = read_checkpoint(a), y = read_checkpoint(b);
  EXPECT_EQ(x.step, y.step);
  EXPECT_EQ(std::memcmp(&x.time, &y.time, sizeof(double)), 0) << x.time << " vs " << y.time;
  EXPECT_TRUE(same_bits(x.state, y.state)) << "final states differ";
  EXPECT_TRUE(same_bits(x.mass, y.mass));
  EXPECT_EQ(x.fixed, y.fixed);
  EXPECT_EQ(x.images, y.images);
  EXPECT_EQ(x.plugin_states, y.plugin_states);
  EXPECT_EQ(x.next_frame, y.next_frame);
  ASSERT_EQ(x.outputs.size(), y.outputs.size());
  for (std::size_t k = 0; k < x.outputs.size(); ++k) {
    EXPECT_EQ(x.outputs[k].path, y.outputs[k].path);
    EXPECT_EQ(x.outputs[k].mark, y.outputs[k].mark) << x.outputs[k].path;
  }
}

// The length of out/frames.csv that checkpoint `c` recorded (the csv
// writer's mark, pdyn::FileMark).
std::uint64_t frames_bytes(const Checkpoint& c) {
  const WriterMark* m = c.output("out/frames.csv");
  return m ? FileMark::decode(m->mark).bytes : 0;
}

void expect_no_temporaries(const fs::path& out) {
  for (const char* name :
       {"frames.csv.tmp-", "energy.csv.tmp-", "run.ckpt.tmp-", "split.ckpt.tmp-"}) {
    EXPECT_TRUE(files_starting(out, name).empty())
        << "a temporary " << name << "* was left in " << out;
  }
}

TEST(ResumeIdentity, SplitRunEqualsWholeRun) {
  int tested = 0;
  for (const std::string& solver : shipped_solvers()) {
    if (solver_is_adaptive(solver)) continue;  // see KilledRunResumesExactly
    // every = 5: step N = 100 is a regular frame; every = 7: it is not, so
    // the N-step run's final frame is not one the 2N-step run writes.
    for (int every : {5, 7}) {
      SCOPED_TRACE("solver " + solver + ", a frame every " + std::to_string(every) + " steps");
      const fs::path dir = temp_dir("split-" + solver + "-" + std::to_string(every));
      write_file(dir / "scene.yaml", sheet_scene(solver, every, /*ckpt_every=*/0));
      const std::string set = "output.checkpoint={path: out/split.ckpt}";

      // The whole run, moved aside as the reference.
      auto whole = pdyn_in(dir, {"run", "scene.yaml", "--steps", "200", "--set", set, "-q"});
      ASSERT_EQ(whole.status, 0) << whole.err;
      fs::create_directories(dir / "ref");
      for (const char* f : {"frames.csv", "energy.csv", "split.ckpt"}) {
        fs::rename(dir / "out" / f, dir / "ref" / f);
      }
      // Half of it with a checkpoint at its end, then the rest resumed.
      auto first = pdyn_in(dir, {"run", "scene.yaml", "--steps", "100", "--set", set, "-q"});
      ASSERT_EQ(first.status, 0) << first.err;
      const Checkpoint half = read_checkpoint(dir / "out/split.ckpt");
      EXPECT_EQ(half.step, 100);
      EXPECT_EQ(half.time, 100 * 0.001);
      auto rest = pdyn_in(dir, {"run", "scene.yaml", "--steps", "200", "--set", set, "-q",
                                "--resume", "out/split.ckpt"});
      ASSERT_EQ(rest.status, 0) << rest.err;
      EXPECT_EQ(rest.err, "");

      expect_same_state(dir / "ref/split.ckpt", dir / "out/split.ckpt");
      expect_same_file(dir / "ref/split.ckpt", dir / "out/split.ckpt");
      expect_same_file(dir / "ref/frames.csv", dir / "out/frames.csv");
      expect_same_file(dir / "ref/energy.csv", dir / "out/energy.csv");
      EXPECT_EQ(check_frames_file(dir / "out/frames.csv", kResumeParticles),
                200 / every + 1 + (200 % every != 0));
      expect_no_temporaries(dir / "out");
      ++tested;
    }
  }
  EXPECT_GE(tested, 2 * 3) << "expected at least euler, midpoint and rk4";
}

// A periodic Lennard-Jones liquid under velocity Verlet: the solver reuses
// its end-of-step forces across the wraps into the box (evaluated before the
// wrap, so they differ from a fresh evaluation in the last bits), and the
// checkpoint carries them (pdyn/force_reuse.hpp): the resumed run is the
// uninterrupted run's bits, with and without reuse_forces, and for the
// Nose-Hoover solver built on the same reuse.
TEST(ResumeIdentity, PeriodicLiquidResumesWithTheReusedForces) {
  for (const std::string solver : {"{ type: verlet }", "{ type: verlet, reuse_forces: true }",
                                   "{ type: nose_hoover, kT: 1, tdamp: 0.5 }"}) {
    SCOPED_TRACE(solver);
    const fs::path dir = temp_dir("resume-liquid");
    fs::copy_file(source_path("tests/scenes/thermo/thermo_start.data"), dir / "start.data");
    write_file(dir / "liquid.yaml",
               "simulation: { dt: 0.005, steps: 300, solver: " + solver +
                   ", box: { file: start.data } }\n"
                   "particles:\n"
                   "  - file: start.data\n"
                   "forces:\n"
                   "  - { type: lennard_jones, epsilon: 1, sigma: 1, cutoff: 2.5, skin: 0.3 }\n"
                   "output:\n"
                   "  path: out/frames.csv\n"
                   "  every: 150\n"
                   "  checkpoint: { path: out/run.ckpt }\n");
    auto whole = pdyn_in(dir, {"run", "liquid.yaml", "-q"});
    ASSERT_EQ(whole.status, 0) << whole.err;
    const std::string reference = read_bytes(dir / "out/frames.csv");
    auto first = pdyn_in(dir, {"run", "liquid.yaml", "--steps", "173", "-q"});
    ASSERT_EQ(first.status, 0) << first.err;
    auto rest = pdyn_in(dir, {"run", "liquid.yaml", "--resume", "out/run.ckpt", "-q"});
    ASSERT_EQ(rest.status, 0) << rest.err;
    EXPECT_EQ(read_bytes(dir / "out/frames.csv"), reference);
  }
}

TEST(ResumeIdentity, ResumingAtTheEndRewritesTheSameFiles) {
  // Step 100 is not a regular frame (every 7): the checkpoint leaves the
  // final frame out of its record, and a run resumed with nothing left to
  // do must write it again.
  for (const std::string solver : {"rk4", "rk45"}) {
    if (!shipped_plugins().find(PluginKind::Solver, solver)) continue;
    SCOPED_TRACE("solver " + solver);
    const fs::path dir = temp_dir("resume-at-end-" + solver);
    write_file(dir / "scene.yaml", sheet_scene(solver, 7, 0));
    ASSERT_EQ(pdyn_in(dir, {"run", "scene.yaml", "--steps", "100", "-q"}).status, 0);
    for (const char* f : {"frames.csv", "energy.csv", "run.ckpt"}) {
      fs::copy_file(dir / "out" / f, dir / (std::string("first-") + f));
    }
    auto again =
        pdyn_in(dir, {"run", "scene.yaml", "--steps", "100", "-q", "--resume", "first-run.ckpt"});
    ASSERT_EQ(again.status, 0) << again.err;
    expect_same_file(dir / "first-frames.csv", dir / "out/frames.csv");
    expect_same_file(dir / "first-energy.csv", dir / "out/energy.csv");
    expect_same_file(dir / "first-run.ckpt", dir / "out/run.ckpt");
    EXPECT_EQ(check_frames_file(dir / "out/frames.csv", kResumeParticles), 100 / 7 + 2);
  }
}

// Kills a child `pdyn run` (checkpoint every 20 steps, an endless run) once
// it has written a periodic checkpoint. Returns that checkpoint, or nothing
// (after a failed expectation) if the child did not behave.
std::optional<Checkpoint> kill_after_checkpoint(const fs::path& dir) {
  Child child({"run", "scene.yaml", "--steps", "100000000", "-q"}, dir);
  const bool written =
      wait_until([&] { return fs::exists(dir / "out/run.ckpt") || !child.running(); },
                 std::chrono::seconds(30));
  child.signal(SIGKILL);
  const bool ended = child.wait(std::chrono::seconds(10));
  if (!written || !ended || !WIFSIGNALED(child.status()) || WTERMSIG(child.status()) != SIGKILL) {
    ADD_FAILURE() << "the child did not write a checkpoint and run on until killed: "
                  << child.err();
    return std::nullopt;
  }
  return read_checkpoint(dir / "out/run.ckpt");
}

TEST(ResumeIdentity, KilledRunResumesExactly) {
  const double dt = 0.001;
  int tested = 0;
  for (const std::string& solver : shipped_solvers()) {
    SCOPED_TRACE("solver " + solver);
    const bool adaptive = solver_is_adaptive(solver);
    const fs::path killed = temp_dir("killed-" + solver), whole = temp_dir("whole-" + solver);
    const std::string scene = sheet_scene(solver, /*every=*/3, /*ckpt_every=*/20, dt);
    write_file(killed / "scene.yaml", scene);
    write_file(whole / "scene.yaml", scene);

    const std::optional<Checkpoint> killed_at = kill_after_checkpoint(killed);
    if (!killed_at) continue;
    const Checkpoint& mid = *killed_at;
    ASSERT_GT(mid.step, 0);
    EXPECT_EQ(mid.step % 20, 0) << "not a periodic checkpoint";
    // The killed run left its output under temporary names only, holding at
    // least what the checkpoint recorded.
    EXPECT_FALSE(fs::exists(killed / "out/frames.csv"));
    const auto temps = files_starting(killed / "out", "frames.csv.tmp-");
    ASSERT_EQ(temps.size(), 1u);
    EXPECT_GE(fs::file_size(temps[0]), frames_bytes(mid));
    fs::copy_file(killed / "out/run.ckpt", whole / "mid.ckpt");

    // A run long enough that the checkpoint falls in its first half.
    std::int64_t steps = 200;
    if (adaptive) {
      steps =
          std::max<std::int64_t>(steps, static_cast<std::int64_t>(std::ceil(2 * mid.time / dt)));
    } else {
      steps = std::max<std::int64_t>(steps, 2 * mid.step);
    }
    const std::string n = std::to_string(steps);
    auto ref = pdyn_in(whole, {"run", "scene.yaml", "--steps", n, "-q"});
    ASSERT_EQ(ref.status, 0) << ref.err;
    for (const char* f : {"frames.csv", "energy.csv", "run.ckpt"}) {
      fs::copy_file(whole / "out" / f, whole / (std::string("ref-") + f));
    }

    // Resumed from the temporary files the killed process left.
    auto resumed =
        pdyn_in(killed, {"run", "scene.yaml", "--steps", n, "-q", "--resume", "out/run.ckpt"});
    ASSERT_EQ(resumed.status, 0) << resumed.err;
    EXPECT_EQ(resumed.err, "");
    expect_same_file(whole / "ref-frames.csv", killed / "out/frames.csv");
    expect_same_file(whole / "ref-energy.csv", killed / "out/energy.csv");
    expect_same_state(whole / "ref-run.ckpt", killed / "out/run.ckpt");
    expect_same_file(whole / "ref-run.ckpt", killed / "out/run.ckpt");

    // Resumed from the same periodic checkpoint where the finished run's
    // complete output files, longer than the recorded prefix, exist.
    ASSERT_GT(fs::file_size(whole / "out/frames.csv"), frames_bytes(mid));
    auto again = pdyn_in(whole, {"run", "scene.yaml", "--steps", n, "-q", "--resume", "mid.ckpt"});
    ASSERT_EQ(again.status, 0) << again.err;
    expect_same_file(whole / "ref-frames.csv", whole / "out/frames.csv");
    expect_same_file(whole / "ref-energy.csv", whole / "out/energy.csv");
    expect_same_file(whole / "ref-run.ckpt", whole / "out/run.ckpt");
    expect_no_temporaries(whole / "out");
    ++tested;
  }
  EXPECT_GE(tested, 3);
}

TEST(ResumeIdentity, AdaptiveCheckpointPastScheduledSteps) {
  // With dt = 0.05 s and 20 steps (1 s), an adaptive solver takes many more
  // than 20 accepted steps, so a checkpoint's step count (accepted steps)
  // can exceed the scene's nominal steps while its time lies inside the run.
  for (const std::string& solver : shipped_solvers()) {
    if (!solver_is_adaptive(solver)) continue;
    SCOPED_TRACE("solver " + solver);
    const fs::path dir = temp_dir("adaptive-steps-" + solver);
    write_file(dir / "scene.yaml", sheet_scene(solver, 1, /*ckpt_every=*/0, 0.05));
    auto whole = pdyn_in(dir, {"run", "scene.yaml", "--steps", "20", "-q"});
    ASSERT_EQ(whole.status, 0) << whole.err;
    const Checkpoint end = read_checkpoint(dir / "out/run.ckpt");
    ASSERT_GT(end.step, 20) << solver << " took only " << end.step << " steps; the test needs more";
    // The first half (0.5 s) takes more accepted steps than the whole
    // run's 20 nominal ones; its end checkpoint must still resume the run.
    auto half = pdyn_in(dir, {"run", "scene.yaml", "--steps", "10", "-q"});
    ASSERT_EQ(half.status, 0) << half.err;
    const Checkpoint h = read_checkpoint(dir / "out/run.ckpt");
    ASSERT_GT(h.step, 20) << "the first half should take more accepted steps than the run's 20";
    auto rest =
        pdyn_in(dir, {"run", "scene.yaml", "--steps", "20", "-q", "--resume", "out/run.ckpt"});
    EXPECT_EQ(rest.status, 0) << rest.err;
    EXPECT_EQ(check_frames_file(dir / "out/frames.csv", kResumeParticles), 21);
  }
}

TEST(ResumeIdentity, PeriodicBoxSplitRunEqualsWholeRun) {
  int tested = 0;
  for (const std::string& solver : shipped_solvers()) {
    if (solver_is_adaptive(solver)) continue;  // PeriodicBoxKilledRunResumesExactly
    SCOPED_TRACE("solver " + solver);
    const fs::path dir = temp_dir("periodic-split-" + solver);
    write_file(dir / "scene.yaml", periodic_scene(solver, /*every=*/7));
    auto whole = pdyn_in(dir, {"run", "scene.yaml", "--steps", "200", "-q"});
    ASSERT_EQ(whole.status, 0) << whole.err;
    fs::create_directories(dir / "ref");
    for (const char* f : {"frames.csv", "energy.csv", "run.ckpt"}) {
      fs::rename(dir / "out" / f, dir / "ref" / f);
    }
    auto first = pdyn_in(dir, {"run", "scene.yaml", "--steps", "100", "-q"});
    ASSERT_EQ(first.status, 0) << first.err;
    const Checkpoint half = read_checkpoint(dir / "out/run.ckpt");
    // By step 100 (t = 0.1 s) particle 0 has crossed x = 0.2 m twice (to
    // about 0.15 + 0.3 m) and particle 1 y = 0.3 m once (0.29 + 0.27 m).
    ASSERT_EQ(half.images.size(), 3u);
    EXPECT_EQ(half.images[0][0], 2);
    EXPECT_EQ(half.images[1][1], 1);
    EXPECT_EQ(half.images[2][2], 0);
    auto rest =
        pdyn_in(dir, {"run", "scene.yaml", "--steps", "200", "-q", "--resume", "out/run.ckpt"});
    ASSERT_EQ(rest.status, 0) << rest.err;
    expect_same_state(dir / "ref/run.ckpt", dir / "out/run.ckpt");
    expect_same_file(dir / "ref/run.ckpt", dir / "out/run.ckpt");
    expect_same_file(dir / "ref/frames.csv", dir / "out/frames.csv");
    expect_same_file(dir / "ref/energy.csv", dir / "out/energy.csv");
    ++tested;
  }
  EXPECT_GE(tested, 3);
}

TEST(ResumeIdentity, PeriodicBoxKilledRunResumesExactly) {
  int tested = 0;
  for (const std::string& solver : shipped_solvers()) {
    if (!solver_is_adaptive(solver)) continue;  // fixed steps: the split run above
    SCOPED_TRACE("solver " + solver);
    const fs::path killed = temp_dir("periodic-killed-" + solver),
                   whole = temp_dir("periodic-whole-" + solver);
    const std::string scene = periodic_scene(solver, /*every=*/3, /*ckpt_every=*/20);
    write_file(killed / "scene.yaml", scene);
    write_file(whole / "scene.yaml", scene);
    const std::optional<Checkpoint> mid = kill_after_checkpoint(killed);
    if (!mid) continue;
    const std::string n = std::to_string(
        std::max<std::int64_t>(200, static_cast<std::int64_t>(std::ceil(2 * mid->time / 0.001))));
    auto ref = pdyn_in(whole, {"run", "scene.yaml", "--steps", n, "-q"});
    ASSERT_EQ(ref.status, 0) << ref.err;
    auto resumed =
        pdyn_in(killed, {"run", "scene.yaml", "--steps", n, "-q", "--resume", "out/run.ckpt"});
    ASSERT_EQ(resumed.status, 0) << resumed.err;
    expect_same_file(whole / "out/frames.csv", killed / "out/frames.csv");
    expect_same_file(whole / "out/energy.csv", killed / "out/energy.csv");
    expect_same_state(whole / "out/run.ckpt", killed / "out/run.ckpt");
    const Checkpoint end = read_checkpoint(whole / "out/run.ckpt");
    EXPECT_NE(end.images[0][0], 0) << "particle 0 never crossed a periodic face";
    ++tested;
  }
  EXPECT_GE(tested, 1);
}

}  // namespace
}  // namespace pdyn
