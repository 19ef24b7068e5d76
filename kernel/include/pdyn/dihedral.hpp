// pdyn/dihedral.hpp — the dihedral angle of four particles and its
// gradient (since 0.9.0): the geometry of the `dihedral` bending force and
// of the `bending` constraint, for any plugin that bends sheets or twists
// chains.
//
// For the quadruple [i, j, k, l], the angle between the planes (i, j, k) and
// (j, k, l) about their common edge j-k. With
//
//   F = x_i - x_j,  G = x_j - x_k,  H = x_l - x_k,
//   A = F x G,  B = H x G        (normals of the two planes)
//
// the angle is (Blondel & Karplus 1996, J. Comput. Chem. 17, 1132, eqs. 5-6)
//
//   phi = atan2((B x A) . G / |G|, A . B)              in (-pi, pi]   (rad)
//
// phi = 0 when i and l are on the same side of the edge (cis), +-pi when
// the two triangles lie flat (trans: a flat sheet). Blondel & Karplus's
// gradient, free of the singular 1/sin phi of the arccos form (rad/m):
//
//   dphi/dx_i = -|G| / |A|^2 A
//   dphi/dx_l =  |G| / |B|^2 B
//   dphi/dx_j =  |G| / |A|^2 A + (F.G)/(|A|^2 |G|) A - (H.G)/(|B|^2 |G|) B
//   dphi/dx_k = -|G| / |B|^2 B - (F.G)/(|A|^2 |G|) A + (H.G)/(|B|^2 |G|) B
//
// It is undefined where a triangle degenerates (A = 0 or B = 0: i, j, k or
// j, k, l collinear) or the edge has no length: `defined` is then false.
// The scalar type T is double, or an automatic-differentiation scalar for
// second derivatives (pdyn/harmonic.hpp's Jacobians; the bending
// constraint's bias v^T (d2 phi/dx2) v).
#pragma once

#include <array>
#include <cmath>
#include <numbers>
#include <vector>

#include "pdyn/bonded.hpp"
#include "pdyn/params.hpp"

namespace pdyn {

/// The dihedral angle as a coordinate of pdyn/harmonic.hpp (Harmonic<Dihedral>).
struct Dihedral {
  static constexpr int arity = 4;

  /// phi (rad) of x = [x_i, x_j, x_k, x_l] (m) and, where defined, its
  /// gradient by each (rad/m).
  template <class T>
  Coordinate<4, T> operator()(const std::array<Vector3<T>, 4>& x) const {
    using std::atan2;
    using std::sqrt;
    Coordinate<4, T> q;
    const Vector3<T> f = x[0] - x[1], g = x[1] - x[2], h = x[3] - x[2];
    const Vector3<T> a = f.cross(g), b = h.cross(g);
    const T a2 = a.squaredNorm(), b2 = b.squaredNorm(), glen = g.norm();
    const double a20 = value_of(a2), b20 = value_of(b2), g0 = value_of(glen);
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
    q.defined = all_finite(q.gradient[0]) && all_finite(q.gradient[1]) &&
                all_finite(q.gradient[2]) && all_finite(q.gradient[3]);
    return q;
  }

  /// The parameters every plugin on hinges takes: `quads` and `rest`.
  static std::vector<ParamSpec> params() {
    return {param::required("quads", ParamType::IndexQuads, "",
                            "particle quadruples [[i, j, k, l], ...]: triangles (i, j, k) and "
                            "(j, k, l) hinged on the edge j-k"),
            param::optional("rest", ParamType::RealList, "rad",
                            "rest angles in [-pi, pi] (pi: flat): one for all quadruples or one "
                            "per quadruple; default: the initial angles")
                .at_least(-std::numbers::pi)
                .at_most(std::numbers::pi)};
  }

  /// phi - phi0 folded into (-pi, pi] (rad): the angle's period is 2 pi.
  static double difference(double phi, double phi0) {
    constexpr double kTwoPi = 2.0 * std::numbers::pi;
    double d = std::remainder(phi - phi0, kTwoPi);
    if (d <= -std::numbers::pi) d += kTwoPi;
    return d;
  }
};

/// The energy of a torsion as a function of phi alone, U(phi) (J), and its
/// derivative dU/dphi (J/rad): what a TorsionLaw's `Potential` returns.
struct TorsionEnergy {
  double u = 0.0;
  double du = 0.0;
};

/// A bonded law (pdyn/bonded_law.hpp) for any potential of the dihedral
/// angle alone (since 0.10.0): LAMMPS's dihedral styles opls and harmonic,
/// the improper angle of improper_style harmonic. `Potential` has a
/// `Coefficients` type and `TorsionEnergy operator()(double phi, const
/// Coefficients&) const`; then f_a = -dU/dphi grad_a phi, and where phi
/// has no gradient (a degenerate triangle or edge) the term adds its
/// energy and no force, never NaN:
///
///   struct Opls { struct Coefficients { double k1, k2, k3, k4; };
///                 pdyn::TorsionEnergy operator()(double phi, const Coefficients& c) const; };
///   pdyn::BondedForce<pdyn::TorsionLaw<Opls>>(...)
template <class Potential>
struct TorsionLaw {
  static constexpr int arity = 4;
  using Coefficients = typename Potential::Coefficients;
  Potential potential{};

  BondedTerm<4> operator()(const BondedPoint<4>& p, const Coefficients& c) const {
    BondedTerm<4> t;
    const Coordinate<4> q = Dihedral{}(p.positions());
    const TorsionEnergy e = potential(q.value, c);
    t.energy = e.u;
    if (!q.defined) return t;
    for (int a = 0; a < 4; ++a) t.force[a] = -e.du * q.gradient[a];
    return t;
  }
  /// phi (rad), for read_bonded's default rest values (unused by a
  /// potential whose coefficients hold its rest angle).
  double measure(const std::array<Vec3, 4>& x) const { return Dihedral{}(x).value; }
  bool reads_velocity(const Coefficients&) const { return false; }
};

}  // namespace pdyn
