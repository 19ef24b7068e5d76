// `pdyn render`: particles are drawn where the camera puts them, springs
// between them, nailed particles differently, and the same scene gives the
// same bytes on every run.
#include "render.hpp"

#include <cairo.h>
#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <iterator>

#include "support/test_support.hpp"

namespace pdyn {
namespace {

namespace fs = std::filesystem;
using cli::render::Camera;

struct Rgb {
  int r, g, b;
};

class Picture {
 public:
  explicit Picture(const fs::path& png)
      : surface_(cairo_image_surface_create_from_png(png.c_str()), cairo_surface_destroy) {}
  bool ok() const { return cairo_surface_status(surface_.get()) == CAIRO_STATUS_SUCCESS; }
  int width() const { return cairo_image_surface_get_width(surface_.get()); }
  int height() const { return cairo_image_surface_get_height(surface_.get()); }
  Rgb at(int x, int y) const {
    const unsigned char* row = cairo_image_surface_get_data(surface_.get()) +
                               y * cairo_image_surface_get_stride(surface_.get());
    std::uint32_t px;
    std::memcpy(&px, row + 4 * x, 4);  // native-endian 0x00RRGGBB
    return {static_cast<int>((px >> 16) & 0xff), static_cast<int>((px >> 8) & 0xff),
            static_cast<int>(px & 0xff)};
  }

 private:
  std::unique_ptr<cairo_surface_t, decltype(&cairo_surface_destroy)> surface_;
};

bool near(Rgb c, const double (&want)[3]) {
  return std::abs(c.r - want[0] * 255) <= 2 && std::abs(c.g - want[1] * 255) <= 2 &&
         std::abs(c.b - want[2] * 255) <= 2;
}
bool white(Rgb c) { return c.r == 255 && c.g == 255 && c.b == 255; }

std::string bytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

test::CommandResult render(const std::vector<std::string>& extra) {
  std::vector<std::string> args = {"render", "--plugin-path", PDYN_PLUGIN_DIR};
  args.insert(args.end(), extra.begin(), extra.end());
  return test::pdyn(args);
}

// The hanging cloth at t = 0 seen along +y: a flat 100 x 100 grid in the x-z
// plane, so every particle is visible and the camera is known exactly.
TEST(Render, ParticlesAndSpringsLandWhereTheCameraPutsThem) {
  const fs::path dir = test::temp_dir("render-cloth");
  const std::string scene = test::source_path("configs/hanging_cloth.yaml").string();
  const auto r = render({scene, "--at", "0", "--png", (dir / "cloth.png").string(), "--view", "xz",
                         "--size", "600x500"});
  ASSERT_EQ(r.status, 0) << r.err;
  const Picture pic(dir / "cloth.png");
  ASSERT_TRUE(pic.ok());
  EXPECT_EQ(pic.width(), 600);
  EXPECT_EQ(pic.height(), 500);

  const Scene s = load_scene(scene, test::shipped_plugins());
  const auto x = s.system->positions();
  std::vector<Vec3> points;
  for (Index i = 0; i < x.cols(); ++i) points.push_back(x.col(i));
  const Camera cam = cli::render::fit_camera(cli::render::View::XZ, points, 600, 500);
  auto px = [&](const Vec3& p) {
    const auto q = cam.pixel(p);
    return pic.at(static_cast<int>(q.x()), static_cast<int>(q.y()));
  };
  // Free particles: corners, edges and the middle of the sheet (id = j*100 + i).
  for (Index id : {0, 99, 4950, 5050, 7733}) {
    EXPECT_TRUE(near(px(x.col(id)), cli::render::kFree)) << "particle " << id;
  }
  // The two pinned top corners are drawn as nailed.
  for (Index id : {9900, 9999}) {
    EXPECT_TRUE(near(px(x.col(id)), cli::render::kFixed)) << "particle " << id;
  }
  // Halfway between two neighbours of the bottom row lies a structural
  // spring: drawn, so neither background nor a particle.
  const Rgb link = px((x.col(10) + x.col(11)) / 2);
  EXPECT_FALSE(white(link));
  EXPECT_FALSE(near(link, cli::render::kFree));
  // Outside the sheet: background.
  EXPECT_TRUE(white(px(x.col(0) - Vec3(0.05, 0, 0.05))));
  EXPECT_TRUE(white(pic.at(2, pic.height() - 3)));
}

TEST(Render, SameSceneSameBytesAndOneFilePerTime) {
  const fs::path dir = test::temp_dir("render-repeat");
  const std::string scene = test::source_path("configs/demo.yaml").string();
  const auto a =
      render({scene, "--at", "0,0.05", "--png", (dir / "a.png").string(), "--size", "320x240"});
  const auto b =
      render({scene, "--at", "0,0.05", "--png", (dir / "b.png").string(), "--size", "320x240"});
  ASSERT_EQ(a.status, 0) << a.err;
  ASSERT_EQ(b.status, 0) << b.err;
  EXPECT_NE(a.out.find("a-1.png"), std::string::npos) << a.out;
  for (const char* k : {"-0.png", "-1.png"}) {
    const std::string pa = bytes(dir / (std::string("a") + k)),
                      pb = bytes(dir / (std::string("b") + k));
    ASSERT_GT(pa.size(), 1000u);
    EXPECT_EQ(pa, pb) << k;
  }
  // The cloth has fallen between the two pictures: they differ.
  EXPECT_NE(bytes(dir / "a-0.png"), bytes(dir / "a-1.png"));
  // Nothing is left under a temporary name.
  for (const auto& e : fs::directory_iterator(dir)) {
    EXPECT_EQ(e.path().extension(), ".png") << e.path();
  }
}

TEST(Render, BadOptionsAreRefusedWithTheirReason) {
  const fs::path dir = test::temp_dir("render-bad");
  const std::string scene = test::source_path("configs/demo.yaml").string();
  const std::string png = (dir / "x.png").string();
  struct Case {
    std::vector<std::string> args;
    std::string message;
  };
  const std::vector<Case> cases = {
      {{scene, "--at", "0", "--png", png, "--size", "12x"},
       "pdyn render: --size '12x' is not a picture size (expected WIDTHxHEIGHT in pixels, each "
       "16..16384, e.g. 1200x800)\n"},
      {{scene, "--at", "0", "--png", png, "--view", "top"},
       "pdyn render: --view 'top' is not a view (expected 3d, xy, xz or yz)\n"},
      {{scene, "--at", "0,-1", "--png", png},
       "pdyn render: --at -1 is not a time (expected times >= 0 s, e.g. --at 0,0.5,1)\n"},
      // Cairo writes PNG only: a .jpg name would hold PNG bytes.
      {{scene, "--at", "0", "--png", (dir / "x.jpg").string()},
       "pdyn render: --png '" + (dir / "x.jpg").string() +
           "' does not end in .png (expected a .png file name: pictures are written as PNG "
           "only, e.g. out/frame.png)\n"},
  };
  for (const auto& c : cases) {
    const auto r = render(c.args);
    EXPECT_EQ(r.status, 2) << c.message;
    EXPECT_EQ(r.err, c.message);
  }
  EXPECT_FALSE(fs::exists(png));
  EXPECT_FALSE(fs::exists(dir / "x.jpg"));
  // A bad scene is reported as by `pdyn run`, located.
  const fs::path bad = test::write_file(dir / "bad.yaml",
                                        "simulation: { dt: -1, steps: 1 }\n"
                                        "particles: [{ position: [0, 0, 0] }]\n");
  const auto r = render({bad.string(), "--at", "0", "--png", png});
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("bad.yaml:1:19: simulation.dt:"), std::string::npos) << r.err;
}

// A particle with a radius is a disc of that radius at the camera's scale:
// a pixel 0.8 R from its centre, in any direction, is covered, one 1.3 R
// away is not. A particle without one is the usual marker, and the
// simulation box is a thin wire box around them.
TEST(Render, ParticlesWithRadiiAreDiscsAndTheBoxIsAWireBox) {
  const fs::path dir = test::temp_dir("render-radius");
  const double R = 0.3;
  const fs::path scene = test::write_file(
      dir / "scene.yaml",
      "simulation: { dt: 0.001, steps: 1, box: { min: [-1, -1, -1], max: [1, 1, 1] } }\n"
      "particles:\n"
      "  - { position: [-0.2, 0.1, 0], mass: 1, radius: 0.3 }\n"
      "  - { position: [0.7, -0.6, 0], mass: 1 }\n");
  const fs::path png = dir / "r.png";
  const auto r = render(
      {scene.string(), "--at", "0", "--png", png.string(), "--view", "xy", "--size", "400x400"});
  ASSERT_EQ(r.status, 0) << r.err;
  const Picture pic(png);
  ASSERT_TRUE(pic.ok());
  const Scene s = load_scene(scene, test::shipped_plugins());
  const Drawables d = drawables(s);
  ASSERT_TRUE(d.box);
  std::vector<Vec3> points = cli::render::obstacle_points(d);
  const auto particles = cli::render::particle_points(s.system->positions(), s.system->radii());
  points.insert(points.end(), particles.begin(), particles.end());
  const Camera cam = cli::render::fit_camera(cli::render::View::XY, points, 400, 400);
  ASSERT_GT(R * cam.scale, 20) << "the test needs a disc of many pixels";
  auto px = [&](const Vec3& p) {
    const auto q = cam.pixel(p);
    return pic.at(static_cast<int>(q.x()), static_cast<int>(q.y()));
  };
  const Vec3 c(-0.2, 0.1, 0);
  for (int k = 0; k < 8; ++k) {
    const double a = k * 3.14159265358979 / 4;
    const Vec3 u(std::cos(a), std::sin(a), 0);
    EXPECT_TRUE(near(px(c + 0.8 * R * u), cli::render::kFree)) << "direction " << k;
    EXPECT_TRUE(white(px(c + 1.3 * R * u))) << "direction " << k;
  }
  EXPECT_TRUE(near(px(Vec3(0.7, -0.6, 0)), cli::render::kFree));
  EXPECT_TRUE(white(px(Vec3(0.7, -0.3, 0))));  // the marker is small
  // The box's edges (a line along y at x = -1 and x = 1), not its inside.
  for (const double x : {-1.0, 1.0}) {
    const Rgb edge = px(Vec3(x, 0.5, 0));
    EXPECT_FALSE(white(edge)) << x;
    EXPECT_FALSE(near(edge, cli::render::kFree)) << x;
  }
  EXPECT_TRUE(white(px(Vec3(0.5, 0.6, 0))));
}

// A third party's collider is drawn from its own shape hook: the
// tetra_shape fixture's tetrahedron covers the origin seen along z, with a
// particle far off; a broken hook stops the picture with exit 3, naming the
// collider and its library, and writes nothing.
TEST(Render, AThirdPartyColliderIsDrawnFromItsShapeHook) {
  const fs::path dir = test::temp_dir("render-shape");
  const std::string shapes = (fs::path(PDYN_FIXTURE_DIR) / "shapes").string();
  auto scene = [&](const std::string& mode) {
    return test::write_file(dir / (mode + ".yaml"),
                            "simulation: { dt: 0.001, steps: 1 }\n"
                            "particles: [{ position: [1.5, 1.5, 0], mass: 1 }]\n"
                            "colliders: [{ type: tetra_shape, size: 1, mode: " +
                                mode + " }]\n")
        .string();
  };
  const fs::path png = dir / "tetra.png";
  const auto r = render({scene("mesh"), "--plugin-path", shapes, "--at", "0", "--png", png.string(),
                         "--view", "xy", "--size", "400x400"});
  ASSERT_EQ(r.status, 0) << r.err;
  const Picture pic(png);
  ASSERT_TRUE(pic.ok());
  const double a = 1 / (2 * std::sqrt(2.0));  // the fixture's vertices are (+-a, +-a, +-a)
  const std::vector<Vec3> points{{a, a, a}, {a, -a, -a}, {-a, a, -a}, {-a, -a, a}, {1.5, 1.5, 0}};
  const Camera cam = cli::render::fit_camera(cli::render::View::XY, points, 400, 400);
  auto px = [&](const Vec3& p) {
    const auto q = cam.pixel(p);
    return pic.at(static_cast<int>(q.x()), static_cast<int>(q.y()));
  };
  const Rgb inside = px(Vec3(0.05, 0.02, 0));
  EXPECT_FALSE(white(inside));
  EXPECT_FALSE(near(inside, cli::render::kFree));
  EXPECT_TRUE(near(px(Vec3(1.5, 1.5, 0)), cli::render::kFree));
  EXPECT_TRUE(white(px(Vec3(1.2, -0.2, 0))));  // beside the tetrahedron, inside the frame

  const fs::path broken = dir / "broken.png";
  const auto b =
      render({scene("throw"), "--plugin-path", shapes, "--at", "0", "--png", broken.string()});
  EXPECT_EQ(b.status, 3);
  EXPECT_EQ(b.err, "tetra_shape (" + scene("throw") +
                       ":3:13): shapes() threw: fixture shape failure (library " + shapes +
                       "/pdyn_collider_tetra_shape.so)\n");
  EXPECT_FALSE(fs::exists(broken));
}

}  // namespace
}  // namespace pdyn
