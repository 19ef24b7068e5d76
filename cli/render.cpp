// `pdyn render`: draws a scene at given times to PNG files with Cairo.
//
// Each picture shows the state that `pdyn run --duration T` ends in: the
// scene is loaded and run to T by the same runner, with its output files
// turned off, so a picture and a run's final frame always agree. The camera
// is fitted once to every frame and obstacle, so a series of pictures shares
// one framing and can be flipped through.
#include "render.hpp"

#include <cairo.h>
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <memory>
#include <numeric>
#include <ostream>

#include "commands.hpp"
#include "pdyn/error.hpp"
#include "pdyn/host/registry.hpp"
#include "pdyn/host/runner.hpp"
#include "pdyn/text.hpp"

namespace pdyn::cli {

namespace fs = std::filesystem;

namespace render {

bool parse_view(const std::string& text, View& view) {
  if (text == "3d")
    view = View::Oblique;
  else if (text == "xy")
    view = View::XY;
  else if (text == "xz")
    view = View::XZ;
  else if (text == "yz")
    view = View::YZ;
  else
    return false;
  return true;
}

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr int kLabelHeight = 24;  // px reserved at the top for the caption

// Screen axes (right, up, toward the viewer), a right-handed frame:
// right x up = toward. The oblique view looks from 60 degrees clockwise of
// -y (azimuth -60 deg from +x) and 25 degrees above the horizon, with z up.
void axes(View view, Vec3& right, Vec3& up, Vec3& toward) {
  switch (view) {
    case View::XY:
      right = Vec3::UnitX();
      up = Vec3::UnitY();
      toward = Vec3::UnitZ();
      return;
    case View::XZ:
      right = Vec3::UnitX();
      up = Vec3::UnitZ();
      toward = -Vec3::UnitY();
      return;
    case View::YZ:
      right = Vec3::UnitY();
      up = Vec3::UnitZ();
      toward = Vec3::UnitX();
      return;
    case View::Oblique: {
      const double az = -60.0 * kPi / 180.0, el = 25.0 * kPi / 180.0;
      toward = Vec3(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
      right = Vec3::UnitZ().cross(toward).normalized();
      up = toward.cross(right);
      return;
    }
  }
}

}  // namespace

Camera fit_camera(View view, const std::vector<Vec3>& points, int width, int height) {
  Camera cam;
  axes(view, cam.right, cam.up, cam.toward);
  Eigen::Vector2d lo(0, 0), hi(0, 0);
  if (!points.empty()) {
    lo = hi = Eigen::Vector2d(points[0].dot(cam.right), points[0].dot(cam.up));
  }
  for (const auto& p : points) {
    const Eigen::Vector2d q(p.dot(cam.right), p.dot(cam.up));
    lo = lo.cwiseMin(q);
    hi = hi.cwiseMax(q);
  }
  Eigen::Vector2d extent = hi - lo;
  const Eigen::Vector2d center = (lo + hi) / 2;
  // A flat or single-point scene still gets a finite field of view: the
  // larger extent, or 1 m when everything is one point.
  const double largest = std::max(extent.x(), extent.y());
  const double floor = largest > 0 ? largest * 1e-3 : 1.0;
  extent = extent.cwiseMax(floor);
  const double margin = 0.06 * std::min(width, height) + 8;
  const double usable_w = std::max(1.0, width - 2 * margin);
  const double usable_h = std::max(1.0, height - kLabelHeight - 2 * margin);
  cam.scale = std::min(usable_w / extent.x(), usable_h / extent.y());
  const double cx = width / 2.0, cy = kLabelHeight + (height - kLabelHeight) / 2.0;
  cam.origin = {cx - cam.scale * center.x(), cy + cam.scale * center.y()};
  return cam;
}

std::vector<Vec3> particle_points(const Matrix3X& x, std::span<const double> radius) {
  std::vector<Vec3> points;
  points.reserve(static_cast<std::size_t>(x.cols()));
  for (Index i = 0; i < x.cols(); ++i) {
    const double r = radius.empty() ? 0.0 : radius[static_cast<std::size_t>(i)];
    if (r <= 0) {
      points.push_back(x.col(i));
      continue;
    }
    // A sphere's outline projects to a circle of radius r; a cube's corners
    // reach at least r along any screen direction u (|u|_1 >= |u|_2 = 1).
    for (int k = 0; k < 8; ++k) {
      points.push_back(x.col(i) + r * Vec3(k & 1 ? 1 : -1, k & 2 ? 1 : -1, k & 4 ? 1 : -1));
    }
  }
  return points;
}

namespace {

// One state to draw: positions (m), nailed flags and radii (m; empty: none)
// at time t (s).
struct Frame {
  double t = 0.0;
  Matrix3X x;
  std::vector<std::uint8_t> fixed;
  std::vector<double> radius;
};

void line(cairo_t* cr, const Camera& cam, const Vec3& a, const Vec3& b) {
  const auto p = cam.pixel(a), q = cam.pixel(b);
  cairo_move_to(cr, p.x(), p.y());
  cairo_line_to(cr, q.x(), q.y());
}

// A plane is unbounded: it is drawn as a square patch around the centre of
// every frame's particles, projected onto it, as wide as their bounding box.
std::array<Vec3, 4> plane_patch(const shape::Plane& pl, const Vec3& lo, const Vec3& hi) {
  const Vec3& n = pl.normal;
  Vec3 a = Vec3::UnitX();
  if (std::abs(n.x()) > std::abs(n.y()) && std::abs(n.x()) > std::abs(n.z())) a = Vec3::UnitY();
  const Vec3 t1 = n.cross(a).normalized(), t2 = n.cross(t1);
  const Vec3 center = (lo + hi) / 2;
  const Vec3 c = center - (center - pl.point).dot(n) * n;
  const double half = std::max(0.25, 0.6 * (hi - lo).maxCoeff());
  return {c + half * (t1 + t2), c + half * (t1 - t2), c - half * (t1 + t2), c - half * (t1 - t2)};
}

void draw_plane(cairo_t* cr, const Camera& cam, const std::array<Vec3, 4>& corners) {
  for (int k = 0; k < 4; ++k) {
    const auto p = cam.pixel(corners[k]);
    k == 0 ? cairo_move_to(cr, p.x(), p.y()) : cairo_line_to(cr, p.x(), p.y());
  }
  cairo_close_path(cr);
  cairo_set_source_rgb(cr, 0.86, 0.88, 0.91);
  cairo_fill_preserve(cr);
  cairo_set_source_rgb(cr, 0.55, 0.60, 0.66);
  cairo_set_line_width(cr, 1.5);
  cairo_stroke(cr);
}

// The twelve edges of the axis-aligned box [lo, hi], as a path to stroke.
void box_edges(cairo_t* cr, const Camera& cam, const Vec3& lo, const Vec3& hi) {
  auto corner = [&](int k) {
    return Vec3(k & 1 ? hi.x() : lo.x(), k & 2 ? hi.y() : lo.y(), k & 4 ? hi.z() : lo.z());
  };
  for (int k = 0; k < 8; ++k) {
    for (int bit : {1, 2, 4}) {
      if (!(k & bit)) line(cr, cam, corner(k), corner(k | bit));
    }
  }
}

void draw_box(cairo_t* cr, const Camera& cam, const shape::Box& b) {
  box_edges(cr, cam, b.min, b.max);
  cairo_set_source_rgb(cr, 0.40, 0.45, 0.52);
  cairo_set_line_width(cr, 1.5);
  cairo_stroke(cr);
}

// The simulation box: a thin wire box, dashed when some axis is periodic
// (its faces there are not walls but where the space repeats).
void draw_domain(cairo_t* cr, const Camera& cam, const Domain& b) {
  box_edges(cr, cam, b.min, b.max);
  const double dash[] = {5.0, 3.0};
  cairo_set_dash(cr, dash, b.any_periodic() ? 2 : 0, 0);
  cairo_set_source_rgb(cr, 0.30, 0.55, 0.45);
  cairo_set_line_width(cr, 1.0);
  cairo_stroke(cr);
  cairo_set_dash(cr, nullptr, 0, 0);
}

void draw_sphere(cairo_t* cr, const Camera& cam, const shape::Sphere& s) {
  const auto c = cam.pixel(s.center);
  cairo_new_sub_path(cr);
  cairo_arc(cr, c.x(), c.y(), s.radius * cam.scale, 0, 2 * kPi);
  cairo_set_source_rgb(cr, 0.82, 0.86, 0.92);
  cairo_fill_preserve(cr);
  cairo_set_source_rgb(cr, 0.40, 0.45, 0.52);
  cairo_set_line_width(cr, 1.5);
  cairo_stroke(cr);
}

// A mesh's triangles, far ones first, each filled lightly and outlined.
void draw_mesh(cairo_t* cr, const Camera& cam, const shape::Mesh& m) {
  std::vector<std::size_t> order(m.triangles.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  auto depth = [&](std::size_t t) {
    const auto& tri = m.triangles[t];
    return cam.depth(m.vertices[static_cast<std::size_t>(tri[0])] +
                     m.vertices[static_cast<std::size_t>(tri[1])] +
                     m.vertices[static_cast<std::size_t>(tri[2])]);
  };
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return depth(a) < depth(b); });
  cairo_set_line_width(cr, 1.0);
  for (std::size_t t : order) {
    for (int k = 0; k < 3; ++k) {
      const auto p = cam.pixel(m.vertices[static_cast<std::size_t>(m.triangles[t][k])]);
      k == 0 ? cairo_move_to(cr, p.x(), p.y()) : cairo_line_to(cr, p.x(), p.y());
    }
    cairo_close_path(cr);
    cairo_set_source_rgba(cr, 0.82, 0.86, 0.92, 0.8);
    cairo_fill_preserve(cr);
    cairo_set_source_rgb(cr, 0.40, 0.45, 0.52);
    cairo_stroke(cr);
  }
}

}  // namespace

namespace {

void draw(cairo_t* cr, const Camera& cam, const Frame& f, const Drawables& d,
          const std::vector<std::array<Vec3, 4>>& patches, int width, int height,
          const std::string& caption) {
  cairo_set_source_rgb(cr, 1, 1, 1);
  cairo_paint(cr);
  const Index n = f.x.cols();
  for (const auto& patch : patches) draw_plane(cr, cam, patch);
  for (const auto& s : d.spheres) draw_sphere(cr, cam, s);
  for (const auto& b : d.boxes) draw_box(cr, cam, b);
  for (const auto& m : d.meshes) draw_mesh(cr, cam, m);
  if (d.box) draw_domain(cr, cam, *d.box);

  cairo_set_line_width(cr, 1.0);
  for (const auto& l : d.links) line(cr, cam, f.x.col(l[0]), f.x.col(l[1]));
  cairo_set_source_rgba(cr, 0.45, 0.47, 0.52, 0.7);
  cairo_stroke(cr);

  // Far particles first (painter's order); ties keep index order, so the
  // picture is the same on every run.
  std::vector<Index> order(static_cast<std::size_t>(n));
  std::iota(order.begin(), order.end(), Index{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](Index a, Index b) { return cam.depth(f.x.col(a)) < cam.depth(f.x.col(b)); });
  // A marker of at least kMinRadiusPixels, smaller the more particles there
  // are; a particle with a radius is a disc of that radius at the camera's
  // scale (never smaller than the marker's minimum), outlined so that
  // touching spheres stay apart.
  const double r = std::clamp(0.12 * std::min(width, height) / std::sqrt(static_cast<double>(n)),
                              kMinRadiusPixels, 5.0);
  for (Index i : order) {
    const auto p = cam.pixel(f.x.col(i));
    const double radius = f.radius.empty() ? 0.0 : f.radius[static_cast<std::size_t>(i)];
    if (radius > 0) {
      const double* fill = f.fixed[static_cast<std::size_t>(i)] ? kFixed : kFree;
      cairo_new_sub_path(cr);
      cairo_arc(cr, p.x(), p.y(), std::max(radius * cam.scale, kMinRadiusPixels), 0, 2 * kPi);
      cairo_set_source_rgb(cr, fill[0], fill[1], fill[2]);
      cairo_fill_preserve(cr);
      cairo_set_source_rgb(cr, 0.6 * fill[0], 0.6 * fill[1], 0.6 * fill[2]);
      cairo_set_line_width(cr, std::min(1.0, 0.25 * radius * cam.scale));
      cairo_stroke(cr);
      continue;
    }
    if (f.fixed[static_cast<std::size_t>(i)]) {
      cairo_rectangle(cr, p.x() - 1.3 * r, p.y() - 1.3 * r, 2.6 * r, 2.6 * r);
      cairo_set_source_rgb(cr, kFixed[0], kFixed[1], kFixed[2]);
    } else {
      cairo_new_sub_path(cr);
      cairo_arc(cr, p.x(), p.y(), r, 0, 2 * kPi);
      cairo_set_source_rgb(cr, kFree[0], kFree[1], kFree[2]);
    }
    cairo_fill(cr);
  }

  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, 14);
  cairo_set_source_rgb(cr, 0.2, 0.2, 0.2);
  cairo_move_to(cr, 8, 17);
  cairo_show_text(cr, caption.c_str());
}

}  // namespace
}  // namespace render

namespace {

struct RenderArgs {
  std::string scene;
  std::vector<double> at;
  std::string png;
  std::string size = "1200x800";
  std::string view = "3d";
  std::vector<std::string> sets;
  std::vector<std::string> plugin_path;
  bool quiet = false;
};

// "frame.png" for one picture; "frame-0.png", "frame-1.png", ... for several.
fs::path picture_path(const fs::path& png, std::size_t k, std::size_t count) {
  if (count == 1) return png;
  const int digits = static_cast<int>(std::to_string(count - 1).size());
  return png.parent_path() /
         fmt::format("{}-{:0{}}{}", png.stem().string(), k, digits, png.extension().string());
}

// Writes the surface under a temporary name beside `path` and renames it,
// so a failed write never leaves a picture that looks finished.
void write_png(cairo_surface_t* surface, const fs::path& path) {
  if (path.has_parent_path()) fs::create_directories(path.parent_path());
  const fs::path temp = path.string() + ".tmp";
  const cairo_status_t status = cairo_surface_write_to_png(surface, temp.c_str());
  if (status != CAIRO_STATUS_SUCCESS) {
    std::error_code ec;
    fs::remove(temp, ec);
    throw Error(fmt::format("cannot write {}: {}", path.string(), cairo_status_to_string(status)));
  }
  fs::rename(temp, path);
}

// --size, --png, --view and --at checked: false (with the message printed)
// if one is wrong.
bool render_args_ok(const RenderArgs& a, int& width, int& height, render::View& view,
                    std::ostream& err) {
  char x = 0, rest = 0;
  if (std::sscanf(a.size.c_str(), "%d%c%d%c", &width, &x, &height, &rest) != 3 || x != 'x' ||
      width < 16 || height < 16 || width > 16384 || height > 16384) {
    err << fmt::format(
        "pdyn render: --size '{}' is not a picture size (expected WIDTHxHEIGHT in "
        "pixels, each 16..16384, e.g. 1200x800)\n",
        a.size);
    return false;
  }
  // Cairo writes PNG bytes whatever the name: a .jpg file would hold a PNG.
  std::string extension = fs::path(a.png).extension().string();
  for (char& ch : extension) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  if (extension != ".png") {
    err << fmt::format(
        "pdyn render: --png '{}' does not end in .png (expected a .png file name: "
        "pictures are written as PNG only, e.g. out/frame.png)\n",
        a.png);
    return false;
  }
  if (!render::parse_view(a.view, view)) {
    err << fmt::format("pdyn render: --view '{}' is not a view (expected 3d, xy, xz or yz)\n",
                       a.view);
    return false;
  }
  for (double t : a.at) {
    if (!std::isfinite(t) || t < 0) {
      err << fmt::format(
          "pdyn render: --at {} is not a time (expected times >= 0 s, e.g. "
          "--at 0,0.5,1)\n",
          t);
      return false;
    }
  }
  return true;
}

// One run per picture, each from the start: the state at T is exactly the
// final state of `pdyn run --duration T`. Returns a run's nonzero exit
// status (its message printed), else 0.
int run_to_frames(const RenderArgs& a, std::vector<render::Frame>& frames, render::Drawables& drawn,
                  std::ostream& err) {
  PluginRegistry registry;
  registry.discover(
      PluginRegistry::search_path(std::vector<fs::path>(a.plugin_path.begin(), a.plugin_path.end()),
                                  DefaultFolders::LibraryAndProgram));
  std::vector<Override> base;
  for (const auto& s : a.sets) base.push_back(parse_override(s));

  for (std::size_t k = 0; k < a.at.size(); ++k) {
    auto overrides = base;
    if (a.at[k] > 0) {
      overrides.push_back({"simulation.steps", "~"});
      overrides.push_back({"simulation.duration", fmt::format("{:.17g}", a.at[k])});
    }
    Scene scene = load_scene(a.scene, registry, overrides);
    scene.output = {};  // pictures only: no frames, energies or checkpoints
    if (a.at[k] > 0) {
      const RunResult r = run_scene(scene);
      if (r.exit_code != 0) {
        err << fmt::format("pdyn render: {} at t = {} s: {}\n", a.scene, a.at[k], r.message);
        return r.exit_code;
      }
    }
    if (k == 0) drawn = render::drawables(scene);
    frames.push_back({scene.system->time(), scene.system->positions(), scene.system->fixed(),
                      scene.system->radii()});
  }
  return 0;
}

// The pictures: one camera fitted to every frame, obstacles and planes.
void draw_frames(const RenderArgs& a, const std::vector<render::Frame>& frames,
                 const render::Drawables& drawn, render::View view, int width, int height,
                 std::ostream& out) {
  Vec3 lo = frames[0].x.rowwise().minCoeff(), hi = frames[0].x.rowwise().maxCoeff();
  for (const auto& f : frames) {
    lo = lo.cwiseMin(f.x.rowwise().minCoeff());
    hi = hi.cwiseMax(f.x.rowwise().maxCoeff());
  }
  std::vector<Vec3> points = render::obstacle_points(drawn);
  std::vector<std::array<Vec3, 4>> patches;
  for (const auto& pl : drawn.planes) {
    patches.push_back(render::plane_patch(pl, lo, hi));
    points.insert(points.end(), patches.back().begin(), patches.back().end());
  }
  for (const auto& f : frames) {
    const auto p = render::particle_points(f.x, f.radius);
    points.insert(points.end(), p.begin(), p.end());
  }
  const render::Camera cam = render::fit_camera(view, points, width, height);
  const std::string name = fs::path(a.scene).filename().string();
  std::unique_ptr<cairo_surface_t, decltype(&cairo_surface_destroy)> surface(
      cairo_image_surface_create(CAIRO_FORMAT_RGB24, width, height), cairo_surface_destroy);
  std::unique_ptr<cairo_t, decltype(&cairo_destroy)> cr(cairo_create(surface.get()), cairo_destroy);
  for (std::size_t k = 0; k < frames.size(); ++k) {
    const std::string caption = fmt::format("{}   t = {:.3f} s   {}   view {}", name, frames[k].t,
                                            count_of(frames[k].x.cols(), "particle"), a.view);
    render::draw(cr.get(), cam, frames[k], drawn, patches, width, height, caption);
    cairo_surface_flush(surface.get());
    const fs::path path = picture_path(a.png, k, frames.size());
    write_png(surface.get(), path);
    if (!a.quiet) out << fmt::format("pdyn render: t = {} s -> {}\n", frames[k].t, path.string());
  }
}

int cmd_render(const RenderArgs& a, std::ostream& out, std::ostream& err) {
  int width = 0, height = 0;
  render::View view;
  if (!render_args_ok(a, width, height, view, err)) return kBadInput;
  std::vector<render::Frame> frames;
  render::Drawables drawn;
  if (const int status = run_to_frames(a, frames, drawn, err); status != 0) return status;
  draw_frames(a, frames, drawn, view, width, height, out);
  return kOk;
}

}  // namespace

SdkCommand add_render_command(CLI::App& app) {
  auto a = std::make_shared<RenderArgs>();
  CLI::App* sub = app.add_subcommand("render", "draw a scene at given times to PNG pictures");
  sub->add_option("scene", a->scene, "scene file (YAML)")->required();
  sub->add_option("--at", a->at, "simulated times in s, comma-separated, e.g. 0,0.5,1")
      ->required()
      ->delimiter(',');
  sub->add_option("--png", a->png,
                  "picture file; with several times, FILE-0.png, FILE-1.png, ... are written")
      ->required();
  sub->add_option("--size", a->size, "picture size in pixels, WIDTHxHEIGHT (default 1200x800)");
  sub->add_option("--view", a->view,
                  "3d (oblique, z up), xy (down the z axis), xz (along +y) or yz (along -x)");
  add_scene_options(sub, a->sets, a->plugin_path);
  sub->add_flag("--quiet,-q", a->quiet, "print only errors");
  return {sub, [a](std::ostream& out, std::ostream& err) { return cmd_render(*a, out, err); }};
}

}  // namespace pdyn::cli
