// Links and obstacles of a scene, for pictures and the viewer.
#include "pdyn/host/scene_drawables.hpp"

namespace pdyn {

Drawables drawables(const Scene& scene) {
  Drawables d;
  for (const auto& use : scene.uses) {
    if (use.kind == PluginKind::Force) {
      for (const auto& [name, value] : use.params.values()) {
        if (const auto* pairs = std::get_if<std::vector<IndexPair>>(&value)) {
          d.links.insert(d.links.end(), pairs->begin(), pairs->end());
        } else if (const auto* triples = std::get_if<std::vector<IndexTriple>>(&value)) {
          for (const auto& t : *triples) {
            d.links.push_back({t[0], t[1]});
            d.links.push_back({t[1], t[2]});
            d.links.push_back({t[2], t[0]});
          }
        }
      }
      continue;
    }
    // The shipped colliders' shapes, by their parameter names; a third-party
    // collider is not drawn (its shape is its own business).
    const Params& p = use.params;
    if (use.type == "plane" && p.has("point") && p.has("normal")) {
      d.planes.push_back({p.vec3("point"), p.vec3("normal").normalized()});
    } else if (use.type == "sphere" && p.has("center") && p.has("radius")) {
      d.spheres.push_back({p.vec3("center"), p.real("radius")});
    } else if (use.type == "box" && p.has("min") && p.has("max")) {
      d.boxes.push_back({p.vec3("min"), p.vec3("max")});
    }
  }
  return d;
}

std::vector<Vec3> obstacle_points(const Drawables& d) {
  std::vector<Vec3> pts;
  for (const auto& s : d.spheres) {
    for (int k = 0; k < 3; ++k) {
      pts.push_back(s.center + s.radius * Vec3::Unit(k));
      pts.push_back(s.center - s.radius * Vec3::Unit(k));
    }
  }
  for (const auto& b : d.boxes) {  // all eight corners: any of them may be outermost on screen
    for (int k = 0; k < 8; ++k) {
      pts.emplace_back(k & 1 ? b.max.x() : b.min.x(), k & 2 ? b.max.y() : b.min.y(),
                       k & 4 ? b.max.z() : b.min.z());
    }
  }
  return pts;
}

}  // namespace pdyn
