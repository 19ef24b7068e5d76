// pdyn/harmonic.hpp — Harmonic<Geometry>, the law of a damped harmonic
// spring on one scalar coordinate of a term's particles (since 0.10.0), with
// exact Jacobians by automatic differentiation.
//
// Most bonded terms are one damped harmonic spring on one scalar coordinate
// q of the particles (Witkin's "damped spring" generalised, SIGGRAPH '97
// notes; LAMMPS's bond/angle/dihedral "harmonic" and "quadratic" styles):
//
//   U = k/2 (q - q0)^2,   f_a = -[k (q - q0) + kd dq/dt] grad_a q,
//   dq/dt = sum_b grad_b q . v_b.
//
// For those the author writes only the coordinate and its gradient, once,
// as a template on the scalar type, and uses Harmonic<Geometry> as the law:
//
//   struct Geometry {
//     static constexpr int arity = 3;
//     template <class T>
//     pdyn::Coordinate<3, T> operator()(const std::array<pdyn::Vector3<T>, 3>& x) const;
//     // Optional, for a periodic coordinate (an angle in (-pi, pi]): q - q0
//     // folded into one period.
//     static double difference(double q, double q0);
//   };
//
// Harmonic then gives the forces, the energy, and exact Jacobians: the
// Hessian of q is the derivative of the author's gradient, taken by
// forward-mode automatic differentiation (Eigen's AutoDiffScalar runs the
// same template with a 3N-vector of derivatives), never by finite
// differences. For implicit solvers the curvature term -(k (q - q0) +
// kd dq/dt) Hess q is projected onto its negative semidefinite part
// (eigenvalues clamped at zero: Teran, Sifakis, Irving & Fedkiw 2005,
// "Robust quasistatic finite elements and flesh simulation", section 4), the
// damping force's position derivative, which is not symmetric, is left out
// (Baraff & Witkin 1998, section 5.2), and -k grad q grad q^T is kept: at
// rest (q = q0, v = 0) that is the exact derivative.
//
// make_harmonic<Geometry>() is such a plugin's whole factory, and
// harmonic_params() its `types`, `k` and `kd` parameters. Harmonic is a law
// of pdyn/bonded_law.hpp that BondedForce (pdyn/bonded_force.hpp) runs;
// this header is the one of the bonded SDK that compiles Eigen's
// AutoDiffScalar and eigenvalue solver, which a law written by hand does not
// need.
#pragma once

#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <unsupported/Eigen/AutoDiff>
#include <utility>
#include <vector>

#include "pdyn/bonded_force.hpp"
#include "pdyn/bonded_law.hpp"
#include "pdyn/bonded_params.hpp"
#include "pdyn/export.hpp"
#include "pdyn/force.hpp"
#include "pdyn/params.hpp"
#include "pdyn/plugin.hpp"
#include "pdyn/types.hpp"

namespace pdyn {

/// A 3-vector of any scalar type (double, or an automatic-differentiation
/// scalar when Harmonic takes second derivatives).
template <class T>
using Vector3 = Eigen::Matrix<T, 3, 1>;

/// The value of a scalar, plain or automatic-differentiation: for the tests
/// a geometry makes on its numbers (a zero length, a finite product).
inline double value_of(double x) { return x; }
template <class D>
double value_of(const Eigen::AutoDiffScalar<D>& x) {
  return x.value();
}

/// True when every component's value is finite.
template <class T>
bool all_finite(const Vector3<T>& v) {
  return std::isfinite(value_of(v[0])) && std::isfinite(value_of(v[1])) &&
         std::isfinite(value_of(v[2]));
}

/// A scalar coordinate of N particles and its gradient, for Harmonic.
template <int N, class T = double>
struct Coordinate {
  T value{};                                ///< q (m, rad, m^2, ...)
  std::array<Vector3<T>, N> gradient = {};  ///< dq/dx_a of each particle
  /// false where q has no gradient (collinear or coincident particles): the
  /// term then adds no force, never NaN.
  bool defined = false;
};

/// The coefficients of a damped harmonic term, one set per term type.
struct HarmonicCoefficients {
  double k = 0.0;   ///< stiffness, J per unit of q squared (N/m for a length)
  double kd = 0.0;  ///< damping of dq/dt, J s per unit of q squared
};

/// U = k/2 (q - q0)^2 and f = -[k (q - q0) + kd dq/dt] grad q on the
/// coordinate q of Geometry (see the top of this file).
template <class Geometry>
class Harmonic {
 public:
  static constexpr int arity = Geometry::arity;
  using Coefficients = HarmonicCoefficients;

  explicit Harmonic(Geometry g = {}) : geometry_(std::move(g)) {}

  const Geometry& geometry() const noexcept { return geometry_; }

  static double difference(double q, double q0) {
    if constexpr (requires { Geometry::difference(q, q0); }) {
      return Geometry::difference(q, q0);
    } else {
      return q - q0;
    }
  }

  [[gnu::always_inline]] inline BondedTerm<arity> operator()(const BondedPoint<arity>& p,
                                                             const Coefficients& c) const {
    BondedTerm<arity> t;
    const Coordinate<arity> q = geometry_(p.positions());
    const double dq = difference(q.value, p.rest);
    t.energy = 0.5 * c.k * dq * dq;
    if (!q.defined) return t;
    double magnitude = c.k * dq;
    if (c.kd > 0.0) magnitude += c.kd * rate(p, q);
    for (int a = 0; a < arity; ++a) t.force[a] = -(magnitude * q.gradient[a]);
    return t;
  }

  double measure(const std::array<Vec3, arity>& x) const { return geometry_(x).value; }

  bool reads_velocity(const Coefficients& c) const { return c.kd > 0.0; }

  bool jacobian(const BondedPoint<arity>& p, const Coefficients& c, BondedMatrix<arity>& dfdx,
                BondedMatrix<arity>& dfdv) const {
    return jacobians(p, c, dfdx, dfdv, false);
  }

  bool exact_jacobian(const BondedPoint<arity>& p, const Coefficients& c, BondedMatrix<arity>& dfdx,
                      BondedMatrix<arity>& dfdv) const {
    return jacobians(p, c, dfdx, dfdv, true);
  }

 private:
  static constexpr int kDim = 3 * arity;
  using Derivatives = Eigen::Matrix<double, kDim, 1>;

  static double rate(const BondedPoint<arity>& p, const Coordinate<arity>& q) {
    double r = q.gradient[0].dot(p.velocity(0));
    for (int a = 1; a < arity; ++a) r += q.gradient[a].dot(p.velocity(a));
    return r;
  }

  // g = grad q as one 3N-vector and H = Hess q, the derivative of the
  // geometry's gradient by forward-mode automatic differentiation.
  bool gradient_and_hessian(const BondedPoint<arity>& p, double& value, Derivatives& g,
                            BondedMatrix<arity>& h) const;

  bool jacobians(const BondedPoint<arity>& p, const Coefficients& c, BondedMatrix<arity>& dfdx,
                 BondedMatrix<arity>& dfdv, bool exact) const;

  Geometry geometry_;
};

/// Harmonic's coefficients of each term type 0..n_types-1 from the
/// coefficient lists `k` and `kd` (one value for all types or one per type).
PDYN_API std::vector<HarmonicCoefficients> harmonic_coefficients(const Params& params,
                                                                 std::int32_t n_types,
                                                                 std::string_view k,
                                                                 std::string_view kd);

/// The parameters of a Harmonic force after its term list: `types`, then
/// `k` (default 1, in `k_unit`) and `kd` (default 0, in `kd_unit`), each one
/// value for all term types or one per type; `what` names the stiffness
/// ("bending stiffness").
PDYN_API std::vector<ParamSpec> harmonic_params(const std::string& what, const std::string& k_unit,
                                                const std::string& kd_unit);

/// The factory of a Harmonic<Geometry> force: its terms from `terms_key`,
/// `types`, `rest`, `k` and `kd` read by read_bonded and
/// harmonic_coefficients.
template <class Geometry>
std::unique_ptr<Force> make_harmonic(const Params& params, const SceneContext& ctx,
                                     std::string_view terms_key) {
  const Harmonic<Geometry> law;
  const auto in = read_bonded<Geometry::arity>(params, ctx, terms_key, {"k", "kd"},
                                               [&](const auto& x) { return law.measure(x); });
  return std::make_unique<BondedForce<Harmonic<Geometry>>>(
      law, in, harmonic_coefficients(params, in.n_types, "k", "kd"), ctx.particles.size());
}

// ---- Harmonic's Jacobians ----

template <class Geometry>
bool Harmonic<Geometry>::gradient_and_hessian(const BondedPoint<arity>& p, double& value,
                                              Derivatives& g, BondedMatrix<arity>& h) const {
  using AD = Eigen::AutoDiffScalar<Derivatives>;
  std::array<Vector3<AD>, arity> x;
  for (int a = 0; a < arity; ++a) {
    for (int k = 0; k < 3; ++k) x[a][k] = AD(p.x[a][k], kDim, 3 * a + k);
  }
  const Coordinate<arity, AD> q = geometry_(x);
  if (!q.defined) return false;
  value = q.value.value();
  for (int a = 0; a < arity; ++a) {
    for (int k = 0; k < 3; ++k) {
      const AD& d = q.gradient[a][k];
      g(3 * a + k) = d.value();
      // A component the geometry left constant carries no derivatives.
      if (d.derivatives().size() == kDim) {
        h.row(3 * a + k) = d.derivatives().transpose();
      } else {
        h.row(3 * a + k).setZero();
      }
    }
  }
  return true;
}

template <class Geometry>
bool Harmonic<Geometry>::jacobians(const BondedPoint<arity>& p, const Coefficients& c,
                                   BondedMatrix<arity>& dfdx, BondedMatrix<arity>& dfdv,
                                   bool exact) const {
  double value = 0.0;
  Derivatives g;
  BondedMatrix<arity> h;
  dfdx.setZero();
  dfdv.setZero();
  if (!gradient_and_hessian(p, value, g, h)) return false;  // no force there either
  Derivatives v;
  for (int a = 0; a < arity; ++a) v.template segment<3>(3 * a) = p.velocity(a);
  const double rate = c.kd > 0.0 ? g.dot(v) : 0.0;
  const double magnitude = c.k * difference(value, p.rest) + c.kd * rate;
  const BondedMatrix<arity> ggt = g * g.transpose();
  dfdv = -c.kd * ggt;
  if (exact) {
    // f = -m g with m = k (q - q0) + kd g.v:
    // df/dx = -k g g^T - kd g (H v)^T - m H.
    dfdx = -c.k * ggt - c.kd * g * (h * v).transpose() - magnitude * h;
    return true;
  }
  // The curvature term -m H, symmetrised (H is symmetric up to rounding)
  // and clamped to its negative semidefinite part.
  const BondedMatrix<arity> curvature = -0.5 * magnitude * (h + h.transpose());
  const Eigen::SelfAdjointEigenSolver<BondedMatrix<arity>> eig(curvature);
  const Derivatives lambda = eig.eigenvalues().cwiseMin(0.0);
  dfdx = -c.k * ggt + eig.eigenvectors() * lambda.asDiagonal() * eig.eigenvectors().transpose();
  return true;
}

}  // namespace pdyn
