// A scene's simulation.neighbor (LAMMPS's neigh_modify every / delay /
// check): read into Scene::neighbor_schedule, its bad values refused at
// their place, refused with an adaptive solver (it counts fixed steps), and
// `check: false` warned about, since its lists then miss pairs.
#include <gtest/gtest.h>

#include "support/test_support.hpp"

namespace pdyn {
namespace {

std::string NeighborScene(const std::string& neighbor, const std::string& solver = "verlet") {
  return "simulation: { dt: 0.005, steps: 2, solver: { type: " + solver +
         " }, box: { min: [0, 0, 0], max: [6, 6, 6], periodic: [true, true, true] },\n"
         "  neighbor: " +
         neighbor +
         " }\n"
         "particles:\n  - { position: [1, 1, 1], mass: 1 }\n  - { position: [2, 1, 1], mass: 1 }\n"
         "forces:\n  - { type: lennard_jones, cutoff: 2.5 }\n";
}

TEST(SceneNeighbor, ReadsTheSchedule) {
  const pdyn::Scene s = test::load_text(NeighborScene("{ every: 20, delay: 5, check: false }"));
  EXPECT_EQ(s.neighbor_schedule, (RebuildSchedule{20, 5, false}));
  ASSERT_EQ(s.warnings.size(), 1u);
  EXPECT_EQ(s.warnings[0],
            "test.yaml:2:43: simulation.neighbor.check: false rebuilds the neighbor lists only "
            "every 20 steps whatever the particles do; pairs that come within the cutoff between "
            "rebuilds are missed (LAMMPS's neigh_modify check no: to reproduce a LAMMPS run)");
  EXPECT_EQ(test::load_text(NeighborScene("{ delay: 10 }")).neighbor_schedule,
            (RebuildSchedule{1, 10, true}));
  EXPECT_TRUE(test::load_text(NeighborScene("{ delay: 10 }")).warnings.empty());
}

TEST(SceneNeighbor, BadValuesAreRefusedWhereTheyAre) {
  EXPECT_EQ(
      test::load_problems(NeighborScene("{ every: 0 }")),
      "test.yaml:2:22: simulation.neighbor.every: 0 is out of range (expected a whole number >= "
      "1)");
  EXPECT_EQ(test::load_problems(NeighborScene("{ sometimes: 2 }")),
            "test.yaml:2:15: unknown key 'sometimes' in simulation.neighbor (expected one of: "
            "every, delay, check)");
  EXPECT_EQ(test::load_problems(NeighborScene("{ every: 2 }", "rk45")),
            "test.yaml:2:13: simulation.neighbor: a rebuild schedule counts fixed steps; rk45 "
            "(test.yaml:1:44) chooses its own step lengths (expected a fixed-step solver: "
            "verlet, rk4, euler, ...)");
}

}  // namespace
}  // namespace pdyn
