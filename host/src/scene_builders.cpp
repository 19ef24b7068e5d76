// Particle builders: chain, lattice, cloud, ring and polygon (docs/scenes.md
// lists every key). Each takes a contiguous block of ids starting at the
// number of particles declared before it, in the numbering its section of
// the docs gives, and queues its force objects through BuilderHost, so the
// springs are ordinary `spring`, `angle` and `area` plugin objects.
#include "scene_builders.hpp"

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>

#include "pdyn/text.hpp"

namespace pdyn {

namespace {

// Spring constants of builder springs whose mapping leaves ks or kd out.
// For two 0.01 kg particles ks = 100 N/m gives omega = sqrt(2 ks / m) = 141
// rad/s, so rk4 at dt = 1 ms (omega dt = 0.14, limit 2.8) is stable with a
// wide margin; kd = 0.1 N s/m damps that mode at 7% of critical
// (2 sqrt(ks m / 2) = 1.4 N s/m). Scenes that need a stiffer or softer
// material give ks and kd.
constexpr double kDefaultKs = 100.0;  // N/m
constexpr double kDefaultKd = 0.1;    // N s/m

Params spring_defaults() {
  Params d;
  d.set("ks", std::vector<double>{kDefaultKs});
  d.set("kd", std::vector<double>{kDefaultKd});
  return d;
}

ParamSpec count(std::string name, std::int64_t min, std::string doc) {
  ParamSpec s = param::required(std::move(name), ParamType::Integer, "", std::move(doc));
  s.at_least(static_cast<double>(min));
  return s;
}

ParamSpec mass_spec() {
  return param::required_real("mass", "kg", "mass of each particle").greater_than(0);
}
ParamSpec velocity_spec() {
  return param::vec3("velocity", Vec3::Zero(), "m/s", "initial velocity of every particle");
}
ParamSpec name_spec() { return param::optional("name", ParamType::String, "", "group name"); }
std::vector<ParamSpec> with_properties(std::vector<ParamSpec> specs) {
  for (auto& s : particle_property_specs()) specs.push_back(std::move(s));
  return specs;
}

// A key holding a mapping (a force family, a region): absent or null is
// "not given"; anything else must be a mapping.
enum class Family { Absent, Given, Bad };
Family family(BuilderHost& host, const YAML::Node& parent, const char* key, const std::string& path,
              const char* what) {
  const YAML::Node n = parent[key];
  if (!n.IsDefined() || n.IsNull()) return Family::Absent;
  return host.check_map(n, path + "." + key, what) ? Family::Given : Family::Bad;
}

// `pin:` in the builder's own numbering 0..count-1; negative counts from the
// end, so [0, -1] nails both ends of a chain.
void pin(BuilderHost& host, const Params& p, const YAML::Node& node, const std::string& path,
         Index base, std::int64_t count, const char* what) {
  if (!p.has("pin")) return;
  const auto& pins = p.indices("pin");
  for (std::size_t k = 0; k < pins.size(); ++k) {
    const Index i = pins[k] < 0 ? pins[k] + count : pins[k];
    if (i < 0 || i >= count) {
      host.error(
          node["pin"][k], fmt::format("{}.pin[{}]", path, k),
          fmt::format("{}.pin[{}]: {} is outside the {} of {} (expected "
                      "-{}..{})",
                      path, k, pins[k], what, count_of(count, "particle"), count, count - 1));
      continue;
    }
    host.set_fixed(base + i);
  }
}

void group(BuilderHost& host, const Params& p, const YAML::Node& node, const std::string& path,
           Index base, std::int64_t count) {
  if (!p.has("name")) return;
  std::vector<Index> members(static_cast<std::size_t>(count));
  for (std::int64_t i = 0; i < count; ++i) members[static_cast<std::size_t>(i)] = base + i;
  host.add_group(p.string("name"), std::move(members), node["name"], path + ".name");
}

Params with_pairs(std::vector<IndexPair> pairs) {
  Params g;
  g.set("pairs", std::move(pairs));
  return g;
}
Params with_triples(std::vector<IndexTriple> triples) {
  Params g;
  g.set("triples", std::move(triples));
  return g;
}

// ---------------------------------------------------------------------------
// chain: n particles evenly from `from` to `to`, id base + i. Springs join
// neighbours (i, i+1); `bend` adds angle springs on (i-1, i, i+1), which
// resist the chain folding at particle i (a rope's bending stiffness).

std::vector<ParamSpec> chain_specs() {
  return with_properties({
      param::required_vec3("from", "m", "position of the first particle"),
      param::required_vec3("to", "m", "position of the last particle"),
      count("n", 2, "number of particles"),
      mass_spec(),
      velocity_spec(),
      name_spec(),
      param::optional("pin", ParamType::IndexList, "",
                      "chain positions of nailed particles; negative counts from the end"),
  });
}

void read_chain(BuilderHost& host, const YAML::Node& c, const std::string& path) {
  if (!host.check_map(c, path, "chain: { from, to, n, mass, ... }")) return;
  auto p = host.read_params(c, path, chain_specs(), {"springs", "rods", "bend"});
  if (!p) return;
  const std::int64_t n = p->integer("n");
  const Vec3 from = p->vec3("from"), to = p->vec3("to");
  if (from == to) {
    host.error(c["to"], path + ".to",
               fmt::format("{}.to: is the same point as from (expected the other end of a chain "
                           "of nonzero length)",
                           path));
    return;
  }
  if (!host.can_add(n, c, path)) return;
  const Index base = host.particle_count();
  for (std::int64_t i = 0; i < n; ++i) {
    const double s = static_cast<double>(i) / static_cast<double>(n - 1);
    host.add_particle(from + s * (to - from), p->vec3("velocity"), p->real("mass"), false);
  }
  host.set_properties(base, n, particle_properties(*p));
  pin(host, *p, c, path, base, n, "chain");
  group(host, *p, c, path, base, n);

  // Rods (distance constraints) instead of springs when `rods` is given;
  // both only if both are.
  std::vector<IndexPair> links;
  for (std::int64_t i = 0; i + 1 < n; ++i) links.push_back({base + i, base + i + 1});
  const Family rods = family(host, c, "rods", path, "rods: { compliance: m/N }");
  if (rods == Family::Given) {
    host.add_constraint("distance", c["rods"], path + ".rods", with_pairs(links), true);
  }
  const Family springs = family(host, c, "springs", path, "springs: { ks: N/m, kd: N s/m }");
  if (springs == Family::Given || (springs == Family::Absent && rods == Family::Absent)) {
    host.add_force("spring", c["springs"], path + ".springs", with_pairs(std::move(links)),
                   spring_defaults(), true);
  }
  if (family(host, c, "bend", path, "bend: { k: N m/rad, kd: N m s/rad }") == Family::Given) {
    std::vector<IndexTriple> triples;
    for (std::int64_t i = 1; i + 1 < n; ++i)
      triples.push_back({base + i - 1, base + i, base + i + 1});
    const bool any = !triples.empty();
    host.add_force("angle", c["bend"], path + ".bend", with_triples(std::move(triples)), Params{},
                   any);
  }
}

// ---------------------------------------------------------------------------
// lattice: nx x ny x nz particles at origin + spacing (i, j, k), id
// base + (k ny + j) nx + i. Spring families: structural (axis neighbours),
// shear (both diagonals of every face square) and body (the four diagonals
// of every cube cell). Structural springs alone let a cell shear flat;
// face diagonals make every face rigid and with them the cube.

std::vector<ParamSpec> lattice_specs() {
  return with_properties({
      param::required_vec3("origin", "m", "position of particle (0, 0, 0)"),
      param::required("n", ParamType::Vector, "", "[nx, ny, nz] particles along x, y, z")
          .at_least(1),
      param::required_real("spacing", "m", "distance between neighbours").greater_than(0),
      mass_spec(),
      velocity_spec(),
      name_spec(),
      param::optional("pin", ParamType::IndexTriples, "",
                      "lattice coordinates [i, j, k] of nailed particles; negative counts from "
                      "the end"),
  });
}

// A lattice's size and where its particles start in the scene: particle
// (i, j, k) is id(i, j, k), x fastest.
struct LatticeIds {
  std::int64_t nx, ny, nz;
  Index base;
  Index id(std::int64_t i, std::int64_t j, std::int64_t k) const {
    return base + (k * ny + j) * nx + i;
  }
};

// One family of a lattice's springs: structural (along the axes), shear
// (face diagonals) or body (cube diagonals).
std::vector<IndexPair> lattice_pairs(const LatticeIds& L, const std::string& name) {
  std::vector<IndexPair> pairs;
  auto id = [&](std::int64_t i, std::int64_t j, std::int64_t k) { return L.id(i, j, k); };
  for (std::int64_t k = 0; k < L.nz; ++k)
    for (std::int64_t j = 0; j < L.ny; ++j)
      for (std::int64_t i = 0; i < L.nx; ++i) {
        const bool X = i + 1 < L.nx, Y = j + 1 < L.ny, Z = k + 1 < L.nz;
        if (name == "structural") {
          if (X) pairs.push_back({id(i, j, k), id(i + 1, j, k)});
          if (Y) pairs.push_back({id(i, j, k), id(i, j + 1, k)});
          if (Z) pairs.push_back({id(i, j, k), id(i, j, k + 1)});
        } else if (name == "shear") {
          if (X && Y) {
            pairs.push_back({id(i, j, k), id(i + 1, j + 1, k)});
            pairs.push_back({id(i + 1, j, k), id(i, j + 1, k)});
          }
          if (X && Z) {
            pairs.push_back({id(i, j, k), id(i + 1, j, k + 1)});
            pairs.push_back({id(i + 1, j, k), id(i, j, k + 1)});
          }
          if (Y && Z) {
            pairs.push_back({id(i, j, k), id(i, j + 1, k + 1)});
            pairs.push_back({id(i, j + 1, k), id(i, j, k + 1)});
          }
        } else if (X && Y && Z) {
          pairs.push_back({id(i, j, k), id(i + 1, j + 1, k + 1)});
          pairs.push_back({id(i + 1, j, k), id(i, j + 1, k + 1)});
          pairs.push_back({id(i, j + 1, k), id(i + 1, j, k + 1)});
          pairs.push_back({id(i + 1, j + 1, k), id(i, j, k + 1)});
        }
      }
  return pairs;
}

// `pin`: lattice coordinates of nailed particles, negative from the end.
void pin_lattice(BuilderHost& host, const YAML::Node& l, const std::string& path,
                 const std::vector<IndexTriple>& pins, const LatticeIds& L) {
  const std::int64_t dims[3] = {L.nx, L.ny, L.nz};
  for (std::size_t q = 0; q < pins.size(); ++q) {
    std::int64_t c[3];
    bool ok = true;
    for (int a = 0; a < 3; ++a) {
      c[a] = pins[q][a] < 0 ? pins[q][a] + dims[a] : pins[q][a];
      ok = ok && c[a] >= 0 && c[a] < dims[a];
    }
    if (!ok) {
      host.error(l["pin"][q], fmt::format("{}.pin[{}]", path, q),
                 fmt::format("{}.pin[{}]: [{}, {}, {}] is outside the {} x {} x {} lattice "
                             "(expected i in -{}..{}, j in -{}..{}, k in -{}..{})",
                             path, q, pins[q][0], pins[q][1], pins[q][2], L.nx, L.ny, L.nz, L.nx,
                             L.nx - 1, L.ny, L.ny - 1, L.nz, L.nz - 1));
      continue;
    }
    host.set_fixed(L.id(c[0], c[1], c[2]));
  }
}

// Rods (`distance` constraints, each with its `compliance`) of exactly the
// families `rods` lists: a lattice that XPBD or RATTLE keeps at its lengths.
// Structural rods alone leave a block free to shear; with shear or body
// rods there are more rods than the block's 3 N - 6 degrees of freedom, a
// redundant set that XPBD takes and RATTLE and Witkin's force refuse (their
// system is singular).
Family lattice_rods(BuilderHost& host, const YAML::Node& l, const std::string& path,
                    const LatticeIds& L) {
  const Family rods =
      family(host, l, "rods", path,
             "rods: { structural: { compliance: m/N }, shear: {...}, body: {...} }");
  if (rods != Family::Given) return rods;
  const std::string rp = path + ".rods";
  const YAML::Node rn = l["rods"];
  if (!host.read_params(rn, rp, {}, {"structural", "shear", "body"})) return Family::Bad;
  for (const char* f : {"structural", "shear", "body"}) {
    if (family(host, rn, f, rp, "{ compliance: m/N }") != Family::Given) continue;
    std::vector<IndexPair> pairs = lattice_pairs(L, f);
    const bool any = !pairs.empty();
    host.add_constraint("distance", rn[f], rp + "." + f, with_pairs(std::move(pairs)), any);
  }
  return rods;
}

// Without `springs` (and without `rods`), structural and shear springs with
// the defaults: a lattice that holds its shape. With it, exactly the
// families it lists.
void lattice_springs(BuilderHost& host, const YAML::Node& l, const std::string& path,
                     const LatticeIds& L, Family rods) {
  const Family springs =
      family(host, l, "springs", path, "springs: { structural: {...}, shear: {...}, body: {...} }");
  if (springs == Family::Bad) return;
  if (springs == Family::Absent && rods != Family::Absent) return;
  const std::string sp = path + ".springs";
  const YAML::Node sn = l["springs"];
  if (springs == Family::Given && !host.read_params(sn, sp, {}, {"structural", "shear", "body"})) {
    return;
  }
  for (const char* f : {"structural", "shear", "body"}) {
    const std::string name = f;
    YAML::Node node;  // undefined: the defaults
    if (springs == Family::Given) {
      const Family given = family(host, sn, f, sp, "{ ks: N/m, kd: N s/m }");
      if (given != Family::Given) continue;
      node.reset(sn[f]);
    } else if (name == "body") {
      continue;
    }
    std::vector<IndexPair> pairs = lattice_pairs(L, name);
    const bool any = !pairs.empty();
    host.add_force("spring", node, sp + "." + name, with_pairs(std::move(pairs)), spring_defaults(),
                   any);
  }
}

void read_lattice(BuilderHost& host, const YAML::Node& l, const std::string& path) {
  if (!host.check_map(l, path, "lattice: { origin, n: [nx, ny, nz], spacing, mass, ... }")) return;
  auto p = host.read_params(l, path, lattice_specs(), {"springs", "rods"});
  if (!p) return;
  const Vec3 nv = p->vec3("n");
  if (nv != nv.array().round().matrix()) {
    host.error(l["n"], path + ".n",
               fmt::format("{}.n: [{}, {}, {}] is not three whole numbers (expected [nx, ny, nz], "
                           "each a whole number >= 1)",
                           path, nv.x(), nv.y(), nv.z()));
    return;
  }
  // As a double first: the product of three mistyped sizes may not fit.
  const double total = nv.prod();
  if (!host.can_add(total > 1e15 ? std::int64_t{1} << 50 : static_cast<std::int64_t>(total), l,
                    path)) {
    return;
  }
  const LatticeIds L{static_cast<std::int64_t>(nv.x()), static_cast<std::int64_t>(nv.y()),
                     static_cast<std::int64_t>(nv.z()), host.particle_count()};
  const Vec3 origin = p->vec3("origin");
  const double h = p->real("spacing");
  for (std::int64_t k = 0; k < L.nz; ++k)
    for (std::int64_t j = 0; j < L.ny; ++j)
      for (std::int64_t i = 0; i < L.nx; ++i)
        host.add_particle(origin + h * Vec3(static_cast<double>(i), static_cast<double>(j),
                                            static_cast<double>(k)),
                          p->vec3("velocity"), p->real("mass"), false);
  if (p->has("pin")) pin_lattice(host, l, path, p->triples("pin"), L);
  const std::int64_t count = L.nx * L.ny * L.nz;
  host.set_properties(L.base, count, particle_properties(*p));
  group(host, *p, l, path, L.base, count);
  const Family rods = lattice_rods(host, l, path, L);
  lattice_springs(host, l, path, L, rods);
}

// ---------------------------------------------------------------------------
// cloud: n particles uniformly distributed in a box or a ball, reproducible
// from `seed` on every platform: std::mt19937_64 is fully specified by the
// standard, and the mapping to [0, 1) is our own (the top 53 bits, so every
// double is exact), because std::uniform_real_distribution is not the same
// across standard libraries. Per particle, x, y and z are drawn in that
// order; a ball is sampled by rejection from its bounding cube.

double uniform01(std::mt19937_64& g) { return static_cast<double>(g() >> 11) * 0x1.0p-53; }

std::vector<ParamSpec> cloud_specs() {
  ParamSpec seed = param::integer("seed", 0, "seed of the random generator (std::mt19937_64)");
  seed.at_least(0);
  return with_properties(
      {count("n", 1, "number of particles"), mass_spec(), velocity_spec(), seed, name_spec()});
}
std::vector<ParamSpec> cloud_box_specs() {
  return {param::required_vec3("min", "m", "corner with the smallest coordinates"),
          param::required_vec3("max", "m", "corner with the largest coordinates")};
}
std::vector<ParamSpec> cloud_sphere_specs() {
  return {param::required_vec3("center", "m", "centre of the ball"),
          param::required_real("radius", "m", "radius of the ball").greater_than(0)};
}

void read_cloud(BuilderHost& host, const YAML::Node& c, const std::string& path) {
  if (!host.check_map(c, path,
                      "cloud: { n, box: { min, max } or sphere: { center, radius }, "
                      "mass, seed }")) {
    return;
  }
  auto p = host.read_params(c, path, cloud_specs(), {"box", "sphere"});
  const Family box = family(host, c, "box", path, "box: { min: [x, y, z], max: [x, y, z] }");
  const Family ball = family(host, c, "sphere", path, "sphere: { center: [x, y, z], radius }");
  if (!p || box == Family::Bad || ball == Family::Bad) return;
  if ((box == Family::Given) == (ball == Family::Given)) {
    const bool both = box == Family::Given;
    host.error(both ? c["sphere"] : c, both ? path + ".sphere" : path,
               fmt::format("{}: {} (expected exactly one region: box: {{ min, max }} or sphere: "
                           "{{ center, radius }})",
                           both ? path + ".sphere" : path,
                           both ? "both 'box' and 'sphere' are given" : "no region is given"));
    return;
  }
  Vec3 lo, hi, center = Vec3::Zero();
  double radius = 0.0;
  if (box == Family::Given) {
    auto r = host.read_params(c["box"], path + ".box", cloud_box_specs(), {});
    if (!r) return;
    lo = r->vec3("min");
    hi = r->vec3("max");
    if ((hi.array() < lo.array()).any()) {
      host.error(c["box"]["max"], path + ".box.max",
                 fmt::format("{}.box.max: [{}, {}, {}] is below min [{}, {}, {}] in some "
                             "component (expected max >= min in every component)",
                             path, hi.x(), hi.y(), hi.z(), lo.x(), lo.y(), lo.z()));
      return;
    }
  } else {
    auto r = host.read_params(c["sphere"], path + ".sphere", cloud_sphere_specs(), {});
    if (!r) return;
    center = r->vec3("center");
    radius = r->real("radius");
  }
  const std::int64_t n = p->integer("n");
  if (!host.can_add(n, c, path)) return;
  const Index base = host.particle_count();
  std::mt19937_64 g(static_cast<std::uint64_t>(p->integer("seed")));
  for (std::int64_t i = 0; i < n; ++i) {
    Vec3 x;
    if (box == Family::Given) {
      for (int a = 0; a < 3; ++a) x[a] = lo[a] + uniform01(g) * (hi[a] - lo[a]);
    } else {
      Vec3 u;
      do {
        for (int a = 0; a < 3; ++a) u[a] = 2.0 * uniform01(g) - 1.0;
      } while (u.squaredNorm() > 1.0);
      x = center + radius * u;
    }
    host.add_particle(x, p->vec3("velocity"), p->real("mass"), false);
  }
  host.set_properties(base, n, particle_properties(*p));
  group(host, *p, c, path, base, n);
}

// ---------------------------------------------------------------------------
// ring and polygon: a closed loop of particles, id base + i around the loop.
// Springs join neighbours (i, i+1 mod n). `area` adds area springs on the
// fan of triangles (0, i, i+1), i = 1..n-2: their areas sum to the area the
// loop encloses (for any simple loop with particle 0 seeing every edge, e.g.
// a convex one), so holding each at its rest area holds the blob's area.
// Together with the n edge springs that is 2n - 2 constraints on the 2n - 3
// in-plane shape coordinates of a loop: it keeps its shape, not only its
// area, with no extra centre particle.

void loop_forces(BuilderHost& host, const YAML::Node& node, const std::string& path, Index base,
                 std::int64_t n) {
  const Family springs = family(host, node, "springs", path, "springs: { ks: N/m, kd: N s/m }");
  if (springs != Family::Bad) {
    std::vector<IndexPair> pairs;
    for (std::int64_t i = 0; i < n; ++i) pairs.push_back({base + i, base + (i + 1) % n});
    host.add_force("spring", node["springs"], path + ".springs", with_pairs(std::move(pairs)),
                   spring_defaults(), true);
  }
  if (family(host, node, "area", path, "area: { k: N/m^3, kd }") == Family::Given) {
    std::vector<IndexTriple> triples;
    for (std::int64_t i = 1; i + 1 < n; ++i) triples.push_back({base, base + i, base + i + 1});
    host.add_force("area", node["area"], path + ".area", with_triples(std::move(triples)), Params{},
                   true);
  }
}

std::vector<ParamSpec> loop_specs(std::vector<ParamSpec> specs) {
  specs.push_back(mass_spec());
  specs.push_back(velocity_spec());
  specs.push_back(name_spec());
  specs.push_back(param::optional("pin", ParamType::IndexList, "",
                                  "loop positions of nailed particles; negative counts from the "
                                  "end"));
  return with_properties(std::move(specs));
}

std::vector<ParamSpec> ring_specs() {
  return loop_specs(
      {param::required_vec3("center", "m", "centre of the ring"),
       param::required_real("radius", "m", "radius of the ring").greater_than(0),
       count("n", 3, "number of particles"),
       param::vec3("normal", Vec3::UnitZ(), "", "normal of the ring's plane").not_zero()});
}
std::vector<ParamSpec> polygon_specs() {
  return loop_specs({param::required("points", ParamType::VectorList, "m",
                                     "corners of the loop, in order (at least 3)")});
}

// A regular n-gon of circumradius R around `center` in the plane normal to
// `normal`: particle i at center + R (cos t_i a + sin t_i b), t_i = 2 pi i / n,
// counter-clockwise about the normal, with a the unit projection of x onto
// the plane (of y if the normal is within 25 degrees of x) and b = N x a.
void read_ring(BuilderHost& host, const YAML::Node& r, const std::string& path) {
  if (!host.check_map(r, path, "ring: { center, radius, n, mass, ... }")) return;
  auto p = host.read_params(r, path, ring_specs(), {"springs", "area"});
  if (!p) return;
  const std::int64_t n = p->integer("n");
  if (!host.can_add(n, r, path)) return;
  const Vec3 nn = p->vec3("normal").normalized();
  const Vec3 ref = std::abs(nn.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  const Vec3 a = (ref - ref.dot(nn) * nn).normalized(), b = nn.cross(a);
  const Index base = host.particle_count();
  for (std::int64_t i = 0; i < n; ++i) {
    const double t = 2.0 * std::numbers::pi * static_cast<double>(i) / static_cast<double>(n);
    host.add_particle(p->vec3("center") + p->real("radius") * (std::cos(t) * a + std::sin(t) * b),
                      p->vec3("velocity"), p->real("mass"), false);
  }
  host.set_properties(base, n, particle_properties(*p));
  pin(host, *p, r, path, base, n, "ring");
  group(host, *p, r, path, base, n);
  loop_forces(host, r, path, base, n);
}

// Any closed loop through the given points, in order.
void read_polygon(BuilderHost& host, const YAML::Node& g, const std::string& path) {
  if (!host.check_map(g, path, "polygon: { points: [[x, y, z], ...], mass, ... }")) return;
  auto p = host.read_params(g, path, polygon_specs(), {"springs", "area"});
  if (!p) return;
  const auto& pts = p->vec3s("points");
  const auto n = static_cast<std::int64_t>(pts.size());
  if (n < 3) {
    host.error(
        g["points"], path + ".points",
        fmt::format("{}.points: has {} points (expected at least 3 for a closed loop)", path, n));
    return;
  }
  for (std::int64_t i = 0; i < n; ++i) {
    if (pts[static_cast<std::size_t>(i)] == pts[static_cast<std::size_t>((i + 1) % n)]) {
      host.error(g["points"][i], fmt::format("{}.points[{}]", path, i),
                 fmt::format("{}.points[{}]: is the same point as points[{}] (expected "
                             "neighbouring corners apart)",
                             path, i, (i + 1) % n));
      return;
    }
  }
  if (!host.can_add(n, g, path)) return;
  const Index base = host.particle_count();
  for (const Vec3& x : pts) host.add_particle(x, p->vec3("velocity"), p->real("mass"), false);
  host.set_properties(base, n, particle_properties(*p));
  pin(host, *p, g, path, base, n, "polygon");
  group(host, *p, g, path, base, n);
  loop_forces(host, g, path, base, n);
}

}  // namespace

// One particle's keys are `radius` and `type`; a builder's, which set every
// particle it makes, `particle_radius` and `particle_type`.
std::vector<ParamSpec> particle_property_specs(const std::string& prefix) {
  const bool one = prefix.empty();
  return {
      param::optional(prefix + "radius", ParamType::Real, "m",
                      one ? "radius (what pair forces and pictures use); 0 if not given"
                          : "radius of each particle (what pair forces and pictures use)")
          .at_least(0),
      param::optional(prefix + "type", ParamType::Integer, "",
                      one ? "type, for forces that tell types apart; 0 if not given"
                          : "type of each particle, for forces that tell types apart")
          .at_least(0)
          .at_most(std::numeric_limits<std::int32_t>::max()),
  };
}

ParticleProperties particle_properties(const Params& p, const std::string& prefix) {
  ParticleProperties out;
  if (const std::string r = prefix + "radius"; p.has(r)) out.radius = p.real(r);
  if (const std::string t = prefix + "type"; p.has(t)) {
    out.type = static_cast<std::int32_t>(p.integer(t));
  }
  return out;
}

const std::vector<std::string>& builder_names() {
  static const std::vector<std::string> names = {"chain", "lattice", "cloud", "ring", "polygon"};
  return names;
}

std::vector<BuilderSpec> more_builder_specs() {
  const BuilderNested springs{
      "springs", "springs of the `spring` plugin between neighbours", "spring", "pairs", {}, {}};
  const BuilderNested loop_area{
      "area", "area springs of the `area` plugin on a fan of triangles", "area", "triples", {}, {}};
  return {
      {"chain",
       "a rope of n particles from `from` to `to`",
       chain_specs(),
       {springs,
        {"rods",
         "rods (distance constraints) between neighbours instead of springs: `distance` plugin "
         "parameters and `compliance`",
         "distance",
         "pairs",
         {},
         {},
         PluginKind::Constraint},
        {"bend",
         "angle springs of the `angle` plugin on consecutive triples",
         "angle",
         "triples",
         {},
         {}}}},
      {"lattice",
       "a 3-D block of nx x ny x nz particles (a jelly cube)",
       lattice_specs(),
       {{"springs",
         "spring families of the `spring` plugin",
         "spring",
         "pairs",
         {"structural", "shear", "body"},
         {}},
        {"rods",
         "rod families (distance constraints) instead of the default springs: `distance` plugin "
         "parameters and `compliance` per family",
         "distance",
         "pairs",
         {"structural", "shear", "body"},
         {},
         PluginKind::Constraint}}},
      {"cloud",
       "n particles uniform in a box or a ball, reproducible from `seed`",
       cloud_specs(),
       {{"box", "the region: an axis-aligned box", "", "", {}, cloud_box_specs()},
        {"sphere", "the region: a ball", "", "", {}, cloud_sphere_specs()}}},
      {"ring",
       "a closed loop of n particles on a circle (a 2-D soft blob)",
       ring_specs(),
       {springs, loop_area}},
      {"polygon",
       "a closed loop of particles through given points",
       polygon_specs(),
       {springs, loop_area}},
  };
}

void read_builder(BuilderHost& host, const std::string& name, const YAML::Node& node,
                  const std::string& path) {
  if (name == "chain")
    read_chain(host, node, path);
  else if (name == "lattice")
    read_lattice(host, node, path);
  else if (name == "cloud")
    read_cloud(host, node, path);
  else if (name == "ring")
    read_ring(host, node, path);
  else if (name == "polygon")
    read_polygon(host, node, path);
}

}  // namespace pdyn
