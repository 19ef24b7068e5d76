// simulation.box (host/src/scene_loader.cpp, runner.cpp; docs/scenes.md):
// the box reaches the System before any force is created, periodic axes
// wrap the initial positions (images 0), open axes refuse a particle that
// starts outside, every bad box is reported at its value with its exact
// message, and a run in a periodic box keeps every frame inside it while
// its unwrapped columns follow x0 + v t exactly, for a fixed-step solver and
// for an adaptive one whose frames come from its dense output.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "pdyn/host/scene_drawables.hpp"
#include "pdyn/plugin.hpp"
#include "support/physics_support.hpp"
#include "support/test_support.hpp"

namespace pdyn {
namespace {

namespace fs = std::filesystem;

// What a force's factory saw in SceneContext::particles.
struct Seen {
  Domain domain;
  std::vector<double> radius;
  std::vector<std::int32_t> type;
  std::vector<Vec3> x;
};
Seen g_seen;

PluginDescriptor probe() {
  PluginDescriptor d;
  d.kind = PluginKind::Force;
  d.name = "context_probe";
  d.version = "1.0.0";
  d.description = "test: records the particles its factory is given";
  d.create_force = [](const Params&, const SceneContext& ctx) {
    g_seen.domain = ctx.particles.domain;
    g_seen.radius.assign(ctx.particles.radius.begin(), ctx.particles.radius.end());
    g_seen.type.assign(ctx.particles.type.begin(), ctx.particles.type.end());
    g_seen.x.clear();
    for (Index i = 0; i < ctx.particles.size(); ++i) g_seen.x.push_back(ctx.particles.x.col(i));
    return std::make_unique<test::Nothing>();
  };
  return d;
}

TEST(SimulationBox, ForcesSeeTheBoxWrappedPositionsRadiiAndTypesWhenCreated) {
  static const PluginDescriptor descriptor = probe();
  PluginRegistry registry;
  registry.discover({PDYN_PLUGIN_DIR});
  ASSERT_TRUE(registry.add(descriptor, "(test)"));
  const Scene scene = load_scene_text(
      "simulation:\n"
      "  dt: 0.01\n"
      "  steps: 1\n"
      "  box: { min: [0, -1, -2], max: [1, 1, 2], periodic: [true, false, yes] }\n"
      "particles:\n"
      "  - { position: [7.25, 0.5, -5], mass: 1, radius: 0.1, type: 2 }\n"
      "  - { position: [0.5, -1, 2], mass: 1 }\n"
      "forces:\n"
      "  - { type: context_probe }\n",
      "probe.yaml", registry);
  EXPECT_EQ(g_seen.domain.min, Vec3(0, -1, -2));
  EXPECT_EQ(g_seen.domain.max, Vec3(1, 1, 2));
  EXPECT_EQ(g_seen.domain.periodic, (std::array<bool, 3>{true, false, true}));
  EXPECT_EQ(g_seen.domain, scene.system->domain());
  EXPECT_EQ(g_seen.radius, (std::vector<double>{0.1, 0.0}));
  EXPECT_EQ(g_seen.type, (std::vector<std::int32_t>{2, 0}));
  // Wrapped along x (7.25 - 7) and z (-5 + 4): whole box lengths, exactly;
  // the particle on the faces of the open y axis and the periodic z axis
  // is inside (z = max wraps to min).
  ASSERT_EQ(g_seen.x.size(), 2u);
  EXPECT_EQ(g_seen.x[0], Vec3(0.25, 0.5, -1));
  EXPECT_EQ(g_seen.x[1], Vec3(0.5, -1, -2));
  EXPECT_EQ(scene.system->images(), (std::vector<std::array<std::int32_t, 3>>(2, {0, 0, 0})));
}

TEST(SimulationBox, IsOpenAlongEveryAxisUnlessPeriodicAndAbsentByDefault) {
  const Scene open = test::load_text(
      "simulation: { dt: 0.01, steps: 1, box: { min: [-1, -1, -1], max: [1, 1, 1] } }\n"
      "particles: [{ position: [0, 0, 1], mass: 1 }]\n");
  EXPECT_FALSE(open.system->domain().any_periodic());
  ASSERT_TRUE(simulation_box(open));
  EXPECT_EQ(simulation_box(open)->max, Vec3(1, 1, 1));
  EXPECT_TRUE(drawables(open).box);
  const Scene none = test::load_text(
      "simulation: { dt: 0.01, steps: 1, box: ~ }\n"
      "particles: [{ position: [0, 0, 1], mass: 1 }]\n");
  EXPECT_FALSE(simulation_box(none));
  EXPECT_FALSE(drawables(none).box);
  EXPECT_EQ(none.system->domain(), Domain{});
}

TEST(SimulationBox, BadBoxesAreReportedAtTheirValue) {
  const std::string particles = "particles: [{ position: [0.5, 0.5, 0.5], mass: 1 }]\n";
  struct Case {
    std::string box, message;
  };
  const std::vector<Case> cases = {
      {"box: [0, 1]",
       "test.yaml:1:40: simulation.box: '[0, 1]' is not a mapping (expected box: { min: [x, y, "
       "z], max: [x, y, z], periodic: [bool, bool, bool] })"},
      {"box: { min: [0, 0, 0] }",
       "test.yaml:1:40: simulation.box: missing required key 'max' (expected a vector [x, y, z] "
       "in m: corner with the largest coordinates (> min))"},
      {"box: { min: [0, 0, 0], max: [1, 1, 1], periodc: [true, true, true] }",
       "test.yaml:1:74: unknown key 'periodc' in simulation.box (did you mean 'periodic'? "
       "expected one of: min, max, periodic)"},
      {"box: { min: [0, 0, 0], max: [1, 1, 1], periodic: true }",
       "test.yaml:1:84: simulation.box.periodic: is not a list of 3 booleans: it is 'true' "
       "(expected a list of 3 booleans, one per axis x, y, z, e.g. [true, true, false])"},
      {"box: { min: [0, 0, .nan], max: [1, 1, 1] }",
       "test.yaml:1:54: simulation.box.min[2]: .nan is not finite (expected a number in m)"},
      {"box: { min: [0, 2, 0], max: [1, 1, 1] }",
       "test.yaml:1:63: simulation.box.max: [1, 1, 1] is not above min [0, 2, 0] in y "
       "(expected max > min in every component)"},
  };
  for (const auto& c : cases) {
    EXPECT_EQ(
        test::load_problems("simulation: { dt: 0.01, steps: 1, " + c.box + " }\n" + particles),
        c.message)
        << c.box;
  }
}

TEST(SimulationBox, AParticleOutsideAlongAnOpenAxisIsNamedWithItsEntry) {
  // From a side file: reported at the file's name, with the particle's id.
  const fs::path dir = test::temp_dir("box-outside-file");
  test::write_file(dir / "p.csv", "x,y,z,mass\n0.5,0.5,0.5,1\n0.5,0.5,-0.25,1\n");
  test::write_file(dir / "scene.yaml",
                   "simulation:\n"
                   "  dt: 0.01\n"
                   "  steps: 1\n"
                   "  box: { min: [0, 0, 0], max: [1, 1, 1], periodic: [true, true, false] }\n"
                   "particles:\n"
                   "  - { position: [3, -4, 1], mass: 1 }\n"
                   "  - file: p.csv\n");
  try {
    load_scene(dir / "scene.yaml", test::shipped_plugins());
    FAIL() << "a particle outside the box was accepted";
  } catch (const SceneError& e) {
    ASSERT_EQ(e.diagnostics().size(), 1u) << e.what();
    EXPECT_EQ(e.diagnostics()[0].text(),
              (dir / "scene.yaml").string() +
                  ":7:11: particles[1].file: particle 2 is outside simulation.box along z: z = "
                  "-0.25 m is not in [0, 1] (expected initial positions inside the box along "
                  "every axis that is not periodic)");
  }
}

// Reads a frames CSV with the unwrapped columns: per row t, id and the 9
// numbers x y z vx vy vz xu yu zu.
struct BoxRow {
  double t;
  Index id;
  Vec3 x, v, u;
};
std::vector<BoxRow> read_frames(const fs::path& file) {
  std::ifstream in(file);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "t,id,x,y,z,vx,vy,vz,xu,yu,zu");
  std::vector<BoxRow> rows;
  while (std::getline(in, line)) {
    std::istringstream s(line);
    std::string f;
    std::vector<double> v;
    while (std::getline(s, f, ',')) v.push_back(std::stod(f));
    EXPECT_EQ(v.size(), 11u) << line;
    if (v.size() != 11) break;
    rows.push_back({v[0], static_cast<Index>(v[1]), Vec3(v[2], v[3], v[4]), Vec3(v[5], v[6], v[7]),
                    Vec3(v[8], v[9], v[10])});
  }
  return rows;
}

// Four free particles at constant velocity (no forces) in a box periodic
// along x and y and open along z, crossing the periodic faces several
// times each way; particle 3 leaves through the open top and goes on.
std::string crossing_scene(const std::string& solver) {
  return "simulation:\n"
         "  dt: 0.01\n"
         "  steps: 150\n"
         "  solver: { type: " +
         solver +
         " }\n"
         "  box: { min: [-1, 0, 0], max: [1, 0.5, 1], periodic: [true, true, false] }\n"
         "output: { path: out/frames.csv, every: 7, unwrapped: true }\n"
         "particles:\n"
         "  - { position: [0.9, 0.1, 0.5], velocity: [3.7, -2.3, 0], mass: 1 }\n"
         "  - { position: [-0.95, 0.45, 0.2], velocity: [-5.1, 1.9, 0], mass: 2 }\n"
         "  - { position: [0, 0.25, 0.7], velocity: [0.013, -0.007, 0], mass: 1 }\n"
         "  - { position: [0.3, 0.3, 0.9], velocity: [-1, 0.5, 0.4], mass: 1 }\n";
}

TEST(SimulationBox, ParticlesCrossingPeriodicFacesStayInsideAndUnwrapToX0PlusVt) {
  const Vec3 x0[4] = {{0.9, 0.1, 0.5}, {-0.95, 0.45, 0.2}, {0, 0.25, 0.7}, {0.3, 0.3, 0.9}};
  const Vec3 v[4] = {{3.7, -2.3, 0}, {-5.1, 1.9, 0}, {0.013, -0.007, 0}, {-1, 0.5, 0.4}};
  // euler and verlet take fixed steps; rk45 is adaptive, its frames
  // interpolated inside steps from the dense output and wrapped there.
  for (const std::string solver : {"euler", "verlet", "rk45"}) {
    if (!test::shipped_plugins().find(PluginKind::Solver, solver)) continue;
    SCOPED_TRACE(solver);
    const fs::path dir = test::temp_dir("box-crossing-" + solver);
    test::write_file(dir / "scene.yaml", crossing_scene(solver));
    const fs::path old = fs::current_path();
    fs::current_path(dir);
    Scene scene = load_scene("scene.yaml", test::shipped_plugins());
    const RunResult r = run_scene(scene);
    fs::current_path(old);
    ASSERT_EQ(r.exit_code, 0) << r.message;
    const auto rows = read_frames(dir / "out/frames.csv");
    ASSERT_EQ(rows.size(), 4u * (150 / 7 + 2));
    int crossings = 0;
    for (const BoxRow& row : rows) {
      const Index i = row.id;
      for (int k = 0; k < 2; ++k) {  // periodic: inside [min, max)
        EXPECT_GE(row.x[k], scene.system->domain().min[k]) << "t " << row.t << " particle " << i;
        EXPECT_LT(row.x[k], scene.system->domain().max[k]) << "t " << row.t << " particle " << i;
      }
      const Vec3 exact = x0[i] + v[i] * row.t;
      EXPECT_LT((row.u - exact).cwiseAbs().maxCoeff(), 1e-12)
          << "t " << row.t << " particle " << i << ": " << row.u.transpose() << " vs "
          << exact.transpose();
      // Along the open axis the box is no wall: xu is x, and z goes on.
      EXPECT_EQ(row.u.z(), row.x.z());
      EXPECT_EQ(row.v, v[i]);
      crossings += row.x != row.u;
    }
    EXPECT_GT(crossings, 0);
    // Particle 3 left through the open top (z = 0.9 + 0.4 t > 1 after 0.25 s).
    EXPECT_GT(rows.back().x.z(), 1.0);
    // The final state's images agree with the last frame.
    const auto& images = scene.system->images();
    EXPECT_EQ(images[0][0], static_cast<int>(std::floor((0.9 + 3.7 * 1.5 + 1) / 2)));
    EXPECT_EQ(images[3][2], 0);
  }
}

TEST(SimulationBox, UnwrappedColumnsAreOptionalAndEqualXWithoutABox) {
  const fs::path dir = test::temp_dir("box-unwrapped-open");
  test::write_file(dir / "scene.yaml",
                   "simulation: { dt: 0.1, steps: 3, solver: { type: euler } }\n"
                   "output: { path: a.csv, unwrapped: true }\n"
                   "particles: [{ position: [1, 2, 3], velocity: [1, 0, 0], mass: 1 }]\n");
  ASSERT_EQ(test::pdyn({"run", (dir / "scene.yaml").string(), "-q", "--set",
                        "output.path=" + (dir / "a.csv").string()})
                .status,
            0);
  std::ifstream in(dir / "a.csv");
  std::string header, first;
  std::getline(in, header);
  std::getline(in, first);
  EXPECT_EQ(header, "t,id,x,y,z,vx,vy,vz,xu,yu,zu");
  EXPECT_EQ(first, "0,0,1,2,3,1,0,0,1,2,3");
  ASSERT_EQ(
      test::pdyn({"run", (dir / "scene.yaml").string(), "-q", "--set",
                  "output.path=" + (dir / "b.csv").string(), "--set", "output.unwrapped=false"})
          .status,
      0);
  std::ifstream b(dir / "b.csv");
  std::getline(b, header);
  EXPECT_EQ(header, "t,id,x,y,z,vx,vy,vz");
}

}  // namespace
}  // namespace pdyn
