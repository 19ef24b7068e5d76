// Links and obstacles of a scene, for pictures and the viewer. The host
// knows no collider by name: each one that derives from ShapeSource says
// what it looks like.
#include "pdyn/host/scene_drawables.hpp"

#include <fmt/format.h>

#include "pdyn/error.hpp"
#include "pdyn/kernel/plugin_call.hpp"

namespace pdyn {

namespace {

void add_links(const Params& params, std::vector<IndexPair>& links) {
  for (const auto& entry : params.values()) {
    if (const auto* pairs = std::get_if<std::vector<IndexPair>>(&entry.second)) {
      links.insert(links.end(), pairs->begin(), pairs->end());
    } else if (const auto* triples = std::get_if<std::vector<IndexTriple>>(&entry.second)) {
      for (const auto& t : *triples) {
        links.push_back({t[0], t[1]});
        links.push_back({t[1], t[2]});
        links.push_back({t[2], t[0]});
      }
    }
  }
}

// The collider's shapes, checked; a fault names the collider and its library.
std::vector<Shape> shapes_of(const Scene& scene, const System::ColliderEntry& entry,
                             const ShapeSource& source) {
  const auto library = scene.libraries.find(entry.label);
  const std::string where = library == scene.libraries.end()
                                ? ""
                                : fmt::format(" (library {})", library->second.string());
  std::vector<Shape> shapes;
  try {
    const crash::CallScope scope(entry.label, "shapes");
    shapes = source.shapes();
  } catch (const std::exception& e) {
    throw PluginRuntimeError(entry.label, fmt::format("shapes() threw: {}{}", e.what(), where));
  } catch (...) {
    throw PluginRuntimeError(entry.label, "shapes() threw a non-standard exception" + where);
  }
  for (std::size_t k = 0; k < shapes.size(); ++k) {
    if (const std::string problem = shape_problem(shapes[k]); !problem.empty()) {
      throw PluginRuntimeError(
          entry.label, fmt::format("shapes()[{}] cannot be drawn: {}{}", k, problem, where));
    }
  }
  return shapes;
}

}  // namespace

std::vector<IndexPair> scene_links(const Scene& scene) {
  std::vector<IndexPair> links;
  for (const auto& use : scene.uses) {
    if (use.kind == PluginKind::Force) add_links(use.params, links);
  }
  return links;
}

std::optional<Domain> simulation_box(const Scene& scene) {
  if (!scene.system) return std::nullopt;
  const Domain& d = scene.system->domain();
  if ((d.min.array() < d.max.array()).all()) return d;
  return std::nullopt;
}

Drawables drawables(const Scene& scene) {
  Drawables d;
  d.links = scene_links(scene);
  if (!scene.system) return d;
  d.box = simulation_box(scene);
  for (const auto& entry : scene.system->collider_objects()) {
    // A collider without the hook collides but is not drawn.
    const auto* source = dynamic_cast<const ShapeSource*>(entry.collider.get());
    if (!source) continue;
    for (auto& s : shapes_of(scene, entry, *source)) {
      if (auto* plane = std::get_if<shape::Plane>(&s)) {
        plane->normal.normalize();
        d.planes.push_back(*plane);
      } else if (const auto* sphere = std::get_if<shape::Sphere>(&s)) {
        d.spheres.push_back(*sphere);
      } else if (const auto* box = std::get_if<shape::Box>(&s)) {
        d.boxes.push_back(*box);
      } else {
        d.meshes.push_back(std::move(std::get<shape::Mesh>(s)));
      }
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
  for (const auto& m : d.meshes) pts.insert(pts.end(), m.vertices.begin(), m.vertices.end());
  if (d.box) {
    for (int k = 0; k < 8; ++k) {
      pts.emplace_back(k & 1 ? d.box->max.x() : d.box->min.x(),
                       k & 2 ? d.box->max.y() : d.box->min.y(),
                       k & 4 ? d.box->max.z() : d.box->min.z());
    }
  }
  return pts;
}

}  // namespace pdyn
