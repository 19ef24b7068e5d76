// The kernel's side of the constraints: every constraint object's rows
// gathered into one sparse system, and Witkin's constraint force computed
// from it (pdyn/constraint.hpp, docs/constraints.md). Private to the kernel.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <memory>
#include <string>
#include <vector>

#include "pdyn/constraint.hpp"
#include "pdyn/system.hpp"

namespace pdyn {

class ConstraintForce {
 public:
  /// Adds one object's rows, each with `compliance` (>= 0); throws Error
  /// naming `label` if its pattern is malformed or names a particle outside
  /// 0 .. n-1.
  void add(const Constraint& c, const std::string& label, Index n, double compliance);
  Index rows() const noexcept { return rows_.rows(); }
  /// The gathered rows as of the last gather().
  const ConstraintRows& gathered() const noexcept { return rows_; }
  /// The largest particle index any row names (-1 without rows).
  Index max_particle() const noexcept { return max_particle_; }

  /// Object k's values, sized from its pattern, with rate and bias zeroed:
  /// System hands it to the object's evaluate().
  ConstraintValues& prepare(std::size_t k);
  /// Checks object k's values after its evaluate() (sizes kept, all finite)
  /// and copies them into the gathered C, c_t, b and J; an empty string, or
  /// what is wrong.
  std::string gather(std::size_t k);
  /// max |C_r| of the last evaluate().
  double max_error() const;

  /// Adds J^T lambda to `f`, lambda solving J W J^T lambda = -b - J W f -
  /// ks C - kd (J v + c_t) by conjugate gradients preconditioned by J W J^T's
  /// sparse LDL^T (regularised when rows are redundant: the minimum-norm
  /// lambda).
  /// `w` holds the inverse masses (0 for fixed particles). Throws Error if CG
  /// does not reach the tolerance.
  void add_force(const ParticleView& p, const Eigen::VectorXd& w, const ConstraintFeedback& fb,
                 Eigen::Ref<Matrix3X> f);
  /// lambda of the last add_force() (empty before the first).
  const Eigen::VectorXd& multipliers() const noexcept { return lambda_; }

 private:
  // Jacobian-free products with J W J^T over the involved particles only.
  void apply(const Eigen::VectorXd& lambda, Eigen::VectorXd& out);
  // Assembles A = J W J^T (diagonal 1 on rows that cannot act) on its
  // pattern, analysed when the rows change, and factorises it.
  void factorise();
  void analyse();
  // z ~ A^+ r: the factor's solve, or for a singular A
  // (A + s I)^-1 A (A + s I)^-1, which keeps CG in A's range.
  void precondition(const Eigen::VectorXd& r, Eigen::VectorXd& z);

  struct Block {  // one object's rows within the gathered ones
    Index first_row = 0, first_entry = 0;
    ConstraintValues values;
  };
  std::vector<Block> blocks_;
  ConstraintRows rows_;          // gathered pattern and values
  std::vector<Index> slot_;      // per entry: the involved particle's slot
  std::vector<Index> involved_;  // per slot: the particle
  std::vector<Index> slot_of_;   // per particle seen so far: its slot, or -1
  Index max_particle_ = -1;
  // CG work space, kept to avoid allocating per evaluation.
  Eigen::VectorXd w_slot_, diag_, rhs_, lambda_, r_, z_, d_, q_, t_;
  // J W J^T and its factor: per pair of entries on one particle, the slot of
  // A's values it adds to; the pattern analysed once per set of rows.
  std::vector<Index> pair_first_, pair_second_, pair_slot_, diagonal_slot_;
  Eigen::SparseMatrix<double> a_;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt_;
  bool analysed_ = false, singular_ = false;
  Matrix3X u_;  // 3 x involved: W J^T lambda
};

}  // namespace pdyn
