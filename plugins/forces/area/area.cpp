// area: a damped spring on the area of each triangle [i, j, k], for 2-D soft
// bodies and membranes. With e1 = x_j - x_i, e2 = x_k - x_i, c = e1 x e2:
//
//   A = |c| / 2                                        (unsigned, in 3-D)
//   U = k/2 (A - A0)^2
//   f = -[k (A - A0) + kd dA/dt] grad A,   dA/dt = grad A . v
//
// and, with n = c / |c|, the gradient of A with respect to each corner is
// half the normal crossed with the opposite edge, pointing away from it in
// the triangle's plane:
//
//   dA/dx_i = n x (x_k - x_j) / 2,  dA/dx_j = n x (x_i - x_k) / 2,
//   dA/dx_k = n x (x_j - x_i) / 2
//
// The unsigned 3-D area is used rather than the signed area in a fixed
// plane: it needs no plane to be chosen, works for triangles anywhere in
// space (a membrane in 3-D, or a 2-D body in any plane), and is invariant
// under every rigid motion, so the force is internal (zero net force and
// torque). The price: it does not resist inversion, since a triangle folded
// through zero area has the same A as before. A degenerate triangle (A = 0:
// coincident or collinear corners) has no normal; there the triple adds no
// force, and never NaN.
//
// The loop, the per-type coefficients, the threads and the Jacobians are
// pdyn/bonded.hpp's (Harmonic<Triangle>): this file gives A and its
// gradient, written once for any scalar type so that the SDK differentiates
// the gradient exactly for implicit solvers.
#include <cmath>
#include <pdyn/bonded.hpp>
#include <pdyn/plugin.hpp>

namespace {

using pdyn::Coordinate;
using pdyn::Vector3;

// The area of [i, j, k] and its gradient.
struct Triangle {
  static constexpr int arity = 3;

  template <class T>
  Coordinate<3, T> operator()(const std::array<Vector3<T>, 3>& x) const {
    Coordinate<3, T> q;
    const Vector3<T> c = (x[1] - x[0]).cross(x[2] - x[0]);
    const T len = c.norm();
    q.value = 0.5 * len;
    const double len0 = pdyn::value_of(len);
    if (!(len0 > 0.0) || !std::isfinite(len0)) return q;
    const T half = 0.5 / len;
    const Vector3<T> half_n = half * c;
    q.gradient[0] = half_n.cross(x[2] - x[1]);
    q.gradient[1] = half_n.cross(x[0] - x[2]);
    q.gradient[2] = half_n.cross(x[1] - x[0]);
    q.defined = true;
    return q;
  }
};

std::unique_ptr<pdyn::Force> create(const pdyn::Params& p, const pdyn::SceneContext& ctx) {
  return pdyn::make_harmonic<Triangle>(p, ctx, "triples");
}

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Force;
  d.name = "area";
  d.version = "1.1.0";
  d.description =
      "damped spring on the area A = |(x_j - x_i) x (x_k - x_i)|/2 of each triangle: U = k/2 (A - "
      "A0)^2, f = -[k (A - A0) + kd dA/dt] grad A";
  d.params = {
      pdyn::param::required("triples", pdyn::ParamType::IndexTriples, "",
                            "triangles [[i, j, k], ...] of particle indices"),
      pdyn::param::optional("rest", pdyn::ParamType::RealList, "m^2",
                            "rest areas: one for all triangles or one per triangle; default: the "
                            "initial areas")
          .at_least(0),
  };
  // After the terms: types, k, kd (pdyn/bonded.hpp); then rest.
  auto shared = pdyn::harmonic_params("area stiffness (U = k/2 (A - A0)^2)", "N/m^3", "N s/m^3");
  d.params.insert(d.params.begin() + 1, shared.begin(), shared.end());
  d.force_traits.internal = true;
  d.create_force = create;
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
