// pdyn/constraint.hpp — the Constraint interface (since ABI 7).
//
// A hard constraint is a set of scalar functions of the positions (and
// perhaps the time) that must stay zero: C(x, t) = 0. A rod keeps two
// particles at a distance, C = |x_i - x_j| - L; a bead stays on a wire. The
// constraint object only describes C; the kernel and the solvers enforce it
// (docs/constraints.md):
//
//  - Witkin's constrained dynamics (SIGGRAPH '97 notes "Constrained
//    Dynamics"; Witkin, Gleicher & Welch 1990): with every solver, the
//    kernel adds the constraint force J^T lambda to the forces, where
//        J W J^T lambda = -b - J W Q - ks C - kd Cdot,
//    W the inverse masses, Q the applied forces, Cdot = J v + c_t, and
//    b = Cddot - J a the part of the constraint's acceleration that does not
//    come from the particles' accelerations a;
//  - position and velocity projection (SHAKE/RATTLE, XPBD) in the solvers
//    that offer it, from C and J alone.
//
// A constraint object therefore reports, at a state, for each of its rows r:
//   value      C_r                                         (the row's unit, e.g. m)
//   rate       c_t = dC_r/dt at fixed positions            (unit/s; 0 unless
//                                                            C moves with time)
//   bias       b_r = Cddot_r - J_r a                       (unit/s^2; below)
//   jacobian   dC_r/dx_k for each particle k the row involves  (unit/m)
// The conformance kit (pdyn check) checks each of them by finite differences
// along the motion x(t) = x + v t.
//
// The bias, precisely. Witkin's notes differentiate C(x(t)) twice along a
// motion: Cdot = J xdot, Cddot = J xddot + Jdot xdot, where Jdot is J's
// change along the motion. With C(x, t) moving with time too, J = dC/dx and
// c_t = dC/dt are functions of (x, t), and
//   Cdot  = J v + c_t
//   Cddot = J a + (dJ/dt)_total v + (dc_t/dt)_total
//         = J a + [sum_k (dJ/dx_k) v_k] v + (dJ/dt) v  +  (dc_t/dx) v + d2C/dt2
// and dc_t/dx = d2C/dxdt = dJ/dt, so
//   b = Jdot_x v + 2 (dJ/dt) v + d2C/dt2,
//   Jdot_x v = [sum_k (dJ/dx_k) v_k] v = v^T (d2C/dx2) v
// where Jdot_x is J's change along the motion at fixed t: the position part
// only (J's explicit time dependence is the middle term, which appears twice,
// once from J and once from c_t). A constraint that does not move with time
// has b = v^T (d2C/dx2) v, Witkin's Jdot v; a constant J with C linear in t
// (a plane, a pin moving at constant velocity) gives b = 0. Every partial
// derivative here is taken at the state, every other argument fixed.
//
// A minimal plugin: a bead held on a sphere of radius R about c,
// C = |x - c| - R, J = n = (x - c)/|x - c|, b = (|v|^2 - (n.v)^2)/|x - c|
// (plugins/constraints/on_sphere, on pdyn/particle_constraint.hpp: the base
// class of constraints whose every row holds one particle).
#pragma once

#include <Eigen/Core>
#include <initializer_list>
#include <vector>

#include "pdyn/export.hpp"
#include "pdyn/particles.hpp"
#include "pdyn/plugin_object.hpp"
#include "pdyn/types.hpp"

namespace pdyn {

/// Which particles each row of a constraint involves: the sparsity of its
/// Jacobian, fixed for the object's lifetime. Row r's entries are
/// [row_begin[r], row_begin[r + 1]), entry e differentiates by particle[e].
/// Entries are numbered across all rows, not per row: the j-th particle of
/// row r is entry row_begin[r] + j, which is r only when every row before it
/// has exactly one particle. A rod over [i, j] as row r writes
/// jacobian.col(row_begin[r]) = dC/dx_i and jacobian.col(row_begin[r] + 1) =
/// dC/dx_j.
struct ConstraintPattern {
  std::vector<Index> row_begin{0};  ///< rows + 1 offsets, starting at 0
  std::vector<Index> particle;      ///< per entry: the particle (0 .. N-1)

  /// Number of rows.
  Index rows() const noexcept { return static_cast<Index>(row_begin.size()) - 1; }
  /// Number of Jacobian entries (3-vectors).
  Index entries() const noexcept { return static_cast<Index>(particle.size()); }
  /// Appends a row over `particles` (distinct indices).
  void add_row(std::initializer_list<Index> particles) {
    particle.insert(particle.end(), particles.begin(), particles.end());
    row_begin.push_back(static_cast<Index>(particle.size()));
  }
};

/// What a constraint writes at a state; the kernel sizes every member from
/// the pattern and zeroes `rate` and `bias` before each evaluate().
struct ConstraintValues {
  Eigen::VectorXd value;  ///< C_r, per row (the row's unit)
  Eigen::VectorXd rate;   ///< c_t: dC_r/dt at fixed positions, unit/s (per row)
  /// b_r = Cddot_r - J_r a = v^T (d2C_r/dx2) v + 2 (d2C_r/dx dt) v +
  /// d2C_r/dt2, unit/s^2 (per row; the header's comment derives it)
  Eigen::VectorXd bias;
  /// 3 x entries, unit/m: column row_begin[r] + j is dC_r/dx of the row's
  /// j-th particle, particle[row_begin[r] + j] (column r only when every row
  /// before r has one particle; pdyn/particle_constraint.hpp's family).
  Matrix3X jacobian;
};

/// Every constraint row of a system gathered in the order of its constraint
/// objects (since 0.9.0): what a solver that enforces the constraints itself
/// reads (System::evaluate_constraint_rows; RATTLE in plugins/solvers/verlet,
/// plugins/solvers/xpbd). Entry e of row r, for e in
/// [row_begin[r], row_begin[r + 1]), is dC_r/dx of particle[e].
struct PDYN_API ConstraintRows {
  std::vector<Index> row_begin{0};  ///< rows + 1 offsets
  std::vector<Index> particle;      ///< per entry: the particle (0 .. N-1)
  Eigen::VectorXd value;            ///< C_r (the row's unit)
  Eigen::VectorXd rate;             ///< c_t, unit/s
  Eigen::VectorXd bias;             ///< b_r, unit/s^2
  Eigen::VectorXd compliance;       ///< alpha_r: the row's unit per N (0 = rigid); the scene's
                                    ///< `compliance` of the row's constraint (XPBD)
  Matrix3X jacobian;                ///< 3 x entries, unit/m

  Index rows() const noexcept { return static_cast<Index>(value.size()); }
};

class PDYN_API Constraint : public PluginObject {
 public:
  /// The rows and the particles each involves. Called once, when the object
  /// is added to a system; the kernel checks the indices.
  virtual ConstraintPattern pattern() const = 0;

  /// Writes C, c_t, b and J at the state `p` into `out`. Called once per
  /// derivative evaluation (Witkin's method) or per projection iteration
  /// (RATTLE, XPBD), on one thread; must not allocate in a loop's hot path.
  virtual void evaluate(const ParticleView& p, ConstraintValues& out) const = 0;
};

}  // namespace pdyn
