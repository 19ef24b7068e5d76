// Per-particle radius and type (host/src/scene_loader.cpp, scene_builders.cpp,
// grid_builder.cpp, side_files.cpp; docs/scenes.md): given on single
// particles, for a builder's whole block (particle_radius, particle_type) or
// as side-file columns; particles that give none get 0 once any particle
// gives one, and a scene that gives none leaves the System without them.
#include <gtest/gtest.h>

#include "pdyn/host/side_files.hpp"
#include "support/test_support.hpp"

namespace pdyn {
namespace {

namespace fs = std::filesystem;

const char* kPropertiesHead = "simulation: { dt: 0.01, steps: 1 }\nparticles:\n";

TEST(ParticleProperties, NoneGivenLeavesTheSystemWithoutRadiiOrTypes) {
  const Scene s = test::load_text(std::string(kPropertiesHead) +
                                  "  - { position: [0, 0, 0], mass: 1 }\n"
                                  "  - chain: { from: [0, 0, 1], to: [1, 0, 1], n: 3, mass: 1 }\n");
  EXPECT_TRUE(s.system->radii().empty());
  EXPECT_TRUE(s.system->types().empty());
  EXPECT_TRUE(s.system->view().radius.empty());
}

TEST(ParticleProperties, OthersGetZeroOnceAnyParticleGivesOne) {
  const Scene s = test::load_text(std::string(kPropertiesHead) +
                                  "  - { position: [0, 0, 0], mass: 1 }\n"
                                  "  - { position: [1, 0, 0], mass: 1, radius: 0.25 }\n"
                                  "  - { position: [2, 0, 0], mass: 1, type: 7 }\n"
                                  "  - { position: [3, 0, 0], mass: 1, radius: 0, type: 0 }\n");
  EXPECT_EQ(s.system->radii(), (std::vector<double>{0, 0.25, 0, 0}));
  EXPECT_EQ(s.system->types(), (std::vector<std::int32_t>{0, 0, 7, 0}));
  // A radius given only to the last particle still makes N radii.
  const Scene last = test::load_text(std::string(kPropertiesHead) +
                                     "  - grid: { origin: [0, 0, 0], u: [1, 0, 0], v: [0, 1, 0], "
                                     "nx: 2, ny: 2, mass: 1 }\n"
                                     "  - { position: [5, 5, 5], mass: 1, radius: 0.5 }\n");
  EXPECT_EQ(last.system->radii(), (std::vector<double>{0, 0, 0, 0, 0.5}));
  EXPECT_TRUE(last.system->types().empty());
}

TEST(ParticleProperties, EveryBuilderGivesItsWholeBlockOneRadiusAndType) {
  const Scene s = test::load_text(
      std::string(kPropertiesHead) +
      "  - grid: { origin: [0, 0, 0], u: [1, 0, 0], v: [0, 1, 0], nx: 2, ny: 1, mass: 1,\n"
      "            particle_radius: 0.1, particle_type: 1 }\n"
      "  - chain: { from: [0, 0, 1], to: [1, 0, 1], n: 2, mass: 1, particle_radius: 0.2,\n"
      "             particle_type: 2 }\n"
      "  - lattice: { origin: [0, 0, 2], n: [2, 1, 1], spacing: 1, mass: 1,\n"
      "               particle_radius: 0.3, particle_type: 3 }\n"
      "  - cloud: { n: 2, box: { min: [0, 0, 3], max: [1, 1, 4] }, mass: 1,\n"
      "             particle_radius: 0.4, particle_type: 4 }\n"
      "  - ring: { center: [0, 0, 5], radius: 1, n: 3, mass: 1, particle_radius: 0.5,\n"
      "            particle_type: 5 }\n"
      "  - polygon: { points: [[0, 0, 6], [1, 0, 6], [0, 1, 6]], mass: 1,\n"
      "               particle_radius: 0.6, particle_type: 6 }\n"
      "  - { position: [9, 9, 9], mass: 1 }\n");
  EXPECT_EQ(s.system->radii(), (std::vector<double>{0.1, 0.1, 0.2, 0.2, 0.3, 0.3, 0.4, 0.4, 0.5,
                                                    0.5, 0.5, 0.6, 0.6, 0.6, 0}));
  EXPECT_EQ(s.system->types(),
            (std::vector<std::int32_t>{1, 1, 2, 2, 3, 3, 4, 4, 5, 5, 5, 6, 6, 6, 0}));
  // The ring's own `radius` is still the ring's.
  EXPECT_NEAR(s.system->positions().col(8).x(), 1.0, 1e-15);
}

TEST(ParticleProperties, BadValuesAreReportedAtTheirValue) {
  struct Case {
    std::string particle, message;
  };
  const std::vector<Case> cases = {
      {"  - { position: [0, 0, 0], mass: 1, radius: .inf }\n",
       "test.yaml:3:45: particles[0].radius: .inf is not finite (expected a number >= 0 in m)"},
      {"  - { position: [0, 0, 0], mass: 1, type: 1.5 }\n",
       "test.yaml:3:43: particles[0].type: '1.5' is not a whole number (expected a whole number "
       "in [0, 2147483647])"},
      {"  - { position: [0, 0, 0], mass: 1, type: 2147483648 }\n",
       "test.yaml:3:43: particles[0].type: 2147483648 is out of range (expected a whole number "
       "in [0, 2147483647])"},
      {"  - cloud: { n: 2, box: { min: [0, 0, 0], max: [1, 1, 1] }, mass: 1, "
       "particle_radius: -1 }\n",
       "test.yaml:3:87: particles[0].cloud.particle_radius: -1 is out of range (expected a "
       "number >= 0 in m)"},
      {"  - grid: { origin: [0, 0, 0], u: [1, 0, 0], v: [0, 1, 0], nx: 2, ny: 2, mass: 1, "
       "type: 1 }\n",
       "test.yaml:3:83: unknown key 'type' in particles[0].grid (did you mean 'particle_type'? "
       "expected one of: origin, u, v, nx, ny, mass, velocity, name, pin, particle_radius, "
       "particle_type, springs, rods, bending)"},
  };
  for (const auto& c : cases)
    EXPECT_EQ(test::load_problems(kPropertiesHead + c.particle), c.message) << c.particle;
}

TEST(ParticleProperties, SideFileColumnsRoundTripAndMixWithOtherEntries) {
  const fs::path dir = test::temp_dir("properties-side-file");
  side_files::ParticleRows rows;
  for (int i = 0; i < 5; ++i) {
    rows.x.emplace_back(i, 0, 0);
    rows.v.emplace_back(0, 0, 0);
    rows.mass.push_back(1);
    rows.fixed.push_back(0);
    rows.radius.push_back(0.01 * i + 1.0 / 3);
    rows.type.push_back(i % 2);
  }
  side_files::write_particles(dir / "p.csv", rows);
  std::vector<Diagnostic> none;
  const auto back = side_files::read_particles(dir / "p.csv", "p.csv", none);
  ASSERT_TRUE(back);
  EXPECT_EQ(back->radius, rows.radius);  // 17 digits: exact
  EXPECT_EQ(back->type, rows.type);
  // Only a type column: radius stays empty.
  test::write_file(dir / "t.csv", "x,y,z,mass,type\n0,0,0,1,3\n");
  test::write_file(dir / "scene.yaml",
                   "simulation: { dt: 0.01, steps: 1 }\n"
                   "particles:\n"
                   "  - { position: [9, 9, 9], mass: 1 }\n"
                   "  - file: p.csv\n"
                   "  - file: t.csv\n");
  const Scene s = load_scene(dir / "scene.yaml", test::shipped_plugins());
  ASSERT_EQ(s.system->size(), 7);
  std::vector<double> radius{0};
  radius.insert(radius.end(), rows.radius.begin(), rows.radius.end());
  radius.push_back(0);
  EXPECT_EQ(s.system->radii(), radius);
  EXPECT_EQ(s.system->types(), (std::vector<std::int32_t>{0, 0, 1, 0, 1, 0, 3}));
}

TEST(ParticleProperties, BadSideFileFieldsAreLocated) {
  const fs::path dir = test::temp_dir("properties-side-bad");
  test::write_file(dir / "p.csv",
                   "x,y,z,mass,radius,type\n"
                   "0,0,0,1,-0.5,0\n"
                   "0,0,0,1,0.5,-2\n"
                   "0,0,0,1,0.5,1.5\n"
                   "0,0,0,1,nan,1\n"
                   "0,0,0,1,0.5,2147483648\n");
  test::write_file(dir / "scene.yaml",
                   "simulation: { dt: 0.01, steps: 1 }\nparticles:\n  - file: p.csv\n");
  const std::string f = (dir / "p.csv").string();
  try {
    load_scene(dir / "scene.yaml", test::shipped_plugins());
    FAIL() << "bad fields accepted";
  } catch (const SceneError& e) {
    const std::vector<std::string> want = {
        f + ":2:9: radius: -0.5 is negative (expected a radius >= 0 m)",
        f + ":3:13: type: '-2' is not a particle type (expected a whole number in [0, "
            "2147483647])",
        f + ":4:13: type: '1.5' is not a particle type (expected a whole number in [0, "
            "2147483647])",
        f + ":5:9: radius: nan is not finite (expected a finite number)",
        f + ":6:13: type: '2147483648' is not a particle type (expected a whole number in [0, "
            "2147483647])",
    };
    ASSERT_EQ(e.diagnostics().size(), want.size()) << e.what();
    for (std::size_t k = 0; k < want.size(); ++k) EXPECT_EQ(e.diagnostics()[k].text(), want[k]);
  }
}

}  // namespace
}  // namespace pdyn
