// Files a run writes never overwrite its inputs or each other (issue #18's
// data-loss cases). Every path a run will write (frames, energy, the
// checkpoint, and the implicit checkpoint of an interrupted run) is checked
// at load time against the others, the scene file, its side files and the
// filesystem; a clash is a located error naming both keys, exit 2, from
// `pdyn validate` as from `pdyn run`, and no byte of any file changes.
//
// The scenes of tests/scenes/overwrite/ are copied to a temporary folder and
// run from there by the real binary (PDYN_BIN), as a user would run them.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>

#include "support/test_support.hpp"

namespace pdyn {
namespace {

namespace fs = std::filesystem;
using namespace pdyn::test;

struct Outcome {
  int status = -1;
  std::string err;
};

// `pdyn ARGS` run by the shell in `dir`; stdout is dropped.
Outcome run_in(const fs::path& dir, const std::string& args) {
  const fs::path err = dir / ".stderr";
  const std::string cmd = "cd '" + dir.string() + "' && '" + PDYN_BIN + "' " + args +
                          " >/dev/null 2>'" + err.string() + "'";
  const int rc = std::system(cmd.c_str());
  Outcome r;
  r.status = WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
  r.err = read_bytes(err);
  fs::remove(err);
  return r;
}

struct Case {
  const char* scene;
  int line, column;
  const char* text;
};

class OverwriteScene : public ::testing::TestWithParam<Case> {};

TEST_P(OverwriteScene, RefusedByValidateAndRunAndNothingChanges) {
  const Case& c = GetParam();
  const fs::path dir = temp_dir(std::string("overwrite-") + c.scene);
  fs::copy(source_path("tests/scenes/overwrite"), dir, fs::copy_options::recursive);
  const auto before = snapshot(dir);
  for (const char* command : {"validate", "run"}) {
    SCOPED_TRACE(command);
    const Outcome r = run_in(dir, std::string(command) + " " + c.scene);
    EXPECT_EQ(r.status, 2) << r.err;
    const std::string prefix = fmt::format("{}:{}:{}: ", c.scene, c.line, c.column);
    EXPECT_EQ(r.err.rfind(prefix, 0), 0u) << r.err;
    EXPECT_NE(r.err.find(c.text), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_EQ(snapshot(dir), before) << "a file was written or changed";
  }
}

INSTANTIATE_TEST_SUITE_P(
    WrittenPaths, OverwriteScene,
    ::testing::Values(
        Case{"output_is_scene.yaml", 6, 9,
             "output.path: 'output_is_scene.yaml' is the scene file, which the run reads "
             "(expected an output file that is not an input)"},
        Case{"checkpoint_is_scene.yaml", 7, 23,
             "output.checkpoint.path: 'checkpoint_is_scene.yaml' is the scene file, which the "
             "run reads"},
        Case{"checkpoint_is_output.yaml", 7, 23,
             "output.checkpoint.path: 'out/checkpoint_is_output.csv' is the same file as "
             "output.path (at checkpoint_is_output.yaml:6:9) (expected a different file for "
             "each output)"},
        Case{"energy_is_side_file.yaml", 6, 11,
             "output.energy: 'energy_is_side_file.csv' is particles[0].file (at "
             "energy_is_side_file.yaml:4:11), which the run reads"},
        Case{"output_under_a_file.yaml", 6, 9,
             "output.path: cannot create 'output_under_a_file.yaml/x.csv': "}),
    [](const auto& test) {
      std::string name = test.param.scene;
      return name.substr(0, name.find('.'));
    });

// The cases a scene in the source tree cannot spell: absolute paths, links,
// overrides and the implicit checkpoint.
class WrittenPathsTest : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = temp_dir("written-paths"); }

  fs::path scene(const std::string& output) {
    return write_file(dir_ / "scene.yaml",
                      "simulation: { dt: 0.01, steps: 3 }\n"
                      "particles:\n"
                      "  - { position: [0, 0, 1], mass: 1 }\n"
                      "output:\n" +
                          output);
  }
  // Runs `pdyn run` in-process on `file`; expects exit 2 and returns stderr.
  std::string refused(const fs::path& file, std::vector<std::string> extra = {}) {
    const std::string bytes = read_bytes(file);
    std::vector<std::string> args{"run", file.string()};
    args.insert(args.end(), extra.begin(), extra.end());
    const auto r = pdyn(args);
    EXPECT_EQ(r.status, 2) << r.err;
    EXPECT_EQ(read_bytes(file), bytes);
    return r.err;
  }
  fs::path dir_;
};

TEST_F(WrittenPathsTest, AbsolutePathToTheSceneIsTheScene) {
  const fs::path s = dir_ / "scene.yaml";
  scene("  path: " + s.string() + "\n");
  EXPECT_NE(refused(s).find("scene.yaml:5:9: output.path: '" + s.string() +
                            "' is the scene file, which the run reads"),
            std::string::npos);
}

TEST_F(WrittenPathsTest, ThroughASymbolicLinkIsTheSameFile) {
  fs::create_directory_symlink(dir_, dir_ / "link");
  const fs::path s = dir_ / "scene.yaml";
  scene("  path: " + (dir_ / "link" / "scene.yaml").string() + "\n");
  EXPECT_NE(refused(s).find("is the scene file, which the run reads"), std::string::npos);
}

TEST_F(WrittenPathsTest, AHardLinkToTheSceneIsTheScene) {
  const fs::path s = dir_ / "scene.yaml";
  scene("  path: " + (dir_ / "hard.yaml").string() + "\n");
  fs::create_hard_link(s, dir_ / "hard.yaml");
  EXPECT_NE(refused(s).find("is the scene file, which the run reads"), std::string::npos);
}

TEST_F(WrittenPathsTest, AnOverrideIsLocatedAtTheOverride) {
  const fs::path s = scene("  path: " + (dir_ / "out.csv").string() + "\n");
  const std::string err = refused(s, {"--set", "output.energy=" + s.string()});
  EXPECT_EQ(err.rfind("--set output.energy=" + s.string() + ": output.energy: '" + s.string() +
                          "' is the scene file",
                      0),
            0u)
      << err;
}

TEST_F(WrittenPathsTest, CheckpointAndEnergyTheSameFile) {
  const std::string e = (dir_ / "e.csv").string();
  const fs::path s = scene("  energy: " + e + "\n  checkpoint: { path: " + e + " }\n");
  EXPECT_NE(refused(s).find("scene.yaml:6:23: output.checkpoint.path: '" + e +
                            "' is the same file as output.energy (at " + s.string() + ":5:11)"),
            std::string::npos);
}

// With no output.checkpoint, an interrupted run checkpoints to output.path
// with the extension .ckpt: a frames file named *.ckpt would be replaced.
TEST_F(WrittenPathsTest, TheImplicitCheckpointOfAnInterruptedRun) {
  const std::string f = (dir_ / "frames.ckpt").string();
  const fs::path s = scene("  path: " + f + "\n");
  EXPECT_NE(refused(s).find("scene.yaml:5:9: the checkpoint of an interrupted run (output.path "
                            "with .ckpt; set output.checkpoint.path to choose): '" +
                            f + "' is the same file as output.path"),
            std::string::npos);
}

TEST_F(WrittenPathsTest, DistinctFilesInFoldersToBeCreatedAreFine) {
  const fs::path s = scene("  path: " + (dir_ / "a/b/frames.csv").string() +
                           "\n  energy: " + (dir_ / "a/c/energy.csv").string() +
                           "\n  checkpoint: { path: " + (dir_ / "a/run.ckpt").string() + " }\n");
  const auto r = pdyn({"run", s.string()});
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(fs::is_regular_file(dir_ / "a/b/frames.csv"));
  EXPECT_TRUE(fs::is_regular_file(dir_ / "a/c/energy.csv"));
  EXPECT_TRUE(fs::is_regular_file(dir_ / "a/run.ckpt"));
}

}  // namespace
}  // namespace pdyn
