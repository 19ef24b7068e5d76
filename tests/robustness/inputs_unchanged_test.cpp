// No input file's bytes change after any run (issue #18): every scene of
// configs/ and tests/scenes/ (the bad ones and the ones that once overwrote
// themselves included) and every side file beside them is hashed, each scene
// is validated and run by the real binary from its own folder, as a user
// would, and every file that existed before must hold the same bytes after.
// It works on a copy, so that a regression cannot damage the source tree.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>

#include "support/test_support.hpp"

namespace pdyn {
namespace {

namespace fs = std::filesystem;
using namespace pdyn::test;

std::map<fs::path, std::string> snapshot_paths(const fs::path& dir) {
  std::map<fs::path, std::string> out;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    if (!e.is_regular_file()) continue;
    std::ifstream in(e.path(), std::ios::binary);
    std::ostringstream ss;
    ss << in.rdbuf();
    out[e.path()] = ss.str();
  }
  return out;
}

TEST(InputsUnchanged, NoRunOfAnySceneChangesAnyInputFile) {
  const fs::path root = temp_dir("inputs-unchanged");
  fs::copy(source_path("configs"), root / "configs", fs::copy_options::recursive);
  fs::copy(source_path("tests/scenes"), root / "scenes", fs::copy_options::recursive);
  const auto before = snapshot_paths(root);
  int scenes = 0;
  for (const auto& [file, bytes] : before) {
    if (file.extension() != ".yaml") continue;
    ++scenes;
    for (const char* args : {"validate", "run --steps 3 --threads 1"}) {
      const std::string cmd = "cd '" + file.parent_path().string() + "' && '" + PDYN_BIN + "' " +
                              args + " '" + file.filename().string() + "' >/dev/null 2>&1";
      const int rc = std::system(cmd.c_str());
      ASSERT_TRUE(WIFEXITED(rc)) << cmd << " died with a signal";
      ASSERT_NE(WEXITSTATUS(rc), 1) << cmd << ": exit 1, an unexpected error";
    }
  }
  EXPECT_GT(scenes, 60);
  const auto after = snapshot_paths(root);
  for (const auto& [file, bytes] : before) {
    const auto it = after.find(file);
    ASSERT_NE(it, after.end()) << file << " was removed";
    EXPECT_TRUE(it->second == bytes) << file << " changed";
  }
  std::cout << scenes << " scenes validated and run; " << before.size()
            << " input files unchanged\n";
}

}  // namespace
}  // namespace pdyn
