// pdyn/bonded_law.hpp — what a bonded *law* is (since 0.10.0): the one
// function of a term's particles that a bonded plugin writes, and the types
// it reads and returns (BondedPoint, BondedTerm, BondedMatrix).
//
// A bonded term acts on a fixed list of 2, 3 or 4 particles: a spring
// (bond), a bending angle, a triangle's area, a dihedral. What differs
// between them is one small function of those particles, the law;
// BondedForce<Law> (pdyn/bonded_force.hpp) runs everything else. The
// general law computes the forces of one term itself:
//
//   struct Law {
//     static constexpr int arity = 2;   // particles per term: 2, 3 or 4
//     struct Coefficients { ... };      // one set per term type
//     // Energy (J) and the force on each of the term's particles (N).
//     pdyn::BondedTerm<arity> operator()(const pdyn::BondedPoint<arity>& p,
//                                        const Coefficients& c) const;
//     // The term's coordinate at positions x (its unit: m, rad, m^2):
//     // the rest value when the scene gives none.
//     double measure(const std::array<pdyn::Vec3, arity>& x) const;
//     // Optional: false when forces with these coefficients do not read
//     // velocities (an undamped spring), so that velocity Verlet may reuse
//     // them; without it the force declares that it reads them.
//     bool reads_velocity(const Coefficients& c) const;
//     // Optional: the term's Jacobians for implicit solvers, 3N x 3N with
//     // block (a, b) = d f_a / d x_b (resp. v_b), given zeroed; symmetric
//     // and negative semidefinite, so that the solvers' M - h df/dv -
//     // h^2 df/dx stays positive definite. Returns false where the term
//     // adds nothing (no blocks are added then). Without it implicit solvers
//     // differentiate numerically.
//     bool jacobian(const pdyn::BondedPoint<arity>& p, const Coefficients& c,
//                   pdyn::BondedMatrix<arity>& dfdx, pdyn::BondedMatrix<arity>& dfdv) const;
//     // Optional: the exact derivatives of operator() where jacobian()
//     // approximates them, for the conformance kit's bonded.jacobian_exact.
//     bool exact_jacobian(... same arguments ...) const;
//     // Optional, in place of jacobian() for a two-body law whose force
//     // depends on x_0 - x_1 and v_0 - v_1 alone, with f_1 = -f_0 (a
//     // spring): its one 3 x 3 block k = df_0/dx_0 (d = df_0/dv_0), given
//     // zeroed; the term's Jacobian is then [k -k; -k k] ([d -d; -d d]).
//     // Implicit solvers get the four blocks without a 6 x 6 matrix being
//     // built, zeroed and scanned per term (about a third fewer
//     // instructions for the stiff cloth's Jacobians).
//     bool pair_jacobian(const pdyn::BondedPoint<2>& p, const Coefficients& c,
//                        Eigen::Matrix3d& k, Eigen::Matrix3d& d) const;
//   };
//
// A term that is one damped harmonic spring on a scalar coordinate needs no
// law of its own: Harmonic<Geometry> (pdyn/harmonic.hpp) is that law.
#pragma once

#include <Eigen/Core>
#include <array>

#include "pdyn/types.hpp"

namespace pdyn {

/// One term as a law sees it.
template <int N>
struct BondedPoint {
  static_assert(N >= 2 && N <= 4, "a bonded term joins 2, 3 or 4 particles");
  std::array<const double*, N> x{};  ///< each particle's position: x, y, z, m
  std::array<const double*, N> v{};  ///< each particle's velocity, m/s
  double rest = 0.0;                 ///< the term's rest value, in the unit of Law::measure

  Vec3 position(int a) const { return Vec3(x[a][0], x[a][1], x[a][2]); }
  Vec3 velocity(int a) const { return Vec3(v[a][0], v[a][1], v[a][2]); }
  std::array<Vec3, N> positions() const {
    std::array<Vec3, N> out;
    for (int a = 0; a < N; ++a) out[a] = position(a);
    return out;
  }
};

/// A term's energy and forces.
template <int N>
struct BondedTerm {
  double energy = 0.0;  ///< U of the term, J
  /// The force on each of the term's particles, in term order, N.
  std::array<Vec3, N> force = filled();

 private:
  static std::array<Vec3, N> filled() {
    std::array<Vec3, N> z;
    z.fill(Vec3::Zero());
    return z;
  }
};

/// A term's Jacobian: block (a, b), rows 3a..3a+2 and columns 3b..3b+2, is
/// d f_a / d x_b (or d f_a / d v_b), N/m (N s/m).
template <int N>
using BondedMatrix = Eigen::Matrix<double, 3 * N, 3 * N>;

}  // namespace pdyn
