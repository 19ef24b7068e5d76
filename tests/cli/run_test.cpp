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

}  // namespace
}  // namespace pdyn
