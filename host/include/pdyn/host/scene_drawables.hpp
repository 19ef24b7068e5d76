// What a picture or a viewer draws besides the particles, read from a
// scene's plugin parameters: links from every force's particle pairs
// (springs) and triples (their edges), and the obstacles of the shipped
// colliders. Used by `pdyn render` and `pdyn serve`.
#pragma once

#include <vector>

#include "pdyn/host/scene.hpp"
#include "pdyn/types.hpp"

namespace pdyn {

struct Drawables {
  std::vector<IndexPair> links;
  struct Plane {
    Vec3 point, normal;
  };  ///< m; unit normal
  struct Sphere {
    Vec3 center;
    double radius;
  };  ///< m
  struct Box {
    Vec3 min, max;
  };  ///< m, axis-aligned
  std::vector<Plane> planes;
  std::vector<Sphere> spheres;
  std::vector<Box> boxes;
};
Drawables drawables(const Scene& scene);

/// Points (m) a camera must keep in view for these obstacles: sphere and
/// box extents (planes are unbounded and are drawn to fit the particles).
std::vector<Vec3> obstacle_points(const Drawables& d);

}  // namespace pdyn
