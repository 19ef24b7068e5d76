// on_circle: beads on a circular wire, Witkin's example of a constrained
// particle ("Constrained Dynamics", SIGGRAPH '97 course notes: the bead on
// a wire; Witkin, Gleicher & Welch 1990). The circle has centre c, unit
// normal n and radius R; P = I - n n^T projects into its plane. For
// particle i = ids[k], with y = P (x_i - c), rho = |y|, u = y / rho the unit
// radial and v = v_i, two rows:
//
//   in the plane:   C1 = n.(x_i - c)         J1 = n    b1 = 0     (m)
//   on the circle:  C2 = rho - R_k           J2 = u                (m)
//                   b2 = (|P v|^2 - (u.P v)^2) / rho               (m/s^2)
//   c_t = 0 for both (the wire does not move)
//
// Witkin's notes keep a bead in the plane z = 0 and write the circle as
// C = (|x|^2 - R^2)/2; here the wire may lie in any plane, so the circle is
// the plane row and a cylinder about the circle's axis, rho = R. J2 is
// d|P y|/dx = P^T P y / rho = P u = u (u lies in the plane). Along the
// motion, d/dt u = (I - u u^T) P v / rho, so Cddot2 = u.a + that . v, and
// since u.v = u.P v and P v . v = |P v|^2, the bias is b2 above: the
// centripetal term v_t^2 / rho of the velocity's part along the wire.
#include <fmt/format.h>

#include <cmath>
#include <pdyn/particle_constraint.hpp>
#include <pdyn/plugin.hpp>
#include <utility>
#include <vector>

namespace {

using pdyn::Index;
using pdyn::Vec3;

// Each bead's own circle: its centre c_k and radius R_k.
struct Circle {
  Vec3 center;    // m
  double radius;  // m
};

// One bead's two rows: row 0 keeps it in the plane, row 1 on the circle.
struct OnCircleLaw {
  static constexpr int rows = 2;
  using Site = Circle;
  Vec3 normal;  // unit

  void operator()(const pdyn::ParticlePoint& p, const Circle& circle,
                  pdyn::ParticleRows<2>& out) const {
    const Vec3 d = p.x - circle.center;
    const double h = normal.dot(d);
    out.value[0] = h;
    out.jacobian[0] = normal;
    const Vec3 y = d - h * normal;  // P (x - c)
    const double rho = y.norm();
    out.value[1] = rho - circle.radius;
    // On the axis the radial direction is undefined: the row is zero
    // (finite) there.
    const Vec3 u = rho == 0.0 ? Vec3::Zero() : Vec3(y / rho);
    const Vec3 pv = p.v - normal.dot(p.v) * normal;
    out.jacobian[1] = u;
    // |P v|^2 - (u.P v)^2 as the squared norm of P v's part along the
    // wire: the same number, never negative, without cancellation.
    out.bias[1] = rho == 0.0 ? 0.0 : (pv - u.dot(pv) * u).squaredNorm() / rho;
  }
};

using OnCircle = pdyn::ParticleConstraint<OnCircleLaw>;

// Each bead's circle centre. Given `center`, the beads share its circle and
// must start in its plane: a bead that starts off the plane would be jerked
// onto it. A rounding error of the scene's positions (1e-9 of the distance
// from the centre) is let through. Without `center`, the circles are
// coaxial about the axis through the origin along n, each in the plane of
// its bead's start (c_k = (n . x_k) n), so that C1 = 0 where it starts.
std::vector<Vec3> centers(const pdyn::Params& p, const std::vector<Index>& ids,
                          const pdyn::SceneContext& ctx, const Vec3& n) {
  std::vector<Vec3> c(ids.size());
  for (std::size_t e = 0; e < ids.size(); ++e) {
    const Vec3 x = ctx.particles.x.col(ids[e]);
    c[e] = p.has("center") ? p.vec3("center") : Vec3(n.dot(x) * n);
  }
  return c;
}

void require_in_plane(const std::vector<Index>& ids, const pdyn::SceneContext& ctx,
                      const std::vector<Vec3>& c, const Vec3& n) {
  for (std::size_t e = 0; e < ids.size(); ++e) {
    const Vec3 d = ctx.particles.x.col(ids[e]) - c[e];
    const double h = n.dot(d);
    if (!(std::abs(h) <= 1e-9 * d.norm())) {
      throw pdyn::ParamError("ids",
                             fmt::format("particle {} is not in the circle's plane: it is {} m "
                                         "from it (expected it on the wire: n.(x - center) = "
                                         "0, n the unit normal)",
                                         ids[e], std::abs(h)),
                             static_cast<long>(e));
    }
  }
}

// The radius: given (one for all), or each particle's initial distance from
// the circle's axis, so that C2 = 0 where it starts. A particle on the axis
// (after require_in_plane: at the centre) would give a circle of radius 0,
// on which the radial direction, and so J2, is undefined: refused.
std::vector<double> radii(const pdyn::Params& p, const pdyn::SceneContext& ctx,
                          const std::vector<Index>& ids, const std::vector<Vec3>& c,
                          const Vec3& n) {
  std::vector<double> r(ids.size());
  for (std::size_t e = 0; e < ids.size(); ++e) {
    if (p.has("radius")) {
      r[e] = p.real("radius");
      continue;
    }
    const Vec3 d = ctx.particles.x.col(ids[e]) - c[e];
    r[e] = (d - n.dot(d) * n).norm();
    if (r[e] == 0.0) {
      throw pdyn::ParamError("ids",
                             fmt::format("particle {} is at the circle's centre (expected "
                                         "it away from center: the radius is its initial "
                                         "distance from the centre)",
                                         ids[e]),
                             static_cast<long>(e));
    }
  }
  return r;
}

std::unique_ptr<pdyn::Constraint> create(const pdyn::Params& p, const pdyn::SceneContext& ctx) {
  const auto& ids = p.indices("ids");
  if (ids.empty()) throw pdyn::ParamError("ids", "is empty (expected at least one particle)");
  // A particle listed twice has two pairs of equal rows: J W J^T is singular.
  pdyn::require_distinct_ids(p, "ids", "is threaded on the wire twice");
  const Vec3 n = p.vec3("normal").normalized();  // not zero: the loader checks
  const auto c = centers(p, ids, ctx, n);
  require_in_plane(ids, ctx, c, n);
  auto r = radii(p, ctx, ids, c, n);
  std::vector<Circle> circles(ids.size());
  for (std::size_t k = 0; k < ids.size(); ++k) circles[k] = Circle{c[k], r[k]};
  return std::make_unique<OnCircle>(ids, std::move(circles), OnCircleLaw{n});
}

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Constraint;
  d.name = "on_circle";
  d.version = "1.0.0";
  d.description =
      "beads on a circular wire: C1 = n.(x_i - c) (in the plane), C2 = |P (x_i - c)| - R, "
      "P = I - n n^T";
  d.params = {
      pdyn::param::required("ids", pdyn::ParamType::IndexList, "", "the beads on the wire"),
      pdyn::param::optional("center", pdyn::ParamType::Vector, "m",
                            "the circle's centre c; default: each bead's circle is about the "
                            "axis through the origin along n, in the plane of its start"),
      pdyn::param::vec3("normal", Vec3(0, 0, 1), "",
                        "the normal n of the circle's plane (normalised)")
          .not_zero(),
      pdyn::param::optional("radius", pdyn::ParamType::Real, "m",
                            "radius R; default: each particle's initial distance from the "
                            "circle's axis")
          .greater_than(0),
  };
  d.create_constraint = create;
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
