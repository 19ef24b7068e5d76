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
// The bias, from differentiating C twice along the motion (Witkin's
// Cddot = J a + Jdot v; pdyn/constraint.hpp gives it in full):
//   Cdot  = J v + c_t = v_z - (x v_x + y v_y) / R
//   Cddot = a_z - (x a_x + y a_y) / R - (v_x^2 + v_y^2) / R
//         = J a + Jdot v,   Jdot v = v^T (d2C/dx2) v = -(v_x^2 + v_y^2) / R,
// so b = -(v_x^2 + v_y^2) / R: the horizontal speed bending into the bowl's
// curvature. Jdot here is J's change along the motion at fixed t. A
// constraint whose J does not depend on x (a plane) has b = 0; one that
// moves with time adds 2 (dJ/dt) v + d2C/dt2, dJ/dt and d2C/dt2 taken at
// fixed x. `pdyn check` compares C's derivatives with each of J, c_t and b.
//
// Every row here holds one particle, so the plugin is a law on
// pdyn::ParticleConstraint (pdyn/particle_constraint.hpp), which makes the
// pattern and puts each row's numbers where the kernel reads them. A row
// over two or more particles (a bead kept between two others, a rod) does
// not fit it: derive from pdyn::Constraint and write row r's j-th particle's
// gradient to out.jacobian.col(pattern.row_begin[r] + j), which is column r
// only when every row before it has one particle (pdyn/constraint.hpp;
// plugins/constraints/distance writes a rod's two at 2 r and 2 r + 1).
//
// Physics to test against: on a horizontal circle in the bowl, gravity and
// the normal force give v^2 / r = g r / R, so every circular orbit has the
// same angular speed sqrt(g / R) whatever its radius (test_@NAME@.cpp).
#include <pdyn/particle_constraint.hpp>
#include <pdyn/plugin.hpp>
#include <utility>
#include <vector>

namespace {

// One particle's row, at its position x, velocity v and the time t. Its
// site is what it keeps of its own: here the height h_k of its bowl's
// bottom. Writes C and J always (they start as NaN: a row left unwritten
// fails `pdyn check`), c_t and b where they are not 0. Finite everywhere
// (R > 0): no special case for the axis, coincident or far particles. A
// geometry that divides by a distance (1 / |x - c|, 1 / rho) must give a
// finite row where that distance is 0, or refuse the particle in the
// factory; `pdyn check` puts particles there.
struct BowlLaw {
  static constexpr int rows = 1;
  using Site = double;  // h_k, m
  double r;             // R, m

  void operator()(const pdyn::ParticlePoint& p, const double& bottom,
                  pdyn::ParticleRows<1>& out) const {
    const double x = p.x.x(), y = p.x.y(), z = p.x.z();
    const double vx = p.v.x(), vy = p.v.y();
    out.value[0] = z - bottom - (x * x + y * y) / (2.0 * r);
    out.jacobian[0] = pdyn::Vec3(-x / r, -y / r, 1.0);
    out.rate[0] = 0.0;
    out.bias[0] = -(vx * vx + vy * vy) / r;
  }
};

using Bowl = pdyn::ParticleConstraint<BowlLaw>;

// The loader has checked every declared bound (R > 0, ids within 0..N-1);
// the factory checks what the descriptor cannot say: at least one particle,
// each once (a particle listed twice has two equal rows, and the kernel's
// system J W J^T lambda = ... is then singular). Without `bottom`, each
// particle's bowl is the one through where it starts, so that C = 0 at the
// start: a constraint violated at t = 0 would be pulled back by the
// feedback terms (or not at all), not held. `pdyn check`
// (constraint.satisfied_at_creation) makes it with only the required keys
// and asserts C = 0 there: a geometry that fixes where a particle must be
// (a radius of a helix, a centre) needs no default but the initial
// positions. `radius` may have one because `bottom` absorbs it.
std::unique_ptr<pdyn::Constraint> create(const pdyn::Params& p, const pdyn::SceneContext& ctx) {
  const auto& ids = p.indices("ids");
  if (ids.empty()) throw pdyn::ParamError("ids", "is empty (expected at least one particle)");
  pdyn::require_distinct_ids(p, "ids");
  const double r = p.real("radius");
  std::vector<double> bottoms(ids.size());
  for (std::size_t k = 0; k < ids.size(); ++k) {
    const pdyn::Vec3 x = ctx.particles.x.col(ids[k]);
    bottoms[k] =
        p.has("bottom") ? p.real("bottom") : x.z() - (x.x() * x.x() + x.y() * x.y()) / (2.0 * r);
  }
  return std::make_unique<Bowl>(ids, std::move(bottoms), BowlLaw{r});
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
