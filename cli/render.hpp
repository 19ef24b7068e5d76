// `pdyn render`: pictures of a scene at given times, drawn with Cairo to PNG
// files, with no display. The camera is orthographic and fitted to what is
// drawn, so that a test (or a person) can tell where a particle lands.
#pragma once

#include <Eigen/Core>
#include <span>
#include <string>
#include <vector>

#include "pdyn/host/scene.hpp"
#include "pdyn/host/scene_drawables.hpp"
#include "pdyn/types.hpp"
#include "sdk_commands.hpp"

namespace pdyn::cli {

/// `pdyn render SCENE --at T1,T2,... --png FILE [--size WxH] [--view 3d|xy|xz|yz]`.
SdkCommand add_render_command(CLI::App& app);

namespace render {

/// Which way the camera looks: `3d` is an oblique view with z up; `xy`
/// looks down the z axis, `xz` along +y, `yz` along -x.
enum class View { Oblique, XY, XZ, YZ };

/// Fill colours (RGB in 0..1) of free and nailed particles.
inline constexpr double kFree[3] = {0.12, 0.30, 0.65};
inline constexpr double kFixed[3] = {0.80, 0.10, 0.10};

/// Parses "3d", "xy", "xz" or "yz"; false for anything else.
bool parse_view(const std::string& text, View& view);

/// An orthographic camera from world coordinates (m) to pixels (x to the
/// right, y down, origin at the image's top-left corner).
struct Camera {
  Vec3 right, up, toward;  ///< unit screen axes in the world; `toward` points at the viewer
  double scale = 1.0;      ///< pixels per metre
  Eigen::Vector2d origin;  ///< pixel where the world origin lands
  Eigen::Vector2d pixel(const Vec3& p) const {
    return {origin.x() + scale * p.dot(right), origin.y() - scale * p.dot(up)};
  }
  /// Larger is nearer the viewer; draw far things first.
  double depth(const Vec3& p) const { return p.dot(toward); }
};

/// The camera looking along `view` that fits `points` (m) into a
/// `width` x `height` image with a margin, keeping the aspect ratio. A single
/// point, or none, gets a 1 m field of view.
Camera fit_camera(View view, const std::vector<Vec3>& points, int width, int height);

/// The points a camera must keep in view for particles at `x` (m, 3 x N)
/// with radii `radius` (m, N, or empty): each centre, and the corners of the
/// cube around each particle of radius > 0, so that its disc is not cut off
/// in any view.
std::vector<Vec3> particle_points(const Matrix3X& x, std::span<const double> radius);

/// The smallest radius (px) a particle is drawn with: the pixel under its
/// centre is then wholly inside its disc (a pixel's far corner is at most
/// sqrt(2) px away).
inline constexpr double kMinRadiusPixels = 1.6;

/// Links and obstacles: see scene_drawables.hpp.
using pdyn::Drawables;
using pdyn::drawables;
using pdyn::obstacle_points;

}  // namespace render
}  // namespace pdyn::cli
