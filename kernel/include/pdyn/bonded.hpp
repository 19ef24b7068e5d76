// pdyn/bonded.hpp — bonded terms: the author writes one term, the kernel
// runs the loop.
//
// A bonded term acts on a fixed list of 2, 3 or 4 particles: a spring
// (bond), a bending angle, a triangle's area, a dihedral. What differs
// between them is one small function of those particles; the loop over the
// terms, the per-type coefficients, the rest values a scene may leave out,
// the threads, the energy and the Jacobians are the same for all. As LAMMPS's
// bond, angle and dihedral styles are, but written once: a plugin supplies a
// *law* and instantiates BondedForce<Law>.
//
// The general law computes the forces of one term itself:
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
// Threads and determinism (pdyn/parallel.hpp's rule: bit-identical results
// for every thread count). The particles are cut into fixed blocks of
// consecutive ids, whose size depends on N only. A term whose particles all
// lie in one block is interior to it; the others are boundary terms. Phase
// 1: each block's interior terms add into their particles directly, in term
// order, the blocks spread over the threads; no two threads touch one
// particle. Phase 2: the boundary terms' forces go into a buffer in
// parallel, then each particle they touch adds its entries in term order.
// Each particle's accumulator receives the same terms in the same order
// whatever the thread count. With particles numbered in space (a grid, a
// rope) boundary terms are a few per cent.
//
// Checking. BondedForce also implements BondedReference, which the
// conformance kit (`pdyn check`, the bonded.* checks) uses to look at one
// term at a time: its forces against minus the gradient of its energy, the
// third law and zero torque for an `internal` force, its Jacobians against
// finite differences, and the loop's sum against the terms'.
#pragma once

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <concepts>
#include <cstdint>
#include <limits>
#include <memory>
#include <numbers>
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>
#include <unsupported/Eigen/AutoDiff>
#include <utility>
#include <vector>

#include "pdyn/error.hpp"
#include "pdyn/export.hpp"
#include "pdyn/force.hpp"
#include "pdyn/parallel.hpp"
#include "pdyn/params.hpp"
#include "pdyn/plugin.hpp"
#include "pdyn/thermo.hpp"

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

/// The optional checking hook of a bonded force: one term at a time, for the
/// conformance kit (`pdyn check`, the bonded.* checks). BondedForce<Law>
/// implements it; found by dynamic_cast on the Force, so a force without it
/// keeps its vtable (no ABI bump).
class PDYN_API BondedReference {
 public:
  virtual ~BondedReference();
  /// Particles per term: 2, 3 or 4.
  virtual int bonded_arity() const = 0;
  /// How many terms the force holds.
  virtual Index bonded_terms() const = 0;
  /// Term s's particles (the first bonded_arity() entries).
  virtual std::array<Index, 4> bonded_term(Index s) const = 0;
  /// Term s's energy (J, returned) and forces on its particles (N) at `p`.
  virtual double bonded_term_forces(const ParticleView& p, Index s,
                                    std::array<Vec3, 4>& force) const = 0;
  /// Term s's Jacobians (3n x 3n for n = bonded_arity()): with exact = false
  /// what add_jacobians() adds, with exact = true the exact derivatives of
  /// bonded_term_forces(). False when the law gives no such Jacobian.
  virtual bool bonded_term_jacobian(const ParticleView& p, Index s, bool exact,
                                    Eigen::MatrixXd& dfdx, Eigen::MatrixXd& dfdv) const = 0;
};

/// What a bonded plugin's factory reads from its parameters (read_bonded()).
template <int N>
struct BondedInput {
  std::vector<std::array<Index, N>> terms;  ///< each term's particles
  std::vector<double> rest;                 ///< each term's rest value
  std::vector<std::int32_t> types;          ///< each term's type, or empty: all type 0
  std::int32_t n_types = 1;                 ///< types given coefficients: 0..n_types-1
};

/// The number of term types the coefficient lists `keys` (RealList
/// parameters, each one value for all types or one per type) give: the
/// longest list's length. Throws ParamError on a list whose length is
/// neither 1 nor that.
PDYN_API std::int32_t bonded_type_count(const Params& params,
                                        std::initializer_list<std::string_view> keys);

/// Type t's value of the coefficient list `key` (its only value if it has
/// one).
PDYN_API double bonded_coefficient(const Params& params, std::string_view key, std::int32_t t);

/// Reads the parameters every bonded plugin shares, in one place: the term
/// list `terms_key` (IndexPairs, IndexTriples or IndexQuads for N = 2, 3,
/// 4; no particle twice in one term), `types` (IntegerList, optional: one
/// type per term, each with coefficients in `coefficient_keys`) and `rest`
/// (RealList, optional: one for all terms or one per term; default: each
/// term's `measure` at the scene's initial positions). Throws ParamError
/// naming the key and element.
template <int N, class Measure>
BondedInput<N> read_bonded(const Params& params, const SceneContext& ctx,
                           std::string_view terms_key,
                           std::initializer_list<std::string_view> coefficient_keys,
                           Measure&& measure) {
  BondedInput<N> in;
  require_distinct_particles(params, terms_key);
  if (ctx.particles.size() > std::numeric_limits<std::int32_t>::max()) {
    throw ParamError(std::string(terms_key),
                     "a scene of " + std::to_string(ctx.particles.size()) +
                         " particles (expected at most 2147483647: bonded terms store 32-bit "
                         "particle ids)");
  }
  if constexpr (N == 2) {
    in.terms = params.pairs(terms_key);
  } else if constexpr (N == 3) {
    in.terms = params.triples(terms_key);
  } else {
    in.terms = params.quads(terms_key);
  }
  in.n_types = bonded_type_count(params, coefficient_keys);
  if (params.has("types")) {
    const auto& given = params.integers("types");
    if (given.size() != 1 && given.size() != in.terms.size()) {
      throw ParamError("types", std::string("has ") + std::to_string(given.size()) +
                                    " values for " + std::to_string(in.terms.size()) + " " +
                                    std::string(terms_key) + " (expected 1 value for all, or " +
                                    std::to_string(in.terms.size()) + ")");
    }
    for (std::size_t s = 0; s < given.size(); ++s) {
      if (given[s] < 0 || given[s] >= in.n_types) {
        std::string keys;
        for (const auto k : coefficient_keys) keys += (keys.empty() ? "" : ", ") + std::string(k);
        throw ParamError("types",
                         std::to_string(given[s]) + " is not a term type (expected 0.." +
                             std::to_string(in.n_types - 1) + ": " + keys + " give " +
                             std::to_string(in.n_types) + " type" + (in.n_types > 1 ? "s" : "") +
                             ")",
                         static_cast<long>(s));
      }
    }
    in.types.resize(in.terms.size());
    for (std::size_t s = 0; s < in.types.size(); ++s) {
      in.types[s] = static_cast<std::int32_t>(given.size() == 1 ? given[0] : given[s]);
    }
  }
  const auto& x = ctx.particles.x;
  in.rest = rest_values(params, "rest", in.terms.size(), terms_key, [&](std::size_t s) {
    std::array<Vec3, N> at;
    for (int a = 0; a < N; ++a) at[a] = x.col(in.terms[s][a]);
    return measure(at);
  });
  return in;
}

/// Harmonic's coefficients of each term type 0..n_types-1 from the
/// coefficient lists `k` and `kd` (one value for all types or one per type).
PDYN_API std::vector<HarmonicCoefficients> harmonic_coefficients(const Params& params,
                                                                 std::int32_t n_types,
                                                                 std::string_view k,
                                                                 std::string_view kd);

/// The `types` parameter every bonded plugin declares (see read_bonded).
PDYN_API ParamSpec bonded_types_param();

/// The parameters of a Harmonic force after its term list: `types`, then
/// `k` (default 1, in `k_unit`) and `kd` (default 0, in `kd_unit`), each one
/// value for all term types or one per type; `what` names the stiffness
/// ("bending stiffness").
PDYN_API std::vector<ParamSpec> harmonic_params(const std::string& what, const std::string& k_unit,
                                                const std::string& kd_unit);

/// A force made of bonded terms with law `Law` (see the top of this file).
template <class Law>
class BondedForce : public Force, public BondedReference, public VirialSource {
 public:
  static constexpr int N = Law::arity;
  static_assert(N >= 2 && N <= 4, "a bonded term joins 2, 3 or 4 particles");
  using Coefficients = typename Law::Coefficients;
  /// Particle ids as stored per term: 32 bits (the factory checks N fits).
  using Id = std::int32_t;

  /// `coefficients[t]` for terms of type t (`input.types`, or type 0 for all
  /// when it is empty); `n_particles` is the scene's N: the terms are grouped
  /// by particle block here, once, so that stepping never allocates.
  /// Throws Error when N does not fit 32-bit ids or a type has no
  /// coefficients.
  BondedForce(Law law, const BondedInput<N>& input, std::vector<Coefficients> coefficients,
              Index n_particles)
      : law_(std::move(law)), coefficients_(std::move(coefficients)) {
    if (n_particles > std::numeric_limits<Id>::max()) {
      throw Error("a scene of " + std::to_string(n_particles) +
                  " particles (expected at most 2147483647: bonded terms store 32-bit ids)");
    }
    for (const auto t : input.types) {
      if (t < 0 || static_cast<std::size_t>(t) >= coefficients_.size()) {
        throw Error("a bonded term of type " + std::to_string(t) + " has no coefficients");
      }
    }
    if (coefficients_.empty()) throw Error("a bonded force needs coefficients for type 0");
    group_by_block(input, n_particles);
  }

  const Law& law() const noexcept { return law_; }

  void add_forces(const ParticleView& p, Eigen::Ref<Matrix3X> f) override {
    // The kernel's accumulator is a plain 3 x N matrix: with its stride
    // known at compile time the scatter is plain pointer arithmetic.
    if (f.outerStride() == 3) {
      accumulate(p, f.data(), std::integral_constant<Index, 3>{});
    } else {
      accumulate(p, f.data(), static_cast<Index>(f.outerStride()));
    }
  }

  /// Reads velocities if any term type's coefficients do (Law::reads_velocity).
  StateDependence dependence() const override {
    if constexpr (requires(const Law& l, const Coefficients& c) {
                    { l.reads_velocity(c) } -> std::convertible_to<bool>;
                  }) {
      const bool v = std::any_of(coefficients_.begin(), coefficients_.end(),
                                 [&](const Coefficients& c) { return law_.reads_velocity(c); });
      return {v, false};
    } else {
      return {true, false};
    }
  }

  /// Sum of the terms' energies, J.
  std::optional<double> potential_energy(const ParticleView& p) const override {
    double u = 0.0;
    for (Index s = 0; s < term_count(); ++s) u += law_(point(p, s), coefficients(s)).energy;
    return u;
  }

  /// Sum over the terms of sum_a (x_a - x_0) . f_a (pdyn/thermo.hpp), J:
  /// the positions as given, as the terms measure them.
  double virial(const ParticleView& p) const override {
    double w = 0.0;
    for (Index s = 0; s < term_count(); ++s) {
      const BondedTerm<N> t = law_(point(p, s), coefficients(s));
      const Vec3 x0 = p.x.col(terms_[s][0]);
      for (int a = 1; a < N; ++a) w += (p.x.col(terms_[s][a]) - x0).dot(t.force[a]);
    }
    return w;
  }

  /// The law's jacobian() (or pair_jacobian()) of every term, in term
  /// order; false (numerical differentiation) when the law has neither.
  bool add_jacobians(const ParticleView& p, JacobianSink& sink) override {
    if constexpr (kHasPairJacobian) {
      // The blocks (a, b) of [k -k; -k k] in the order below, as the
      // general loop would report them: the same calls, the same bits.
      Eigen::Matrix3d k, d;
      for (Index s = 0; s < term_count(); ++s) {
        k.setZero();
        d.setZero();
        if (!law_.pair_jacobian(point(p, s), coefficients(s), k, d)) continue;
        const bool damped = !d.isZero(0.0);
        const Eigen::Matrix3d minus_k = -k, minus_d = -d;
        const Index ends[2] = {terms_[s][0], terms_[s][1]};
        for (int a = 0; a < 2; ++a) {
          for (int b = 0; b < 2; ++b) {
            sink.add_dfdx(ends[a], ends[b], a == b ? k : minus_k);
            if (damped) sink.add_dfdv(ends[a], ends[b], a == b ? d : minus_d);
          }
        }
      }
      return true;
    } else if constexpr (kHasJacobian) {
      BondedMatrix<N> dfdx, dfdv;
      for (Index s = 0; s < term_count(); ++s) {
        dfdx.setZero();
        dfdv.setZero();
        if (!law_.jacobian(point(p, s), coefficients(s), dfdx, dfdv)) continue;
        const bool damped = !dfdv.isZero(0.0);
        for (int a = 0; a < N; ++a) {
          for (int b = 0; b < N; ++b) {
            const Index i = terms_[s][a], j = terms_[s][b];
            sink.add_dfdx(i, j, dfdx.template block<3, 3>(3 * a, 3 * b));
            if (damped) sink.add_dfdv(i, j, dfdv.template block<3, 3>(3 * a, 3 * b));
          }
        }
      }
      return true;
    } else {
      return Force::add_jacobians(p, sink);
    }
  }

  // ---- BondedReference ----
  int bonded_arity() const override { return N; }
  Index bonded_terms() const override { return term_count(); }
  std::array<Index, 4> bonded_term(Index s) const override {
    std::array<Index, 4> out{-1, -1, -1, -1};
    for (int a = 0; a < N; ++a) out[a] = terms_[s][a];
    return out;
  }
  double bonded_term_forces(const ParticleView& p, Index s,
                            std::array<Vec3, 4>& force) const override {
    const BondedTerm<N> t = law_(point(p, s), coefficients(s));
    for (int a = 0; a < 4; ++a) force[a] = a < N ? t.force[a] : Vec3::Zero();
    return t.energy;
  }
  bool bonded_term_jacobian(const ParticleView& p, Index s, bool exact, Eigen::MatrixXd& dfdx,
                            Eigen::MatrixXd& dfdv) const override {
    BondedMatrix<N> dx = BondedMatrix<N>::Zero(), dv = BondedMatrix<N>::Zero();
    if (exact) {
      if constexpr (kHasExactJacobian) {
        law_.exact_jacobian(point(p, s), coefficients(s), dx, dv);
      } else if constexpr (kHasJacobian) {
        law_jacobian(point(p, s), coefficients(s), dx, dv);
      } else {
        return false;
      }
    } else {
      if constexpr (kHasJacobian) {
        law_jacobian(point(p, s), coefficients(s), dx, dv);
      } else {
        return false;
      }
    }
    dfdx = dx;
    dfdv = dv;
    return true;
  }

 private:
  static constexpr bool kHasPairJacobian =
      N == 2 &&
      requires(const Law& l, const BondedPoint<N>& q, const Coefficients& c, Eigen::Matrix3d& k) {
    l.pair_jacobian(q, c, k, k);
  };
  static constexpr bool kHasJacobian =
      kHasPairJacobian ||
      requires(const Law& l, const BondedPoint<N>& q, const Coefficients& c, BondedMatrix<N>& m) {
    l.jacobian(q, c, m, m);
  };

  // The law's jacobian(), or its pair_jacobian() as [k -k; -k k] blocks
  // (dfdx and dfdv given zeroed).
  bool law_jacobian(const BondedPoint<N>& q, const Coefficients& c, BondedMatrix<N>& dfdx,
                    BondedMatrix<N>& dfdv) const {
    if constexpr (kHasPairJacobian) {
      Eigen::Matrix3d k = Eigen::Matrix3d::Zero(), d = Eigen::Matrix3d::Zero();
      if (!law_.pair_jacobian(q, c, k, d)) return false;
      for (int a = 0; a < 2; ++a) {
        for (int b = 0; b < 2; ++b) {
          dfdx.template block<3, 3>(3 * a, 3 * b) = a == b ? k : Eigen::Matrix3d(-k);
          dfdv.template block<3, 3>(3 * a, 3 * b) = a == b ? d : Eigen::Matrix3d(-d);
        }
      }
      return true;
    } else {
      return law_.jacobian(q, c, dfdx, dfdv);
    }
  }
  static constexpr bool kHasExactJacobian =
      requires(const Law& l, const BondedPoint<N>& q, const Coefficients& c, BondedMatrix<N>& m) {
    l.exact_jacobian(q, c, m, m);
  };

  Index term_count() const { return static_cast<Index>(terms_.size()); }
  const Coefficients& coefficients(Index s) const {
    return coefficients_[types_.empty() ? 0 : static_cast<std::size_t>(types_[s])];
  }
  double rest(Index s) const { return uniform_rest_ ? rest0_ : rest_[static_cast<std::size_t>(s)]; }
  BondedPoint<N> point(const ParticleView& p, Index s) const {
    BondedPoint<N> q;
    for (int a = 0; a < N; ++a) {
      q.x[a] = p.x.data() + 3 * static_cast<Index>(terms_[s][a]);
      q.v[a] = p.v.data() + 3 * static_cast<Index>(terms_[s][a]);
    }
    q.rest = rest(s);
    return q;
  }

  // What the force loop reads, copied into locals: through `this` and the
  // view, every store into f could alias them, and the compiler would
  // reload the pointers and coefficients once per term (issue 17: 20%
  // slower than the hand-fused reference at 10^6 particles).
  template <bool Uniform, bool Typed>
  struct Kernel {
    Law law;
    const double* __restrict x;  // 3 x N, column-major, stride 3
    const double* __restrict v;
    const std::array<Id, N>* __restrict terms;
    const double* __restrict rest;          // per term, or null if Uniform
    const std::int32_t* __restrict types;   // per term, or null if !Typed
    const Coefficients* __restrict coeffs;  // per type
    double rest0;

    // `c0`: type 0's coefficients, copied by the caller into a local of its
    // loop, so that the compiler keeps them in registers.
    [[gnu::always_inline]] inline BondedTerm<N> term(Index s, const Coefficients& c0) const {
      BondedPoint<N> q;
      for (int a = 0; a < N; ++a) {
        q.x[a] = x + 3 * static_cast<Index>(terms[s][a]);
        q.v[a] = v + 3 * static_cast<Index>(terms[s][a]);
      }
      q.rest = Uniform ? rest0 : rest[s];
      if constexpr (Typed) {
        return law(q, coeffs[types[s]]);
      } else {
        return law(q, c0);
      }
    }
  };

  template <class Stride>
  void accumulate(const ParticleView& p, double* f, Stride fs) const {
    const bool typed = !types_.empty();
    if (uniform_rest_) {
      typed ? accumulate<true, true>(p, f, fs) : accumulate<true, false>(p, f, fs);
    } else {
      typed ? accumulate<false, true>(p, f, fs) : accumulate<false, false>(p, f, fs);
    }
  }

  template <bool Uniform, bool Typed, class Stride>
  void accumulate(const ParticleView& p, double* f, Stride fs) const {
    const Index n_blocks = static_cast<Index>(block_start_.size()) - 1;
    const bool parallel = max_threads() > 1 && term_count() >= kParallelMinElements;
    const Kernel<Uniform, Typed> k{law_,
                                   p.x.data(),
                                   p.v.data(),
                                   terms_.data(),
                                   Uniform ? nullptr : rest_.data(),
                                   Typed ? types_.data() : nullptr,
                                   coefficients_.data(),
                                   rest0_};
    const Index* block_start = block_start_.data();
    // Terms [begin, end) scattered straight into f, in order.
    auto direct = [&](Index begin, Index end) {
      const Coefficients c0 = k.coeffs[0];
      const auto* terms = k.terms;  // a local: stores into f cannot change it
      for (Index s = begin; s < end; ++s) {
        const BondedTerm<N> t = k.term(s, c0);
        for (int a = 0; a < N; ++a) {
          double* fa = f + fs * terms[s][a];
          fa[0] += t.force[a][0];
          fa[1] += t.force[a][1];
          fa[2] += t.force[a][2];
        }
      }
    };
    // Not `omp parallel for if (parallel)`: libgomp allocates a team for
    // every region, even a serial one, and stepping must not allocate. A
    // plugin built without OpenMP runs the blocks in order on one thread.
    if (!parallel) {
      // On one thread the blocks serve nothing: every term in order, the
      // boundary terms last. Each particle then receives its terms' forces
      // in the order the buffered path below adds them (block by block,
      // then its boundary terms in term order), so the bits are the same.
      direct(0, term_count());
      return;
    }
#ifdef _OPENMP
#pragma omp parallel for schedule(static)
#endif
    for (Index blk = 0; blk < n_blocks; ++blk) direct(block_start[blk], block_start[blk + 1]);
    const Index first = block_start_.back(), n_boundary = term_count() - first;
    if (n_boundary == 0) return;
    double* buffer = buffer_.data();
    parallel_ranges(n_boundary, [&](Index b, Index e) {
      const Coefficients c0 = k.coeffs[0];
      for (Index s = b; s < e; ++s) {
        const BondedTerm<N> t = k.term(first + s, c0);
        for (int a = 0; a < N; ++a) {
          double* out = buffer + 3 * (N * s + a);
          out[0] = t.force[a][0];
          out[1] = t.force[a][1];
          out[2] = t.force[a][2];
        }
      }
    });
    const Index* touched = touched_.data();
    const Index* touched_start = touched_start_.data();
    const Index* incident = incident_.data();
    parallel_ranges(static_cast<Index>(touched_.size()), [&](Index b, Index e) {
      for (Index t = b; t < e; ++t) {
        double* fi = f + fs * touched[t];
        for (Index q = touched_start[t]; q < touched_start[t + 1]; ++q) {
          const double* g = buffer + 3 * incident[q];
          fi[0] += g[0];
          fi[1] += g[1];
          fi[2] += g[2];
        }
      }
    });
  }

  // Orders the terms as add_forces uses them: the interior terms of block
  // 0, of block 1, ..., then the boundary terms, each group in the order
  // given (a stable counting sort), and builds the boundary CSR list. About
  // 64 blocks of at least 4096 particles each: enough to balance any thread
  // count up to a few dozen, few enough that boundary terms stay a small
  // fraction. Below 32768 particles, blocks of N/8 particles but at least
  // 1024, so that two threads share a 100 x 100 cloth evenly.
  void group_by_block(const BondedInput<N>& in, Index n) {
    const Index block = std::max({std::min<Index>(4096, (n + 7) / 8), (n + 63) / 64, Index{1024}});
    const Index n_blocks = std::max<Index>(1, (n + block - 1) / block);
    const Index n_terms = static_cast<Index>(in.terms.size());
    auto bucket = [&](const std::array<Index, N>& term) {
      const Index b = term[0] / block;
      for (int a = 1; a < N; ++a) {
        if (term[a] / block != b) return n_blocks;  // boundary
      }
      return b;
    };
    std::vector<Index> start(static_cast<std::size_t>(n_blocks + 2), 0);
    for (const auto& term : in.terms) ++start[bucket(term) + 1];
    for (Index b = 0; b <= n_blocks; ++b) start[b + 1] += start[b];
    terms_.resize(in.terms.size());
    rest_.resize(in.terms.size());
    if (!in.types.empty()) types_.resize(in.terms.size());
    std::vector<Index> next(start.begin(), start.end() - 1);
    for (Index s = 0; s < n_terms; ++s) {
      const Index to = next[bucket(in.terms[s])]++;
      for (int a = 0; a < N; ++a) terms_[to][a] = static_cast<Id>(in.terms[s][a]);
      rest_[to] = in.rest[s];
      if (!in.types.empty()) types_[to] = in.types[s];
    }
    uniform_rest_ =
        std::all_of(rest_.begin(), rest_.end(), [&](double r) { return r == rest_[0]; });
    rest0_ = rest_.empty() ? 0.0 : rest_[0];
    if (uniform_rest_) std::vector<double>().swap(rest_);
    if (!types_.empty() &&
        std::all_of(types_.begin(), types_.end(), [&](std::int32_t t) { return t == types_[0]; })) {
      // One type for all: keep its coefficients as type 0's.
      coefficients_ = {coefficients_[static_cast<std::size_t>(types_[0])]};
      std::vector<std::int32_t>().swap(types_);
    }
    block_start_.assign(start.begin(), start.end() - 1);  // n_blocks + 1 entries
    const Index first = block_start_.back(), n_boundary = n_terms - first;
    // CSR over the particles the boundary terms touch, in id order.
    std::vector<std::pair<Index, Index>> ends;  // (particle, N s + a)
    ends.reserve(static_cast<std::size_t>(N * n_boundary));
    for (Index s = 0; s < n_boundary; ++s) {
      for (int a = 0; a < N; ++a) ends.emplace_back(terms_[first + s][a], N * s + a);
    }
    std::sort(ends.begin(), ends.end());  // by particle, then term order
    for (std::size_t e = 0; e < ends.size(); ++e) {
      if (e == 0 || ends[e].first != ends[e - 1].first) {
        touched_.push_back(ends[e].first);
        touched_start_.push_back(static_cast<Index>(e));
      }
      incident_.push_back(ends[e].second);
    }
    touched_start_.push_back(static_cast<Index>(ends.size()));
    buffer_.resize(3, N * n_boundary);
  }

  Law law_;
  std::vector<Coefficients> coefficients_;  // per term type
  std::vector<std::array<Id, N>> terms_;    // grouped by block (group_by_block)
  std::vector<double> rest_;                // per term; empty if uniform_rest_
  std::vector<std::int32_t> types_;         // per term; empty if all are type 0
  bool uniform_rest_ = false;               // every term has rest value rest0_
  double rest0_ = 0.0;
  std::vector<Index> block_start_;    // block b's interior terms: [start[b], start[b + 1])
  std::vector<Index> touched_;        // particles with boundary terms, increasing
  std::vector<Index> touched_start_;  // their entries in incident_
  std::vector<Index> incident_;       // N s + a: particle a of boundary term s
  mutable Matrix3X buffer_;           // boundary terms' forces, N
};

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
