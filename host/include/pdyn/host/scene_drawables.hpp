// What a picture or a viewer draws besides the particles: links from every
// force's particle pairs (springs) and triples (their edges), the obstacles
// of every collider that describes its shape (pdyn/shape.hpp), and the
// simulation box. Used by `pdyn render` and `pdyn serve`.
#pragma once

#include <optional>
#include <vector>

#include "pdyn/domain.hpp"
#include "pdyn/host/export.hpp"
#include "pdyn/host/scene.hpp"
#include "pdyn/shape.hpp"
#include "pdyn/types.hpp"

namespace pdyn {

struct PDYN_HOST_API Drawables {
  std::vector<IndexPair> links;
  std::vector<shape::Plane> planes;  ///< normals of unit length
  std::vector<shape::Sphere> spheres;
  std::vector<shape::Box> boxes;
  std::vector<shape::Mesh> meshes;
  std::optional<Domain> box;  ///< simulation.box, drawn as a thin wire box; none in open space
};

/// The drawables of a loaded scene, its colliders' shapes as they are now.
/// Throws PluginRuntimeError, naming the collider and its library, when a
/// collider's shapes() throws or gives a shape that cannot be drawn.
PDYN_HOST_API Drawables drawables(const Scene& scene);

/// The scene's simulation box (simulation.box), or nothing when the scene
/// has none (open space: the default Domain, whose min equals its max).
PDYN_HOST_API std::optional<Domain> simulation_box(const Scene& scene);

/// The links alone: every force's particle pairs, and the edges of its
/// triples. Cheap; no plugin is called.
PDYN_HOST_API std::vector<IndexPair> scene_links(const Scene& scene);

/// Points (m) a camera must keep in view for these obstacles: sphere and
/// box extents, mesh vertices and the simulation box's corners (planes are
/// unbounded and are drawn to fit the particles).
PDYN_HOST_API std::vector<Vec3> obstacle_points(const Drawables& d);

}  // namespace pdyn
