// angle: a damped bending spring on the angle at the middle particle of each
// triple [i, j, k], the rope's bending stiffness. With a = x_i - x_j,
// b = x_k - x_j:
//
//   theta = atan2(|a x b|, a . b)                     in [0, pi]
//   U     = k/2 (theta - theta0)^2
//   f     = -[k (theta - theta0) + kd dtheta/dt] grad theta,
//   dtheta/dt = grad theta . v
//
// atan2 rather than acos(a.b / |a||b|): acos loses all precision near 0 and
// pi, where its derivative -1/sqrt(1 - c^2) blows up, while atan2 of the two
// well-conditioned quantities |a x b| and a.b is accurate everywhere.
// Differentiating theta = atan2(s, d), s = |a x b|, d = a.b, n = (a x b)/s:
//
//   dtheta/da = (d (b x n) - s b) / (|a|^2 |b|^2)
//   dtheta/db = (d (n x a) - s a) / (|a|^2 |b|^2)
//   dtheta/dx_i = dtheta/da,  dtheta/dx_k = dtheta/db,
//   dtheta/dx_j = -(dtheta/da + dtheta/db)
//
// |grad theta| is 1/|a| (resp. 1/|b|) at any angle, but its direction is
// undefined when the particles are collinear (s = 0, the tip of a cone in
// theta) or coincide: there the triple adds nothing. For a straight rope
// (theta0 = pi) that is the continuous limit, since theta - theta0 -> 0.
//
// theta is invariant under rigid motions, so grad theta sums to zero and has
// zero moment: the force is internal. The damping term is the bending
// analogue of Witkin's spring damping (SIGGRAPH '97 notes, "Damped Spring"):
// it resists only the rate of bending, f . v = -kd (dtheta/dt)^2 <= 0.
//
// The loop, the per-type coefficients, the threads and the Jacobians are
// pdyn/bonded.hpp's (Harmonic<Bend>): this file gives theta and its
// gradient, written once for any scalar type so that the SDK differentiates
// the gradient exactly for implicit solvers.
#include <cmath>
#include <numbers>
#include <pdyn/bonded.hpp>
#include <pdyn/plugin.hpp>

namespace {

using pdyn::Coordinate;
using pdyn::Vector3;

// theta at the middle particle of [i, j, k] and its gradient.
struct Bend {
  static constexpr int arity = 3;

  template <class T>
  Coordinate<3, T> operator()(const std::array<Vector3<T>, 3>& x) const {
    using std::atan2;
    Coordinate<3, T> q;
    const Vector3<T> a = x[0] - x[1], b = x[2] - x[1];
    const Vector3<T> c = a.cross(b);
    const T s = c.norm(), d = a.dot(b);
    q.value = atan2(s, d);
    const T aabb = a.squaredNorm() * b.squaredNorm();
    const double aabb0 = pdyn::value_of(aabb);
    if (pdyn::value_of(s) == 0.0 || !(aabb0 > 0.0) || !std::isfinite(aabb0)) return q;
    const Vector3<T> n = c / s;
    q.gradient[0] = (d * b.cross(n) - s * b) / aabb;
    q.gradient[2] = (d * n.cross(a) - s * a) / aabb;
    q.gradient[1] = -(q.gradient[0] + q.gradient[2]);
    q.defined = pdyn::all_finite(q.gradient[0]) && pdyn::all_finite(q.gradient[2]);
    return q;
  }
};

std::unique_ptr<pdyn::Force> create(const pdyn::Params& p, const pdyn::SceneContext& ctx) {
  return pdyn::make_harmonic<Bend>(p, ctx, "triples");
}

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Force;
  d.name = "angle";
  d.version = "1.1.0";
  d.description =
      "damped bending spring on the angle at j of each triple [i, j, k]: U = k/2 (theta - "
      "theta0)^2, f = -[k (theta - theta0) + kd dtheta/dt] grad theta";
  d.params = {
      pdyn::param::required("triples", pdyn::ParamType::IndexTriples, "",
                            "particle triples [[i, j, k], ...]; the angle is at the middle one j"),
      pdyn::param::optional("rest", pdyn::ParamType::RealList, "rad",
                            "rest angles: one for all triples or one per triple; default: the "
                            "initial angles")
          .at_least(0)
          .at_most(std::numbers::pi),
  };
  // After the terms: types, k, kd (pdyn/bonded.hpp); then rest.
  auto shared = pdyn::harmonic_params("bending stiffness", "N m/rad", "N m s/rad");
  d.params.insert(d.params.begin() + 1, shared.begin(), shared.end());
  d.force_traits.internal = true;
  d.create_force = create;
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
