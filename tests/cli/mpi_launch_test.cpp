// `mpirun -np N pdyn ...` (issue 43): every command but `run` refuses as
// soon as it sees a launcher's world size above 1, before it reads or
// writes anything, and so does `run` on a pdyn without MPI (each rank would
// run the whole scene and write the same files over the others'); one
// rank, or no launcher, runs as before. `run` on several ranks is tested
// under mpirun (tests/mpi/). The
// launchers are imitated by their environment variables (what mpirun sets
// in each process it starts).
#include "mpi_launch.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <string>

#include "support/test_support.hpp"

namespace pdyn {
namespace {

namespace fs = std::filesystem;

// Sets an environment variable for one scope.
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const char* value) : name_(name) { setenv(name, value, 1); }
  ~ScopedEnv() { unsetenv(name_); }
  ScopedEnv(const ScopedEnv&) = delete;
  ScopedEnv& operator=(const ScopedEnv&) = delete;

 private:
  const char* name_;
};

fs::path SceneWritingFrames(const std::string& name) {
  const fs::path dir = test::temp_dir(name);
  return test::write_file(dir / "scene.yaml",
                          "simulation: { dt: 0.01, steps: 10 }\n"
                          "particles:\n  - { position: [0, 0, 1], mass: 1 }\n"
                          "output: { path: " +
                              (dir / "frames.csv").string() + ", every: 5 }\n");
}

TEST(MpiLaunch, SeveralRanksAreRefusedBeforeAnythingIsWritten) {
  for (const auto& [name, value] :
       {std::pair{"OMPI_COMM_WORLD_SIZE", "2"}, {"PMI_SIZE", "4"}, {"MV2_COMM_WORLD_SIZE", "3"}}) {
    const fs::path scene = SceneWritingFrames(std::string("mpi-ranks-") + name);
    const ScopedEnv env(name, value);
    const std::string launcher = std::string(value) + " MPI ranks (" + name + "=" + value + ")";
    // Every command but run, whatever the build.
    const auto v = test::pdyn({"validate", scene.string()});
    EXPECT_EQ(v.status, 2) << name;
    EXPECT_EQ(v.err, "pdyn: started as one of " + launcher +
                         ": only `pdyn run` runs on several ranks (expected pdyn validate without "
                         "mpirun, or mpirun -np 1)\n");
    // run, in a pdyn built without MPI (with MPI, mpi.run.* runs it under
    // mpirun: an imitated launcher would start MPI in this test program).
    if (!cli::built_with_mpi()) {
      const auto r = test::pdyn({"run", scene.string()});
      EXPECT_EQ(r.status, 2) << name;
      EXPECT_EQ(r.err, "pdyn: started as one of " + launcher +
                           ": this pdyn was built without MPI and runs a scene in one process, so "
                           "each rank would run the whole scene and write the same files "
                           "(expected pdyn without mpirun, or mpirun -np 1, or a pdyn built with "
                           "MPI; several scenes at once: pdyn.sweep in Python)\n");
    }
    EXPECT_EQ(test::snapshot(scene.parent_path()).size(), 1u) << "only the scene: " << name;
  }
}

TEST(MpiLaunch, OneRankOrNoLauncherRunsAsBefore) {
  const fs::path scene = SceneWritingFrames("mpi-one-rank");
  {
    const ScopedEnv env("OMPI_COMM_WORLD_SIZE", "1");
    const auto r = test::pdyn({"run", scene.string(), "-q"});
    EXPECT_EQ(r.status, 0) << r.err;
  }
  EXPECT_TRUE(fs::exists(scene.parent_path() / "frames.csv"));
  const auto plain = test::pdyn({"validate", scene.string(), "-q"});
  EXPECT_EQ(plain.status, 0) << plain.err;
  // --grid cuts the box among MPI ranks: without them it is a mistake.
  const auto grid = test::pdyn({"run", scene.string(), "-q", "--grid", "2,1,1"});
  EXPECT_EQ(grid.status, 2);
  EXPECT_EQ(grid.err,
            "pdyn: --grid 2,1,1: a grid of MPI ranks, but this run has one process (expected "
            "mpirun -np N pdyn run ... --grid NX,NY,NZ)\n");
  // --version and --help answer under any launcher.
  const ScopedEnv env("PMI_SIZE", "2");
  EXPECT_EQ(test::pdyn({"--version"}).status, 0);
}

}  // namespace
}  // namespace pdyn
