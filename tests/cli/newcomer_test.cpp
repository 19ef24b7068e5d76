// What a plugin author's first hour tripped over (issue #16), each checked
// as the author met it, through the real command line (in-process):
//   a misspelled --plugin-path is refused, not silently ignored;
//   --plugin-path takes one folder per occurrence, so the scene after it is the scene;
//   `pdyn plugins describe` keeps its columns aligned when a unit is long.
#include <gtest/gtest.h>

#include <regex>

#include "support/test_support.hpp"

namespace pdyn {
namespace {

namespace fs = std::filesystem;
using namespace pdyn::test;

fs::path small_scene(const std::string& force = "") {
  return write_file(temp_dir("newcomer") / "s.yaml",
                    "simulation: { dt: 0.01, steps: 2 }\n"
                    "particles:\n  - { position: [0, 0, 0], mass: 1 }\n" +
                        (force.empty() ? "" : "forces:\n  - " + force + "\n"));
}

TEST(Newcomer, AMisspelledPluginPathIsAnError) {
  const fs::path s = small_scene();
  for (const char* command : {"run", "validate", "render", "check", "schema", "plugins"}) {
    SCOPED_TRACE(command);
    std::vector<std::string> args{command};
    if (std::string(command) == "check") args.push_back("gravity");
    if (std::string(command) == "run" || std::string(command) == "validate" ||
        std::string(command) == "render") {
      args.push_back(s.string());
    }
    args.insert(args.end(), {"--plugin-path", "/no/such/plugins"});
    const auto r = pdyn(args);
    EXPECT_EQ(r.status, 2) << r.err;
    EXPECT_NE(r.err.find("--plugin-path: '/no/such/plugins' is no such folder (expected a folder "
                         "holding plugin libraries pdyn_KIND_NAME.so)"),
              std::string::npos)
        << r.err;
  }
  const auto file = pdyn({"validate", s.string(), "--plugin-path", s.string()});
  EXPECT_EQ(file.status, 2);
  EXPECT_NE(file.err.find("is not a folder"), std::string::npos) << file.err;
}

TEST(Newcomer, PluginPathTakesOneFolderSoTheSceneAfterItIsTheScene) {
  const fs::path s = small_scene("{ type: upper_case, G: 2 }");
  const std::string dir = std::string(PDYN_FIXTURE_DIR) + "/names";
  // Before: the scene was taken as a second plugin folder and the command
  // said that the scene was missing.
  const auto r = pdyn({"validate", "--plugin-path", dir, s.string()});
  EXPECT_EQ(r.status, 0) << r.err;
  const auto two = pdyn({"validate", "--plugin-path", dir, "--set", "simulation.steps=3",
                         "--plugin-path", PDYN_PLUGIN_DIR, s.string()});
  EXPECT_EQ(two.status, 0) << two.err;
}

TEST(Newcomer, DescribeKeepsColumnsAlignedWithALongUnit) {
  const auto r = pdyn({"plugins", "describe", "upper_case", "--plugin-path",
                       std::string(PDYN_FIXTURE_DIR) + "/names"});
  ASSERT_EQ(r.status, 0) << r.err;
  // The header's MEANING and the row's doc start in the same column.
  const auto header = r.out.find("  KEY");
  ASSERT_NE(header, std::string::npos) << r.out;
  const auto row = r.out.find("  G ", header);
  ASSERT_NE(row, std::string::npos) << r.out;
  const std::string head_line = r.out.substr(header, r.out.find('\n', header) - header);
  const std::string row_line = r.out.substr(row, r.out.find('\n', row) - row);
  EXPECT_EQ(head_line.find("MEANING"), row_line.find("gravitational constant")) << r.out;
  EXPECT_EQ(head_line.find("UNIT"), row_line.find("m^3/(kg s^2)")) << r.out;
}

TEST(Newcomer, VersionNamesTheProgramAndThePluginAbi) {
  const auto r = pdyn({"--version"});
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(std::regex_match(r.out, std::regex("pdyn [0-9]+\\.[0-9]+\\.[0-9]+ \\(plugin ABI " +
                                                 std::to_string(kAbiVersion) + "\\)\n")))
      << r.out;
}

// A library built without optimisation is named by `pdyn check` (the
// fixture is compiled with -O0); an optimised one is not.
TEST(Newcomer, CheckWarnsAboutAnUnoptimisedPlugin) {
  const auto slow =
      pdyn({"check", "upper_case", "--plugin-path", std::string(PDYN_FIXTURE_DIR) + "/names"});
  EXPECT_NE(slow.out.find("pdyn_force_upper_case.so was compiled without optimisation"),
            std::string::npos)
      << slow.out;
  const auto fast = pdyn({"check", "gravity"});
  EXPECT_EQ(fast.status, 0) << fast.out << fast.err;
  EXPECT_EQ(fast.out.find("without optimisation"), std::string::npos) << fast.out;
}

// `validate` on an adaptive scene says that the steps are the solver's
// choice, not "3000 steps of 0.001 s"; `run` says what the run cost.
TEST(Newcomer, AdaptiveValidateAndTheRunsCost) {
  const fs::path dir = temp_dir("cost");
  const std::string base =
      "simulation: { dt: 0.001, duration: 3, solver: { type: SOLVER } }\n"
      "particles:\n  - { position: [0, 0, 1], velocity: [0, 1, 0], mass: 1 }\n"
      "forces:\n  - { type: attractor, center: [0, 0, 0], strength: 1 }\n";
  auto scene = [&](const std::string& solver) {
    std::string text = base;
    text.replace(text.find("SOLVER"), 6, solver);
    return write_file(dir / (solver + ".yaml"), text).string();
  };
  const auto v = pdyn({"validate", scene("rk45")});
  ASSERT_EQ(v.status, 0) << v.err;
  EXPECT_NE(v.out.find("solver rk45 (adaptive), to t = 3 s, first step 0.001 s, then as the error "
                       "tolerance allows"),
            std::string::npos)
      << v.out;
  EXPECT_EQ(v.out.find("3000 steps"), std::string::npos) << v.out;

  // rk4 evaluates the forces exactly four times a step, euler once.
  const auto rk4 = pdyn({"run", scene("rk4"), "--steps", "250"});
  ASSERT_EQ(rk4.status, 0) << rk4.err;
  EXPECT_NE(rk4.out.find("pdyn: 1000 force evaluations, "), std::string::npos) << rk4.out;
  EXPECT_NE(rk4.out.find(" particle-steps/s\n"), std::string::npos) << rk4.out;
  const auto euler = pdyn({"run", scene("euler"), "--steps", "250"});
  EXPECT_NE(euler.out.find("pdyn: 250 force evaluations, "), std::string::npos) << euler.out;
  // Dormand-Prince: 6 new evaluations per attempted step (the 7th stage is
  // the next step's first, FSAL), plus the very first.
  const auto rk45 = pdyn({"run", scene("rk45")});
  ASSERT_EQ(rk45.status, 0) << rk45.err;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(rk45.out, m,
                                std::regex("\\(([0-9]+) steps? accepted, ([0-9]+) rejected\\)")))
      << rk45.out;
  const long attempts = std::stol(m[1]) + std::stol(m[2]);
  ASSERT_TRUE(std::regex_search(rk45.out, m, std::regex("pdyn: ([0-9]+) force evaluations")))
      << rk45.out;
  EXPECT_EQ(std::stol(m[1]), 6 * attempts + 1) << rk45.out;
}

}  // namespace
}  // namespace pdyn
