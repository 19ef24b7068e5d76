// The grid builder: a rectangular sheet of nx x ny particles at origin + i u
// + j v; particle (i, j) gets index base + j nx + i. Springs per Provot's
// cloth model ("Deformation Constraints in a Mass-Spring Model to Describe
// Rigid Cloth Behavior", 1995): structural (neighbours), shear (diagonals),
// bend (second neighbours), each a `spring` force object; and `bending`, a
// `dihedral` force object on every interior edge of the sheet's
// triangulation (Baraff & Witkin 1998, section 4.3: bending as the angle
// between adjacent triangles). It sees the loader only through BuilderHost,
// like the other builders.
#include <fmt/format.h>

#include "pdyn/host/scene_specs.hpp"
#include "scene_builders.hpp"

namespace pdyn {

namespace {

// The pairs of one spring family over the whole sheet.
std::vector<IndexPair> family_pairs(char kind, std::int64_t nx, std::int64_t ny, Index base) {
  auto id = [&](std::int64_t i, std::int64_t j) { return base + j * nx + i; };
  std::vector<IndexPair> pairs;
  pairs.reserve(static_cast<std::size_t>(2 * nx * ny));
  for (std::int64_t j = 0; j < ny; ++j) {
    for (std::int64_t i = 0; i < nx; ++i) {
      if (kind == 't') {
        if (i + 1 < nx) pairs.push_back({id(i, j), id(i + 1, j)});
        if (j + 1 < ny) pairs.push_back({id(i, j), id(i, j + 1)});
      } else if (kind == 'h') {
        if (i + 1 < nx && j + 1 < ny) {
          pairs.push_back({id(i, j), id(i + 1, j + 1)});
          pairs.push_back({id(i + 1, j), id(i, j + 1)});
        }
      } else {
        if (i + 2 < nx) pairs.push_back({id(i, j), id(i + 2, j)});
        if (j + 2 < ny) pairs.push_back({id(i, j), id(i, j + 2)});
      }
    }
  }
  return pairs;
}

// The hinges of the sheet cut into triangles: each cell (i, j)..(i+1, j+1)
// split along its diagonal (i, j)-(i+1, j+1) into (i, j), (i+1, j),
// (i+1, j+1) and (i, j), (i+1, j+1), (i, j+1). Every edge two triangles
// share is one quadruple [a, edge, edge, b], a and b the corners opposite
// the edge: the cells' diagonals, the row edges between rows 1..ny-2 and
// the column edges between columns 1..nx-2. A flat sheet has phi = pi at
// every hinge.
std::vector<IndexQuad> hinge_quads(std::int64_t nx, std::int64_t ny, Index base) {
  auto id = [&](std::int64_t i, std::int64_t j) { return base + j * nx + i; };
  std::vector<IndexQuad> quads;
  if (nx < 2 || ny < 2) return quads;
  quads.reserve(static_cast<std::size_t>(3 * (nx - 1) * (ny - 1)));
  for (std::int64_t j = 0; j + 1 < ny; ++j) {
    for (std::int64_t i = 0; i + 1 < nx; ++i) {
      // The cell's diagonal, between its two triangles.
      quads.push_back({id(i + 1, j), id(i, j), id(i + 1, j + 1), id(i, j + 1)});
      // The row edge (i, j)-(i+1, j), between this cell and the one below.
      if (j >= 1) quads.push_back({id(i + 1, j + 1), id(i, j), id(i + 1, j), id(i, j - 1)});
      // The column edge (i, j)-(i, j+1), between this cell and the one left.
      if (i >= 1) quads.push_back({id(i + 1, j + 1), id(i, j), id(i, j + 1), id(i - 1, j)});
    }
  }
  return quads;
}

// `bending: { k, kd, rest }`: a dihedral force on the sheet's hinges.
void read_bending(BuilderHost& host, const YAML::Node& g, const std::string& path, std::int64_t nx,
                  std::int64_t ny, Index base) {
  const YAML::Node b = g["bending"];
  if (!b.IsDefined() || b.IsNull()) return;
  const std::string bp = path + ".bending";
  if (!host.check_map(b, bp, "bending: { k: N m/rad, kd: N m s/rad }")) return;
  std::vector<IndexQuad> quads = hinge_quads(nx, ny, base);
  const bool create = !quads.empty();
  Params generated;
  generated.set("quads", std::move(quads));
  host.add_force("dihedral", b, bp, generated, Params{}, create);
}

}  // namespace

// `springs:` and `rods:` name the same families of pairs: each family a
// mapping of the `spring` plugin's parameters, or of the `distance`
// constraint's and its `compliance` (rods: inextensible links for XPBD or
// RATTLE instead of stiff springs).
void grid_links(BuilderHost& host, const YAML::Node& g, const std::string& path, const char* key,
                std::int64_t nx, std::int64_t ny, Index base) {
  const YAML::Node links = g[key];
  if (!links.IsDefined() || links.IsNull()) return;
  const bool rods = std::string(key) == "rods";
  const std::string sp = path + "." + key;
  if (!host.check_map(links, sp,
                      rods ? "rods: { structural: { compliance: m/N }, shear: {...}, bend: {...}, "
                             "bending: { compliance: rad/(N m) } }"
                           : "springs: { structural: { ks, kd }, shear: {...}, bend: {...} }")) {
    return;
  }
  std::vector<std::string> families = {"structural", "shear", "bend"};
  if (rods) families.push_back("bending");          // the hinges held by `bending` constraints
  (void)host.read_params(links, sp, {}, families);  // unknown families
  for (const std::string& family : families) {
    const YAML::Node s = links[family];
    if (!s.IsDefined() || s.IsNull()) continue;
    const std::string fp = sp + "." + family;
    if (!host.check_map(s, fp, rods ? "{ compliance: ... }" : "{ ks: N/m, kd: N s/m }")) continue;
    if (family == "bending") {
      std::vector<IndexQuad> quads = hinge_quads(nx, ny, base);
      const bool create = !quads.empty();
      Params generated;
      generated.set("quads", std::move(quads));
      host.add_constraint("bending", s, fp, generated, create);
      continue;
    }
    // 't'ructural, 'h'ear, 'e'nd: no string compare per particle. The keys
    // are checked even when the grid is too small for this family, so that
    // a typo is reported whatever the grid's size.
    std::vector<IndexPair> pairs = family_pairs(family[1], nx, ny, base);
    const bool create = !pairs.empty();
    Params generated;
    generated.set("pairs", std::move(pairs));
    if (rods) {
      host.add_constraint("distance", s, fp, generated, create);
    } else {
      host.add_force("spring", s, fp, generated, Params{}, create);
    }
  }
}

void read_grid(BuilderHost& host, const YAML::Node& g, const std::string& path) {
  if (!host.check_map(g, path, "grid: { origin, u, v, nx, ny, mass, ... }")) return;
  auto p = host.read_params(g, path, grid_specs(), {"springs", "rods", "bending"});
  if (!p) return;
  const std::int64_t nx = p->integer("nx"), ny = p->integer("ny");
  if (nx > kMaxParticles || ny > kMaxParticles ||
      static_cast<std::int64_t>(host.particle_count()) + nx * ny > kMaxParticles) {
    host.error(g, path,
               fmt::format("{}: {} x {} particles is too many (expected at most {} particles "
                           "in a scene)",
                           path, nx, ny, kMaxParticles));
    return;
  }
  const Index base = host.particle_count();
  auto id = [&](std::int64_t i, std::int64_t j) { return base + j * nx + i; };
  const Vec3 origin = p->vec3("origin"), u = p->vec3("u"), v = p->vec3("v");
  const Vec3 vel = p->vec3("velocity");
  const double mass = p->real("mass");
  std::vector<Index> members;
  // Reserved up front: at a million particles, growing these vectors (and
  // the spring lists below) by doubling costs more than filling them.
  members.reserve(static_cast<std::size_t>(nx * ny));
  host.reserve(nx * ny);
  for (std::int64_t j = 0; j < ny; ++j) {
    for (std::int64_t i = 0; i < nx; ++i) {
      host.add_particle(origin + static_cast<double>(i) * u + static_cast<double>(j) * v, vel, mass,
                        false);
      members.push_back(id(i, j));
    }
  }
  host.set_properties(base, nx * ny, particle_properties(*p));
  if (p->has("pin")) {
    const auto& pins = p->pairs("pin");
    for (std::size_t k = 0; k < pins.size(); ++k) {
      std::int64_t i = pins[k][0], j = pins[k][1];
      if (i < 0) i += nx;
      if (j < 0) j += ny;
      if (i < 0 || i >= nx || j < 0 || j >= ny) {
        host.error(g["pin"][k], fmt::format("{}.pin[{}]", path, k),
                   fmt::format("{}.pin[{}]: [{}, {}] is outside the {} x {} grid (expected i in "
                               "-{}..{}, j in -{}..{})",
                               path, k, pins[k][0], pins[k][1], nx, ny, nx, nx - 1, ny, ny - 1));
        continue;
      }
      host.set_fixed(id(i, j));
    }
  }
  if (p->has("name"))
    host.add_group(p->string("name"), std::move(members), g["name"], path + ".name");
  read_bending(host, g, path, nx, ny, base);
  grid_links(host, g, path, "springs", nx, ny, base);
  grid_links(host, g, path, "rods", nx, ny, base);
}

}  // namespace pdyn
