// RATTLE's two projections for velocity Verlet (Andersen 1983, "Rattle: a
// 'velocity' version of the Shake algorithm", J. Comput. Phys. 52, 24; the
// position stage is SHAKE's, Ryckaert, Ciccotti & Berendsen 1977; Hairer,
// Lubich & Wanner, "Geometric Numerical Integration", VII.1.4):
//
//   v_half = v0 + h/2 (a0 + W J(x0)^T lambda),  x1 = x0 + h v_half,  C(x1, t1) = 0
//   v1     = v_half + h/2 (a1 + W J(x1)^T mu),  J(x1) v1 + c_t(x1, t1) = 0
//
// with W the inverse masses. The multipliers act along the rows' gradients
// at the step's start (positions) and end (velocities); the method stays
// symplectic, time-reversible and second order (Leimkuhler & Skeel 1994).
//
// The position stage is a nonlinear system in lambda. SHAKE solves it row by
// row (Gauss-Seidel), which needs O(n^2) sweeps along a chain of n rods; this
// one takes simplified Newton steps on all rows at once,
//   (J0 W J0^T) dmu = C(x),  x <- x - W J0^T dmu,
// with J0 W J0^T factorised once per step (sparse LDL^T; its symbolic
// analysis once per run). The velocity stage is linear: one solve with
// J1 W J1^T.
//
// Redundant rows (a cloth of structural, shear and bend rods; a taut edge
// between two pins) make J W J^T singular; its rank is then revealed by the
// factorisation's pivots and the solves give the minimum-norm multipliers
// (solve_min_norm in rattle.cpp). Near a singular configuration (a square of
// rods sheared flat, its four rods parallel) the position stage can have no
// solution along J(x0) at all: the simplified iteration then stalls at a
// nonzero |C|, and that step projects along the current gradients instead
// (Gauss-Newton on C(x) = 0, x <- x - W J(x)^T dmu: the mass-weighted
// projection onto C = 0 of Hairer, Lubich & Wanner IV.4), which is still
// second order but not symplectic on that step.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <cstdint>
#include <pdyn/constraint.hpp>
#include <pdyn/system.hpp>
#include <pdyn/types.hpp>
#include <vector>

namespace pdyn_verlet {

using pdyn::Index;

class Rattle {
 public:
  Rattle(double tolerance, Index max_iterations)
      : tolerance_(tolerance), max_iterations_(max_iterations) {}

  /// At the step's start (x0, t0): evaluates the rows and factorises
  /// J0 W J0^T, unless the state is the one the last step ended with.
  void begin(const pdyn::System& sys);

  /// After the drift to x1 at t1: moves the positions onto C = 0 and v_half
  /// by the same displacement / h. v_half is the system's velocities, or
  /// `half` when the step keeps it apart (velocity-dependent forces); the
  /// system's velocities are then the predictor 2 v_half - v0 and move by
  /// twice as much. Throws pdyn::Error if the iteration does not reach the
  /// tolerance.
  void project_positions(pdyn::System& sys, double h, pdyn::Matrix3X* half);

  /// At x1 after the kick: removes J1 v + c_t from the velocities.
  void project_velocities(pdyn::System& sys);

  /// Records the state the step ended with: the next begin() reuses the
  /// rows and factor of the end of this step if nothing changed it.
  void end(const pdyn::System& sys) {
    version_ = sys.state_version();
    time_ = sys.time();
  }

  /// The multipliers of the last solve (the velocity stage's after a step),
  /// one per row: minimum-norm when rows are redundant.
  const Eigen::VectorXd& multipliers() const noexcept { return mu_; }

  /// Iterations of the last position stage.
  Index iterations() const noexcept { return iterations_; }
  /// Position stages so far that projected along the current gradients
  /// because RATTLE's equations had no solution along J(x0).
  std::int64_t projected_steps() const noexcept { return projected_steps_; }

 private:
  // Copies J and c_t of the rows just evaluated, assembles J W J^T over
  // them and factorises it.
  void factorise(const pdyn::System& sys, const pdyn::ConstraintRows& rows);
  void fill_products(const pdyn::System& sys);
  // mu_ = the minimum-norm least-squares solution of A mu = rhs_ (A = the
  // last factorised J W J^T): the factor's solve when A is nonsingular,
  // conjugate gradients preconditioned by the regularised factor when rows
  // are redundant. Refines until |rhs - A mu| <= goal or nothing more can be
  // gained (a part of rhs outside A's range).
  void solve_min_norm(double goal);
  void apply(const Eigen::VectorXd& x, Eigen::VectorXd& y) const;   // y = A x
  void precondition(const Eigen::VectorXd& r, Eigen::VectorXd& z);  // z ~ A^+ r
  // Throws if the last solve gave a non-finite multiplier.
  void require_finite_multipliers(const char* stage) const;
  // Calls add(k, -W_k J0_e^T mu_r) for each entry e of each active row r
  // on a free particle k: the correction the multipliers mu_ make.
  template <class Add>
  void for_each_correction(const pdyn::System& sys, Add&& add) const {
    for (Index r = 0; r < static_cast<Index>(active_.size()); ++r) {
      if (active_[r] == 0) continue;
      for (Index e = row_begin_[r]; e < row_begin_[r + 1]; ++e) {
        const Index k = particle_[e];
        if (sys.fixed()[static_cast<std::size_t>(k)] != 0) continue;
        const double w = sys.inverse_masses()(k);
        add(k, pdyn::Vec3(-(w * mu_(r)) * jacobian_.col(e)));
      }
    }
  }
  // Rows whose particles are all fixed can act on nothing: they are left
  // out of the solves (identity rows) and out of the convergence test.
  double largest_active(const Eigen::VectorXd& c) const;

  double tolerance_;
  Index max_iterations_;
  Index iterations_ = 0;
  std::int64_t projected_steps_ = 0;
  std::uint64_t version_ = ~std::uint64_t{0};  // state_version() at the last end()
  double time_ = 0.0;

  pdyn::Matrix3X jacobian_;  // J at the last factorisation, 3 x entries
  Eigen::VectorXd rate_;     // c_t there
  std::vector<Index> row_begin_, particle_;
  // A = J W J^T's pattern, fixed: per pair of entries on one particle, the
  // slot of A's values it adds to.
  std::vector<Index> pair_first_, pair_second_, pair_slot_;
  std::vector<Index> diagonal_slot_;  // per row
  std::vector<std::uint8_t> active_;  // per row
  Eigen::SparseMatrix<double> a_;     // J W J^T
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt_;
  bool analysed_ = false;
  // A's pivots showed it singular (redundant rows): ldlt_ then holds
  // A + shift_ I, and solves refine towards the minimum-norm multipliers.
  bool singular_ = false;
  double shift_ = 0.0;
  Eigen::VectorXd rhs_, mu_;
  Eigen::VectorXd cg_r_, cg_z_, cg_d_, cg_q_, cg_t_;  // solve_min_norm's work space
};

}  // namespace pdyn_verlet
