// The drawing hook's out-of-line parts: the key function, so that
// ShapeSource's type information lives once, in the kernel, and
// dynamic_cast finds it from any plugin; and the check of a shape.
#include "pdyn/shape.hpp"

#include <fmt/format.h>

#include <cmath>

namespace pdyn {

ShapeSource::~ShapeSource() = default;

namespace {

bool finite(const Vec3& v) { return v.allFinite(); }

std::string problem(const shape::Plane& p) {
  if (!finite(p.point) || !finite(p.normal)) return "plane: non-finite point or normal";
  if (p.normal.norm() == 0.0) return "plane: zero normal (expected a unit normal)";
  return {};
}

std::string problem(const shape::Sphere& s) {
  if (!finite(s.center) || !std::isfinite(s.radius)) return "sphere: non-finite centre or radius";
  if (!(s.radius > 0.0))
    return fmt::format("sphere: radius {} (expected a radius > 0 m)", s.radius);
  return {};
}

std::string problem(const shape::Box& b) {
  if (!finite(b.min) || !finite(b.max)) return "box: non-finite corner";
  if (!(b.min.array() < b.max.array()).all()) {
    return "box: min is not below max (expected min < max in every component)";
  }
  return {};
}

std::string problem(const shape::Mesh& m) {
  for (std::size_t k = 0; k < m.vertices.size(); ++k) {
    if (!finite(m.vertices[k])) return fmt::format("mesh: non-finite vertex {}", k);
  }
  const auto n = static_cast<Index>(m.vertices.size());
  for (std::size_t t = 0; t < m.triangles.size(); ++t) {
    for (Index i : m.triangles[t]) {
      if (i < 0 || i >= n) {
        return fmt::format("mesh: triangle {} names vertex {} (expected 0..{})", t, i, n - 1);
      }
    }
  }
  return {};
}

}  // namespace

std::string shape_problem(const Shape& shape) {
  return std::visit([](const auto& s) { return problem(s); }, shape);
}

}  // namespace pdyn
