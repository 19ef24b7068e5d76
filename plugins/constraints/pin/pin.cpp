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

#include <pdyn/plugin.hpp>
#include <unordered_set>
#include <utility>
#include <vector>

namespace {

using pdyn::Index;
using pdyn::Vec3;

class Pin final : public pdyn::Constraint {
 public:
  Pin(std::vector<Index> ids, std::vector<Vec3> points, Vec3 velocity, double t0)
      : ids_(std::move(ids)), points_(std::move(points)), velocity_(velocity), t0_(t0) {}

  pdyn::ConstraintPattern pattern() const override {
    pdyn::ConstraintPattern p;
    for (const Index i : ids_) {
      for (int c = 0; c < 3; ++c) p.add_row({i});
    }
    return p;
  }

  void evaluate(const pdyn::ParticleView& p, pdyn::ConstraintValues& out) const override {
    const Vec3 moved = velocity_ * (p.t - t0_);
    for (std::size_t k = 0; k < ids_.size(); ++k) {
      const Vec3 c = p.x.col(ids_[k]) - (points_[k] + moved);
      for (int axis = 0; axis < 3; ++axis) {
        const Index row = 3 * static_cast<Index>(k) + axis;
        out.value[row] = c[axis];
        out.rate[row] = -velocity_[axis];
        out.bias[row] = 0.0;
        out.jacobian.col(row) = Vec3::Unit(axis);
      }
    }
  }

 private:
  std::vector<Index> ids_;
  std::vector<Vec3> points_;  // p_k at t0, m
  Vec3 velocity_;             // u, m/s
  double t0_;                 // s
};

// Two pins of one particle give six rows for its three coordinates: J W J^T
// is singular. Each particle once.
void require_distinct_ids(const std::vector<Index>& ids) {
  std::unordered_set<Index> seen;
  for (std::size_t e = 0; e < ids.size(); ++e) {
    if (!seen.insert(ids[e]).second) {
      throw pdyn::ParamError(
          "ids", fmt::format("particle {} is pinned twice (expected each id once)", ids[e]),
          static_cast<long>(e));
    }
  }
}

// The points at t0: given (one for all, or one per id), or where the
// particles are when the pin is made, so that C = 0 there. t0 is the time
// of the state the pin is made at: 0 for a scene, the current time for a
// constraint added to a running system, where a pin given no points then
// holds each particle where it is.
std::unique_ptr<pdyn::Constraint> create(const pdyn::Params& p, const pdyn::SceneContext& ctx) {
  const auto& ids = p.indices("ids");
  if (ids.empty()) throw pdyn::ParamError("ids", "is empty (expected at least one particle)");
  require_distinct_ids(ids);
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
  return std::make_unique<Pin>(ids, std::move(points), p.vec3("velocity"), ctx.particles.t);
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
