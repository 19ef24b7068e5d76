// pdyn/shape.hpp — what an obstacle looks like, so that `pdyn render` and
// the viewer can draw a collider they know nothing else about.
//
// Drawing is optional: a collider that also derives from ShapeSource is
// drawn; one that does not still collides, it is just not shown. The hook is
// a separate interface rather than a new virtual of Collider so that a
// collider built against an earlier SDK keeps its vtable (no ABI bump): the
// host asks each collider with dynamic_cast<const ShapeSource*>.
//
//   class Ring final : public pdyn::SurfaceCollider, public pdyn::ShapeSource {
//     ...
//     std::vector<pdyn::Shape> shapes() const override {
//       return {pdyn::shape::Mesh{vertices_, triangles_}};
//     }
//   };
//
// Shapes are for pictures only: nothing in a run depends on them.
#pragma once

#include <string>
#include <variant>
#include <vector>

#include "pdyn/export.hpp"
#include "pdyn/types.hpp"

namespace pdyn {

namespace shape {
/// An infinite plane through `point` (m) with unit `normal` towards the free side.
struct PDYN_API Plane {
  Vec3 point = Vec3::Zero();
  Vec3 normal = Vec3::UnitZ();
};
/// A sphere of centre `center` (m) and radius `radius` (m, > 0).
struct PDYN_API Sphere {
  Vec3 center = Vec3::Zero();
  double radius = 1.0;
};
/// An axis-aligned box between the corners `min` and `max` (m, min < max).
struct PDYN_API Box {
  Vec3 min = Vec3::Constant(-0.5);
  Vec3 max = Vec3::Constant(0.5);
};
/// Any other surface, as triangles: `vertices` (m) and `triangles`, each
/// three indices into `vertices`, counter-clockwise seen from the free side.
struct PDYN_API Mesh {
  std::vector<Vec3> vertices;
  std::vector<IndexTriple> triangles;
};
}  // namespace shape

/// One drawable piece of an obstacle.
using Shape = std::variant<shape::Plane, shape::Sphere, shape::Box, shape::Mesh>;

/// The optional drawing hook of a collider (see the top of this file).
class PDYN_API ShapeSource {
 public:
  virtual ~ShapeSource();
  /// The obstacle's pieces, in metres, as they are now. Called by the host
  /// between steps, never during one; may allocate.
  virtual std::vector<Shape> shapes() const = 0;
};

/// Why `shape` cannot be drawn, e.g. "mesh: triangle 0 names vertex 7
/// (expected 0..3)" (a non-finite coordinate, a zero normal, a radius <= 0,
/// min not below max, a triangle index outside the vertices), or an empty
/// string when it can. The host checks every shape a plugin gives.
PDYN_API std::string shape_problem(const Shape& shape);

}  // namespace pdyn
