// @NAME@: particles kept on a paraboloid bowl with a vertical axis through
// the origin, one scalar row per particle (Witkin, "Constrained Dynamics",
// SIGGRAPH '97 course notes). The bowl of particle i = ids[k] is
// z = h_k + (x^2 + y^2) / (2 R): R is its radius of curvature at the
// bottom, h_k the height of its bottom.
//
// A constraint only describes C; the kernel turns it into a force
// (docs/constraints.md). It needs, per row, at a state (x, v, t):
//
//   C   = z - h_k - (x^2 + y^2) / (2 R)       (m: 0 on the bowl)
//   J   = dC/dx = (-x / R, -y / R, 1)         (dimensionless)
//   c_t = dC/dt at fixed x = 0                (the bowl does not move)
//   b   = Cddot - J a                         (m/s^2)
//
// The bias, from differentiating C twice along the motion:
//   Cdot  = J v + c_t = v_z - (x v_x + y v_y) / R
//   Cddot = a_z - (x a_x + y a_y) / R - (v_x^2 + v_y^2) / R
//         = J a + Jdot v,   Jdot v = -(v_x^2 + v_y^2) / R,
// so b = -(v_x^2 + v_y^2) / R: the horizontal speed bending into the bowl's
// curvature. (A constraint whose J does not depend on x, a plane, has b = 0;
// one that moves with time adds 2 (dJ/dt) v + d2C/dt2.) `pdyn check`
// compares C's derivatives with each of J, c_t and b.
//
// Physics to test against: on a horizontal circle in the bowl, gravity and
// the normal force give v^2 / r = g r / R, so every circular orbit has the
// same angular speed sqrt(g / R) whatever its radius (test_@NAME@.cpp).
#include <fmt/format.h>

#include <pdyn/plugin.hpp>
#include <unordered_set>
#include <utility>
#include <vector>

namespace {

using pdyn::Index;

class Bowl final : public pdyn::Constraint {
 public:
  Bowl(std::vector<Index> ids, double radius, std::vector<double> bottoms)
      : ids_(std::move(ids)), r_(radius), h_(std::move(bottoms)) {}

  // One row per particle, each involving that particle only. Fixed for the
  // object's lifetime: the kernel sizes its matrices from it once.
  pdyn::ConstraintPattern pattern() const override {
    pdyn::ConstraintPattern p;
    for (const Index i : ids_) p.add_row({i});
    return p;
  }

  // Writes every member for every row: the kernel does not clear value and
  // jacobian between calls. Finite everywhere (R > 0), so no special case
  // for coincident or far particles.
  void evaluate(const pdyn::ParticleView& p, pdyn::ConstraintValues& out) const override {
    for (std::size_t k = 0; k < ids_.size(); ++k) {
      const Index row = static_cast<Index>(k);
      const double x = p.x(0, ids_[k]), y = p.x(1, ids_[k]), z = p.x(2, ids_[k]);
      const double vx = p.v(0, ids_[k]), vy = p.v(1, ids_[k]);
      out.value[row] = z - h_[k] - (x * x + y * y) / (2.0 * r_);
      out.jacobian.col(row) = pdyn::Vec3(-x / r_, -y / r_, 1.0);
      out.rate[row] = 0.0;
      out.bias[row] = -(vx * vx + vy * vy) / r_;
    }
  }

 private:
  std::vector<Index> ids_;
  double r_;               // R, m
  std::vector<double> h_;  // h_k, m
};

// A particle listed twice has two equal rows, and the kernel's system
// J W J^T lambda = ... is then singular: each particle once.
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

// The loader has checked every declared bound (R > 0, ids within 0..N-1);
// the factory checks what the descriptor cannot say. Without `bottom`, each
// particle's bowl is the one through where it starts, so that C = 0 at the
// start: a constraint violated at t = 0 would be pulled back by the
// feedback terms (or not at all), not held.
std::unique_ptr<pdyn::Constraint> create(const pdyn::Params& p, const pdyn::SceneContext& ctx) {
  const auto& ids = p.indices("ids");
  if (ids.empty()) throw pdyn::ParamError("ids", "is empty (expected at least one particle)");
  require_distinct_ids(ids);
  const double r = p.real("radius");
  std::vector<double> bottoms(ids.size());
  for (std::size_t k = 0; k < ids.size(); ++k) {
    const pdyn::Vec3 x = ctx.particles.x.col(ids[k]);
    bottoms[k] =
        p.has("bottom") ? p.real("bottom") : x.z() - (x.x() * x.x() + x.y() * x.y()) / (2.0 * r);
  }
  return std::make_unique<Bowl>(ids, r, std::move(bottoms));
}

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Constraint;
  d.name = "@NAME@";
  d.version = "0.1.0";
  d.description = "particles kept on a paraboloid bowl: C = z - h - (x^2 + y^2) / (2 R)";
  d.params = {
      pdyn::param::required("ids", pdyn::ParamType::IndexList, "", "the particles in the bowl"),
      pdyn::param::real("radius", 1.0, "m", "the bowl's radius of curvature R at its bottom")
          .greater_than(0),
      pdyn::param::optional("bottom", pdyn::ParamType::Real, "m",
                            "height h of the bowl's bottom; default: each particle's bowl "
                            "through its initial position"),
  };
  d.create_constraint = create;
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
