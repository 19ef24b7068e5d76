// dihedral: a damped bending spring on the dihedral angle of each quadruple
// [i, j, k, l], the angle between the planes (i, j, k) and (j, k, l) about
// their common edge j-k: cloth's and shells' bending stiffness (two
// triangles sharing an edge; Baraff & Witkin 1998, section 4.3; Bridson,
// Marino & Fedkiw 2003) and the torsion of molecular chains (LAMMPS's
// dihedral styles, with the same atom order). With
//
//   F = x_i - x_j,  G = x_j - x_k,  H = x_l - x_k,
//   A = F x G,  B = H x G        (normals of the two planes)
//
// the angle is (Blondel & Karplus 1996, J. Comput. Chem. 17, 1132, eqs. 5-6)
//
//   phi = atan2((B x A) . G / |G|, A . B)              in (-pi, pi]
//
// phi = 0 when i and l are on the same side of the edge (cis), +-pi when
// the two triangles lie flat (trans: a flat sheet). And
//
//   U = k/2 d(phi, phi0)^2,   f = -[k d + kd dphi/dt] grad phi,
//
// with d(phi, phi0) = phi - phi0 folded into (-pi, pi], so that a flat
// sheet (phi0 = pi) bent slightly either way is pushed back either way and
// the energy has no jump where atan2 wraps. Blondel & Karplus's gradient,
// free of the singular 1/sin phi of the arccos form:
//
//   dphi/dx_i = -|G| / |A|^2 A
//   dphi/dx_l =  |G| / |B|^2 B
//   dphi/dx_j =  |G| / |A|^2 A + (F.G)/(|A|^2 |G|) A - (H.G)/(|B|^2 |G|) B
//   dphi/dx_k = -|G| / |B|^2 B - (F.G)/(|A|^2 |G|) A + (H.G)/(|B|^2 |G|) B
//
// It is undefined where a triangle degenerates (A = 0 or B = 0: i, j, k or
// j, k, l collinear) or the edge has no length: there the term adds no force.
// phi is invariant under rigid motions, so the force is internal; the
// damping resists only the rate of bending (power -kd (dphi/dt)^2 <= 0).
//
// The loop, the per-type coefficients, the threads and the Jacobians are
// pdyn/bonded.hpp's (Harmonic<Dihedral>).
#include <cmath>
#include <numbers>
#include <pdyn/bonded.hpp>
#include <pdyn/plugin.hpp>

namespace {

using pdyn::Coordinate;
using pdyn::Vector3;

struct Dihedral {
  static constexpr int arity = 4;

  template <class T>
  Coordinate<4, T> operator()(const std::array<Vector3<T>, 4>& x) const {
    using std::atan2;
    using std::sqrt;
    Coordinate<4, T> q;
    const Vector3<T> f = x[0] - x[1], g = x[1] - x[2], h = x[3] - x[2];
    const Vector3<T> a = f.cross(g), b = h.cross(g);
    const T a2 = a.squaredNorm(), b2 = b.squaredNorm(), glen = g.norm();
    const double a20 = pdyn::value_of(a2), b20 = pdyn::value_of(b2), g0 = pdyn::value_of(glen);
    // An edge of no length has no planes: phi is taken as 0 (no NaN in U).
    if (!(g0 > 0.0)) return q;
    q.value = atan2(b.cross(a).dot(g) / glen, a.dot(b));
    if (!(a20 > 0.0) || !(b20 > 0.0) || !std::isfinite(a20 * b20 * g0)) return q;
    const Vector3<T> ua = (glen / a2) * a, ub = (glen / b2) * b;
    const Vector3<T> ta = (f.dot(g) / (a2 * glen)) * a, tb = (h.dot(g) / (b2 * glen)) * b;
    q.gradient[0] = -ua;
    q.gradient[3] = ub;
    q.gradient[1] = ua + ta - tb;
    q.gradient[2] = -ub - ta + tb;
    q.defined = pdyn::all_finite(q.gradient[0]) && pdyn::all_finite(q.gradient[1]) &&
                pdyn::all_finite(q.gradient[2]) && pdyn::all_finite(q.gradient[3]);
    return q;
  }

  // phi - phi0 folded into (-pi, pi]: the angle's period is 2 pi.
  static double difference(double phi, double phi0) {
    constexpr double kTwoPi = 2.0 * std::numbers::pi;
    double d = std::remainder(phi - phi0, kTwoPi);
    if (d <= -std::numbers::pi) d += kTwoPi;
    return d;
  }
};

std::unique_ptr<pdyn::Force> create(const pdyn::Params& p, const pdyn::SceneContext& ctx) {
  return pdyn::make_harmonic<Dihedral>(p, ctx, "quads");
}

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Force;
  d.name = "dihedral";
  d.version = "1.0.0";
  d.description =
      "damped bending spring on the dihedral angle phi of each quadruple [i, j, k, l] about the "
      "edge j-k: U = k/2 (phi - phi0)^2, f = -[k (phi - phi0) + kd dphi/dt] grad phi";
  d.params = {
      pdyn::param::required("quads", pdyn::ParamType::IndexQuads, "",
                            "particle quadruples [[i, j, k, l], ...]: triangles (i, j, k) and "
                            "(j, k, l) hinged on the edge j-k"),
      pdyn::param::optional("rest", pdyn::ParamType::RealList, "rad",
                            "rest angles in [-pi, pi] (pi: flat): one for all quadruples or one "
                            "per quadruple; default: the initial angles")
          .at_least(-std::numbers::pi)
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
