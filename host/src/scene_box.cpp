// The loader's simulation box and per-particle properties: reading
// simulation.box into the kernel's Domain, checking that particles start
// inside it along open axes (periodic ones are wrapped), and recording the
// radii and types that particles, builders and side files give (a box
// taken from a file is scene_files.cpp's). Members of Loader (loader.hpp),
// apart from scene_loader.cpp for size.
#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>

#include "loader.hpp"
#include "pdyn/text.hpp"

namespace pdyn::loading {

// simulation.box: the kernel's Domain. min < max along every axis, so that
// the box can be drawn and checked against, although only its periodic
// axes change the simulation.
void Loader::read_box(const YAML::Node& n) {
  const std::string path = "simulation.box";
  if (n.IsMap() && n["file"].IsDefined()) return read_box_file(n, path);
  if (!check_map(n, path,
                 "box: { min: [x, y, z], max: [x, y, z], periodic: [bool, bool, bool] }")) {
    return;
  }
  auto p = read_params(n, path, box_specs(), {"periodic"}, -1);
  std::array<bool, 3> periodic{};
  const bool periodic_ok = read_periodic(n["periodic"], path + ".periodic", periodic);
  if (!p || !periodic_ok) return;
  const Vec3 lo = p->vec3("min"), hi = p->vec3("max");
  for (int k = 0; k < 3; ++k) {
    if (lo[k] < hi[k]) continue;
    error(n["max"], path + ".max",
          fmt::format("{}.max: [{}, {}, {}] is not above min [{}, {}, {}] in {} (expected max > "
                      "min in every component)",
                      path, hi.x(), hi.y(), hi.z(), lo.x(), lo.y(), lo.z(), "xyz"[k]));
    return;
  }
  Domain d;
  d.min = lo;
  d.max = hi;
  d.periodic = periodic;
  box_ = d;
}

// `periodic: [x, y, z]`, each written as a boolean is anywhere in a scene
// (true/false, yes/no, on/off, 1/0); absent or null: open along every axis.
bool Loader::read_periodic(const YAML::Node& n, const std::string& path, std::array<bool, 3>& out) {
  if (!n.IsDefined() || n.IsNull()) return true;
  constexpr const char* expected =
      "a list of 3 booleans, one per axis x, y, z, e.g. [true, true, false]";
  if (!n.IsSequence() || n.size() != 3) {
    const std::string found = n.IsSequence()
                                  ? "it has " + count_of(static_cast<long long>(n.size()), "value")
                              : n.IsMap() ? fmt::format("it is the mapping {}", shown(n))
                                          : fmt::format("it is '{}'", shown(n));
    error(n, path,
          fmt::format("{}: is not a list of 3 booleans: {} (expected {})", path, found, expected));
    return false;
  }
  bool ok = true;
  for (std::size_t k = 0; k < 3; ++k) {
    const YAML::Node e = n[k];
    bool b = false;
    if (e.IsScalar() && YAML::convert<bool>::decode(e, b)) {
      out[k] = b;
    } else if (e.IsScalar() && (e.Scalar() == "0" || e.Scalar() == "1")) {
      out[k] = e.Scalar() == "1";
    } else {
      error(e, fmt::format("{}[{}]", path, k),
            fmt::format("{}[{}]: '{}' is not true or false (expected {})", path, k, shown(e),
                        expected));
      ok = false;
    }
  }
  return ok;
}

// Along an axis that is not periodic the box is not a wall (a particle may
// leave it during the run), but a scene that starts outside its own box is
// a mistake: reported once per particles entry, at its first such particle.
void Loader::check_inside_box() {
  if (!box_ || !particles_ok_) return;
  const Domain& d = *box_;
  for (const auto& e : entries_) {
    Index bad = -1;
    int axis = 0;
    std::int64_t more = 0;
    for (Index i = e.first; i < e.end; ++i) {
      const Vec3& x = x_[static_cast<std::size_t>(i)];
      for (int k = 0; k < 3; ++k) {
        if (d.periodic[k] || (x[k] >= d.min[k] && x[k] <= d.max[k])) continue;
        if (bad < 0) {
          bad = i;
          axis = k;
        } else {
          ++more;
        }
        break;
      }
    }
    if (bad < 0) continue;
    const char name = "xyz"[axis];
    error(e.node, e.path,
          fmt::format("{}: particle {} is outside simulation.box along {}: {} = {} m is not in "
                      "[{}, {}]{} (expected initial positions inside the box along every axis "
                      "that is not periodic)",
                      e.path, bad, name, name, x_[static_cast<std::size_t>(bad)][axis], d.min[axis],
                      d.max[axis],
                      more == 0 ? ""
                      : more == 1
                          ? ", and so is 1 more particle of this entry"
                          : fmt::format(", and so are {} more particles of this entry", more)));
  }
}

void Loader::set_properties(Index first, std::int64_t count, const ParticleProperties& p) {
  const auto b = static_cast<std::ptrdiff_t>(first), e = b + static_cast<std::ptrdiff_t>(count);
  if (p.radius) {
    radius_.resize(x_.size(), 0.0);
    std::fill(radius_.begin() + b, radius_.begin() + e, *p.radius);
  }
  if (p.type) {
    type_.resize(x_.size(), 0);
    std::fill(type_.begin() + b, type_.begin() + e, *p.type);
  }
}

}  // namespace pdyn::loading
