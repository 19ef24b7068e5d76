// on_sphere: particles kept on a sphere, one row per particle (Witkin,
// "Constrained Dynamics", SIGGRAPH '97 course notes; Witkin, Gleicher &
// Welch 1990). The sphere has centre c and radius R_k for particle
// i = ids[k]; with d = x_i - c, r = |d|, u = d / r and v = v_i:
//
//   C   = r - R_k                          (m)
//   J   = u                                (dimensionless)
//   b   = (|v|^2 - (u.v)^2) / r            (m/s^2: the centripetal term v_t^2 / r)
//   c_t = 0                                (the sphere does not move)
//
// Witkin writes the circle of his bead as C = (|x|^2 - R^2)/2; C = |d| - R
// is the same surface, measured in metres, so that a run's drift and the
// feedback ks C act in the sphere's own unit. With R = |d| the particle is
// a spherical pendulum of length R about c.
#include <fmt/format.h>

#include <pdyn/particle_constraint.hpp>
#include <pdyn/plugin.hpp>
#include <utility>
#include <vector>

namespace {

using pdyn::Index;
using pdyn::Vec3;

// One particle's row; its site is its sphere's radius R_k, m.
struct OnSphereLaw {
  static constexpr int rows = 1;
  using Site = double;
  Vec3 center;  // m

  void operator()(const pdyn::ParticlePoint& p, const double& radius,
                  pdyn::ParticleRows<1>& out) const {
    const Vec3 d = p.x - center;
    const double r = d.norm();
    out.value[0] = r - radius;
    // At the centre the radial direction is undefined: the row is zero
    // (finite) there.
    const Vec3 u = r == 0.0 ? Vec3::Zero() : Vec3(d / r);
    out.jacobian[0] = u;
    // |v|^2 - (u.v)^2 as the squared norm of v's tangential part: the
    // same number, never negative, without cancellation.
    out.bias[0] = r == 0.0 ? 0.0 : (p.v - u.dot(p.v) * u).squaredNorm() / r;
  }
};

using OnSphere = pdyn::ParticleConstraint<OnSphereLaw>;

// The radius: given (one for all), or each particle's initial distance from
// the centre, so that C = 0 where it starts. A particle at the centre would
// give a sphere of radius 0, on which J is undefined: refused.
std::vector<double> radii(const pdyn::Params& p, const pdyn::SceneContext& ctx,
                          const std::vector<Index>& ids, const Vec3& c) {
  std::vector<double> r(ids.size());
  for (std::size_t e = 0; e < ids.size(); ++e) {
    if (p.has("radius")) {
      r[e] = p.real("radius");
      continue;
    }
    r[e] = (ctx.particles.x.col(ids[e]) - c).norm();
    if (r[e] == 0.0) {
      throw pdyn::ParamError("ids",
                             fmt::format("particle {} is at the sphere's centre (expected it "
                                         "away from center: the radius is its initial distance "
                                         "from the centre)",
                                         ids[e]),
                             static_cast<long>(e));
    }
  }
  return r;
}

std::unique_ptr<pdyn::Constraint> create(const pdyn::Params& p, const pdyn::SceneContext& ctx) {
  const auto& ids = p.indices("ids");
  if (ids.empty()) throw pdyn::ParamError("ids", "is empty (expected at least one particle)");
  // A particle listed twice has two equal rows: J W J^T is singular.
  pdyn::require_distinct_ids(p, "ids");
  const Vec3 c = p.vec3("center");
  auto r = radii(p, ctx, ids, c);
  return std::make_unique<OnSphere>(ids, std::move(r), OnSphereLaw{c});
}

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Constraint;
  d.name = "on_sphere";
  d.version = "1.0.0";
  d.description = "particles kept on a sphere: C = |x_i - c| - R";
  d.params = {
      pdyn::param::required("ids", pdyn::ParamType::IndexList, "", "the particles on the sphere"),
      pdyn::param::vec3("center", Vec3::Zero(), "m", "the sphere's centre c"),
      pdyn::param::optional("radius", pdyn::ParamType::Real, "m",
                            "radius R; default: each particle's initial distance from center")
          .greater_than(0),
  };
  d.create_constraint = create;
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
