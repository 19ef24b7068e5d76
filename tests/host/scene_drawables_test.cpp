// What `pdyn render` and the viewer draw: the shipped colliders through
// their shape hook (pdyn/shape.hpp), a third party's mesh (the tetra_shape
// fixture, folder shapes/), a collider without the hook (not drawn), and a
// broken hook refused with the collider's label and library.
#include "pdyn/host/scene_drawables.hpp"

#include <gtest/gtest.h>

#include "pdyn/error.hpp"
#include "support/test_support.hpp"

namespace pdyn {
namespace {

namespace fs = std::filesystem;

const std::string kDrawablesParticles = R"(
simulation: { dt: 0.001, steps: 1 }
particles:
  - { position: [0, 0, 2], mass: 1 }
  - { position: [1, 0, 2], mass: 1 }
  - { position: [1, 1, 2], mass: 1 }
forces:
  - { type: spring, pairs: [[0, 1]], ks: 10, kd: 0.1 }
  - { type: angle, triples: [[0, 1, 2]], k: 1, kd: 0 }
)";

// Shipped plugins, plus the fixture folder `extra` when given.
const PluginRegistry& registry_with(const std::string& extra) {
  static std::map<std::string, PluginRegistry> registries;
  auto [it, fresh] = registries.try_emplace(extra);
  if (fresh) {
    std::vector<fs::path> dirs;
    if (!extra.empty()) dirs.push_back(fs::path(PDYN_FIXTURE_DIR) / extra);
    dirs.push_back(PDYN_PLUGIN_DIR);
    it->second.discover(dirs);
  }
  return it->second;
}

Scene load(const std::string& colliders, const std::string& extra = "") {
  return load_scene_text(kDrawablesParticles + "colliders:\n" + colliders, "scene.yaml",
                         registry_with(extra));
}

TEST(SceneDrawables, ShippedCollidersDrawWhatTheirParametersSay) {
  const Scene s = load(
      "  - { type: plane, point: [0, 0, -1], normal: [0, 0, 2] }\n"
      "  - { type: sphere, center: [1, 2, 3], radius: 0.25, inside: true }\n"
      "  - { type: box, min: [-1, -2, -3], max: [1, 2, 3] }\n");
  const Drawables d = drawables(s);
  ASSERT_EQ(d.planes.size(), 1u);
  EXPECT_EQ(d.planes[0].point, Vec3(0, 0, -1));
  EXPECT_EQ(d.planes[0].normal, Vec3(0, 0, 1));  // unit length
  ASSERT_EQ(d.spheres.size(), 1u);
  EXPECT_EQ(d.spheres[0].center, Vec3(1, 2, 3));
  EXPECT_EQ(d.spheres[0].radius, 0.25);
  ASSERT_EQ(d.boxes.size(), 1u);
  EXPECT_EQ(d.boxes[0].min, Vec3(-1, -2, -3));
  EXPECT_EQ(d.boxes[0].max, Vec3(1, 2, 3));
  EXPECT_TRUE(d.meshes.empty());
  // The spring's pair and the angle's three edges.
  const std::vector<IndexPair> links{{0, 1}, {0, 1}, {1, 2}, {2, 0}};
  EXPECT_EQ(d.links, links);
  EXPECT_EQ(scene_links(s), links);
  // Six sphere extremes and eight box corners frame the camera.
  EXPECT_EQ(obstacle_points(d).size(), 14u);
}

TEST(SceneDrawables, AThirdPartyColliderDrawsItsOwnMesh) {
  const Scene s = load("  - { type: tetra_shape, size: 2 }\n", "shapes");
  const Drawables d = drawables(s);
  ASSERT_EQ(d.meshes.size(), 1u);
  const auto& m = d.meshes[0];
  ASSERT_EQ(m.vertices.size(), 4u);
  ASSERT_EQ(m.triangles.size(), 4u);
  // A regular tetrahedron of edge 2 m: all six edges 2 m long.
  for (std::size_t i = 0; i < 4; ++i) {
    for (std::size_t j = i + 1; j < 4; ++j) {
      EXPECT_NEAR((m.vertices[i] - m.vertices[j]).norm(), 2.0, 1e-12) << i << "-" << j;
    }
  }
  EXPECT_TRUE(d.planes.empty() && d.spheres.empty() && d.boxes.empty());
  EXPECT_EQ(obstacle_points(d).size(), 4u);
}

TEST(SceneDrawables, AColliderWithoutTheHookIsNotDrawn) {
  const Scene s = load("  - { type: throwing_collider, after: 100 }\n", "faults");
  const Drawables d = drawables(s);
  EXPECT_TRUE(d.planes.empty() && d.spheres.empty() && d.boxes.empty() && d.meshes.empty());
  EXPECT_EQ(d.links.size(), 4u);
}

// Each broken hook: the exact message, with the collider's label and library.
TEST(SceneDrawables, ABrokenHookIsRefusedNamingTheColliderAndItsLibrary) {
  const std::string library =
      (fs::path(PDYN_FIXTURE_DIR) / "shapes" / "pdyn_collider_tetra_shape.so").string();
  const std::pair<const char*, std::string> cases[] = {
      {"throw", "shapes() threw: fixture shape failure"},
      {"nan", "shapes()[0] cannot be drawn: mesh: non-finite vertex 2"},
      {"bad_index", "shapes()[0] cannot be drawn: mesh: triangle 0 names vertex 7 (expected 0..3)"},
  };
  for (const auto& [mode, what] : cases) {
    SCOPED_TRACE(mode);
    const Scene s = load(std::string("  - { type: tetra_shape, mode: ") + mode + " }\n", "shapes");
    try {
      drawables(s);
      ADD_FAILURE() << "no error";
    } catch (const PluginRuntimeError& e) {
      EXPECT_EQ(e.label(), "tetra_shape (scene.yaml:11:5)");
      EXPECT_EQ(std::string(e.what()),
                "tetra_shape (scene.yaml:11:5): " + what + " (library " + library + ")");
    }
  }
}

}  // namespace
}  // namespace pdyn
