// on_plane: particles kept on a plane, one row per particle (Witkin,
// "Constrained Dynamics", SIGGRAPH '97 course notes; Witkin, Gleicher &
// Welch 1990). With n the unit normal and d_k the plane's offset for
// particle i = ids[k] (the plane is n.x = d_k):
//
//   C   = n.x_i - d_k          (m: the signed distance from the plane)
//   J   = n                    (dimensionless)
//   b   = 0                    (J is constant)
//   c_t = 0                    (the plane does not move)
//
// A particle on a plane slides freely within it: unlike a collider's floor,
// which only pushes, the constraint also pulls a particle that would leave
// the plane on the other side.
#include <pdyn/particle_constraint.hpp>
#include <pdyn/plugin.hpp>
#include <utility>
#include <vector>

namespace {

using pdyn::Vec3;

// One particle's row; its site is its plane's offset d_k, m.
struct OnPlaneLaw {
  static constexpr int rows = 1;
  using Site = double;
  Vec3 normal;  // unit

  void operator()(const pdyn::ParticlePoint& p, const double& offset,
                  pdyn::ParticleRows<1>& out) const {
    out.value[0] = normal.dot(p.x) - offset;
    out.jacobian[0] = normal;
  }
};

using OnPlane = pdyn::ParticleConstraint<OnPlaneLaw>;

// The offset: given (one plane for all), or each particle's own n.x at the
// start, so that every particle stays on the plane through where it starts
// and C = 0 there.
std::unique_ptr<pdyn::Constraint> create(const pdyn::Params& p, const pdyn::SceneContext& ctx) {
  const auto& ids = p.indices("ids");
  if (ids.empty()) throw pdyn::ParamError("ids", "is empty (expected at least one particle)");
  // A particle listed twice has two equal rows: J W J^T is singular.
  pdyn::require_distinct_ids(p, "ids");
  const Vec3 n = p.vec3("normal").normalized();  // not zero: the loader checks
  std::vector<double> offsets(ids.size());
  for (std::size_t k = 0; k < ids.size(); ++k) {
    offsets[k] = p.has("offset") ? p.real("offset") : n.dot(ctx.particles.x.col(ids[k]));
  }
  return std::make_unique<OnPlane>(ids, std::move(offsets), OnPlaneLaw{n});
}

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Constraint;
  d.name = "on_plane";
  d.version = "1.0.0";
  d.description = "particles kept on a plane: C = n.x_i - d, n the unit normal";
  d.params = {
      pdyn::param::required("ids", pdyn::ParamType::IndexList, "", "the particles on the plane"),
      pdyn::param::required_vec3("normal", "", "the plane's normal (normalised)").not_zero(),
      pdyn::param::optional("offset", pdyn::ParamType::Real, "m",
                            "the plane n.x = offset, n the unit normal; default: each particle's "
                            "plane through its initial position"),
  };
  d.create_constraint = create;
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
