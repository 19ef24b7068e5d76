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

#include <pdyn/plugin.hpp>
#include <unordered_set>
#include <utility>
#include <vector>

namespace {

using pdyn::Index;
using pdyn::Vec3;

class OnSphere final : public pdyn::Constraint {
 public:
  OnSphere(std::vector<Index> ids, Vec3 center, std::vector<double> radii)
      : ids_(std::move(ids)), center_(center), radii_(std::move(radii)) {}

  pdyn::ConstraintPattern pattern() const override {
    pdyn::ConstraintPattern p;
    for (const Index i : ids_) p.add_row({i});
    return p;
  }

  void evaluate(const pdyn::ParticleView& p, pdyn::ConstraintValues& out) const override {
    for (std::size_t k = 0; k < ids_.size(); ++k) {
      const Index row = static_cast<Index>(k);
      const Vec3 d = p.x.col(ids_[k]) - center_;
      const double r = d.norm();
      out.value[row] = r - radii_[k];
      out.rate[row] = 0.0;
      // At the centre the radial direction is undefined: the row is zero
      // (finite) there.
      const Vec3 u = r == 0.0 ? Vec3::Zero() : Vec3(d / r);
      const Vec3 v = p.v.col(ids_[k]);
      out.jacobian.col(row) = u;
      // |v|^2 - (u.v)^2 as the squared norm of v's tangential part: the
      // same number, never negative, without cancellation.
      out.bias[row] = r == 0.0 ? 0.0 : (v - u.dot(v) * u).squaredNorm() / r;
    }
  }

 private:
  std::vector<Index> ids_;
  Vec3 center_;                // m
  std::vector<double> radii_;  // R_k, m
};

// A particle listed twice has two equal rows: J W J^T is singular.
void require_distinct_ids(const std::vector<Index>& ids) {
  std::unordered_set<Index> seen;
  for (std::size_t e = 0; e < ids.size(); ++e) {
    if (!seen.insert(ids[e]).second) {
      throw pdyn::ParamError(
          "ids", fmt::format("particle {} is listed twice (expected each id once)", ids[e]),
          static_cast<long>(e));
    }
  }
}

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
  require_distinct_ids(ids);
  const Vec3 c = p.vec3("center");
  auto r = radii(p, ctx, ids, c);
  return std::make_unique<OnSphere>(ids, c, std::move(r));
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
