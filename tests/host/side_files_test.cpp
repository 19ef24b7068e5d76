// CSV side files (host/src/side_files.cpp): particles and spring pairs
// read from files a scene names, with exact located messages for bad rows.
#include "pdyn/host/side_files.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <functional>

#include "support/test_support.hpp"

namespace pdyn::test {
namespace {

namespace fs = std::filesystem;

// The one diagnostic a bad file gives.
std::string only_problem(const std::function<void()>& load) {
  try {
    load();
  } catch (const SceneError& e) {
    if (e.diagnostics().size() != 1) return "several problems: " + std::string(e.what());
    return e.diagnostics()[0].text();
  }
  return "no problem reported";
}

TEST(SideFiles, ParticlesRoundTripExactly) {
  const fs::path dir = temp_dir("side_round_trip");
  side_files::ParticleRows rows;
  for (int i = 0; i < 50; ++i) {
    rows.x.emplace_back(0.1 * i, 1.0 / (i + 3), -2e-300 * i);
    rows.v.emplace_back(i % 3 == 0 ? 0.0 : 1.0 / 7.0, -3.5, 1e10 / (i + 1));
    rows.mass.push_back(0.001 + 1.0 / (i + 11));
    rows.fixed.push_back(i == 7 ? 1 : 0);
  }
  rows.v[7].setZero();  // a fixed particle's velocity is zeroed on assembly
  side_files::write_particles(dir / "cloth.csv", rows);
  std::vector<Diagnostic> problems;
  const auto back = side_files::read_particles(dir / "cloth.csv", "cloth.csv", problems);
  ASSERT_TRUE(back) << (problems.empty() ? "" : problems[0].text());
  ASSERT_EQ(back->x.size(), rows.x.size());
  for (std::size_t i = 0; i < rows.x.size(); ++i) {
    EXPECT_EQ(std::memcmp(back->x[i].data(), rows.x[i].data(), sizeof(Vec3)), 0) << i;
    EXPECT_EQ(std::memcmp(back->v[i].data(), rows.v[i].data(), sizeof(Vec3)), 0) << i;
    EXPECT_EQ(back->mass[i], rows.mass[i]);
    EXPECT_EQ(back->fixed[i], rows.fixed[i]);
  }
  // And through a scene: the same system as the inline particles give.
  const std::vector<IndexPair> pairs{{0, 1}, {1, 2}, {2, 49}};
  side_files::write_pairs(dir / "springs.csv", pairs);
  write_file(dir / "scene.yaml",
             "simulation: { dt: 0.001, steps: 1 }\n"
             "particles:\n"
             "  - { position: [5, 5, 5], mass: 2 }\n"
             "  - file: cloth.csv\n"
             "forces:\n"
             "  - { type: spring, ks: 10, pairs: { file: springs.csv } }\n");
  const Scene scene = load_scene(dir / "scene.yaml", shipped_plugins());
  ASSERT_EQ(scene.system->size(), 51);
  EXPECT_EQ(scene.system->positions().col(1), rows.x[0]);
  EXPECT_EQ(scene.system->velocities().col(50), rows.v[49]);
  EXPECT_EQ(scene.system->masses()(8), rows.mass[7]);
  EXPECT_EQ(scene.system->fixed()[8], 1);
  EXPECT_EQ(scene.system->force_objects().size(), 1u);
}

class BadRow : public ::testing::TestWithParam<std::pair<std::string, std::string>> {};

TEST_P(BadRow, IsReportedAtItsLineAndColumn) {
  const fs::path dir = temp_dir("side_bad_row");
  write_file(dir / "p.csv", "x,y,z,mass\n0,0,0,1\n" + GetParam().first + "\n1,1,1,1\n");
  write_file(dir / "scene.yaml",
             "simulation: { dt: 0.001, steps: 1 }\nparticles:\n  - file: p.csv\n");
  const std::string shown = (dir / "p.csv").string();
  EXPECT_EQ(only_problem([&] { load_scene(dir / "scene.yaml", shipped_plugins()); }),
            shown + ":" + GetParam().second);
}

INSTANTIATE_TEST_SUITE_P(
    Particles, BadRow,
    ::testing::Values(
        std::pair{"0,zero,0,1",
                  "3:3: y: 'zero' is not a number (expected a real number, e.g. 0.25)"},
        std::pair{"0,0,0",
                  "3:6: has 3 fields, the header has 4 (expected 4 comma-separated "
                  "values: x,y,z,mass)"},
        std::pair{"0,0,0,1,5",
                  "3:10: has 5 fields, the header has 4 (expected 4 comma-separated "
                  "values: x,y,z,mass)"},
        std::pair{"0, nan,0,1", "3:4: y: nan is not finite (expected a finite number)"},
        std::pair{"0,0,0,-0.5", "3:7: mass: -0.5 is not positive (expected a mass > 0 kg)"},
        std::pair{"0,0,,1",
                  "3:5: z: an empty field is not a number (expected a real number, "
                  "e.g. 0.25)"}));

TEST(SideFiles, BadHeaderAndBadPairsAreLocated) {
  const fs::path dir = temp_dir("side_bad_header");
  write_file(dir / "p.csv", "x,y,z,weight\n0,0,0,1\n");
  write_file(dir / "q.csv", "x,y,z,mass\n0,0,0,1\n1,0,0,1\n");
  write_file(dir / "s.csv", "i,j\n0,1\n1,7\n");
  write_file(dir / "a.yaml", "simulation: { dt: 0.001, steps: 1 }\nparticles:\n  - file: p.csv\n");
  write_file(dir / "b.yaml",
             "simulation: { dt: 0.001, steps: 1 }\nparticles:\n  - file: q.csv\n"
             "forces:\n  - { type: spring, pairs: { file: s.csv } }\n");
  write_file(dir / "c.yaml",
             "simulation: { dt: 0.001, steps: 1 }\nparticles:\n  - file: none.csv\n");
  try {
    load_scene(dir / "a.yaml", shipped_plugins());
    FAIL() << "a bad header was accepted";
  } catch (const SceneError& e) {
    ASSERT_EQ(e.diagnostics().size(), 2u) << e.what();
    EXPECT_EQ(e.diagnostics()[0].text(),
              (dir / "p.csv").string() +
                  ":1:7: unknown column 'weight' (expected x, y, z, vx, vy, vz, mass, fixed, "
                  "radius, type)");
    EXPECT_EQ(e.diagnostics()[1].text(), (dir / "p.csv").string() +
                                             ":1:1: the header has no column 'mass' (expected "
                                             "x,y,z[,vx,vy,vz],mass[,fixed][,radius][,type])");
  }
  EXPECT_EQ(only_problem([&] { load_scene(dir / "b.yaml", shipped_plugins()); }),
            (dir / "s.csv").string() +
                ":3:3: j: particle index 7 is out of range (expected 0..1: the scene has 2 "
                "particles)");
  EXPECT_EQ(only_problem([&] { load_scene(dir / "c.yaml", shipped_plugins()); }),
            (dir / "none.csv").string() +
                ": cannot read the particle file (expected a readable CSV file)");
}

}  // namespace
}  // namespace pdyn::test
