// pin: particles held at points, which may move at a constant velocity
// (Witkin, "Constrained Dynamics", SIGGRAPH '97 course notes; Witkin,
// Gleicher & Welch 1990): a point-to-point constraint whose point is driven
// along a straight line, the simplest constraint that moves with time. For
// particle i = ids[k], its point p_k and the points' velocity u, three rows,
// one per axis c = x, y, z:
//
//   p_k(t) = p_k + u (t - t0)                       (t0: when the pin was made)
//   C_c    = x_i,c - p_k,c(t)                       (m)
//   J_c    = e_c  (the unit vector of axis c)       (dimensionless)
//   c_t,c  = dC_c/dt at fixed x = -u_c              (m/s)
//   b_c    = Jdot v + 2 (dJ/dt) v + d2C/dt2 = 0     (J is constant, p(t) linear)
//
// A pin is a hard `anchor`: the particle is not pulled towards the point
// but held there, by a constraint force the kernel solves for. A particle
// held still for ever may as well be nailed (`fixed: true`), which takes it
// out of the dynamics altogether; a pin can move.
#include <fmt/format.h>

#include <pdyn/particle_constraint.hpp>
#include <pdyn/plugin.hpp>
#include <utility>
#include <vector>

namespace {

using pdyn::Vec3;

// One particle's three rows; its site is its point p_k at t0, m.
struct PinLaw {
  static constexpr int rows = 3;
  using Site = Vec3;
  Vec3 velocity;  // u, m/s
  double t0;      // s

  void operator()(const pdyn::ParticlePoint& p, const Vec3& point,
                  pdyn::ParticleRows<3>& out) const {
    const Vec3 moved = velocity * (p.t - t0);
    const Vec3 c = p.x - (point + moved);
    for (int axis = 0; axis < 3; ++axis) {
      out.value[axis] = c[axis];
      out.rate[axis] = -velocity[axis];
      out.jacobian[axis] = Vec3::Unit(axis);
    }
  }
};

using Pin = pdyn::ParticleConstraint<PinLaw>;

// The points at t0: given (one for all, or one per id), or where the
// particles are when the pin is made, so that C = 0 there. t0 is the time
// of the state the pin is made at: 0 for a scene, the current time for a
// constraint added to a running system, where a pin given no points then
// holds each particle where it is.
std::unique_ptr<pdyn::Constraint> create(const pdyn::Params& p, const pdyn::SceneContext& ctx) {
  const auto& ids = p.indices("ids");
  if (ids.empty()) throw pdyn::ParamError("ids", "is empty (expected at least one particle)");
  // Two pins of one particle give six rows for its three coordinates: J W J^T
  // is singular. Each particle once.
  pdyn::require_distinct_ids(p, "ids", "is pinned twice");
  std::vector<Vec3> points(ids.size());
  if (p.has("points")) {
    const auto& given = p.vec3s("points");
    if (given.size() != 1 && given.size() != ids.size()) {
      throw pdyn::ParamError(
          "points", fmt::format("has {} points for {} ids (expected 1 point for all, or {})",
                                given.size(), ids.size(), ids.size()));
    }
    for (std::size_t k = 0; k < ids.size(); ++k) points[k] = given[given.size() == 1 ? 0 : k];
  } else {
    for (std::size_t k = 0; k < ids.size(); ++k) points[k] = ctx.particles.x.col(ids[k]);
  }
  return std::make_unique<Pin>(ids, std::move(points), PinLaw{p.vec3("velocity"), ctx.particles.t});
}

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Constraint;
  d.name = "pin";
  d.version = "1.0.0";
  d.description =
      "particles held at points moving at a constant velocity: C = x_i - (p + u (t - t0))";
  d.params = {
      pdyn::param::required("ids", pdyn::ParamType::IndexList, "", "the pinned particles"),
      pdyn::param::optional("points", pdyn::ParamType::VectorList, "m",
                            "the points at the start: one per id, or one for all; default: the "
                            "particles' initial positions"),
      pdyn::param::vec3("velocity", Vec3::Zero(), "m/s", "velocity u of every point"),
  };
  d.create_constraint = create;
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
