// The implicit_euler solver class, declared here rather than inside the
// plugin's translation unit so that bench/ can build it directly and read
// its conjugate-gradient statistics (the Solver interface has no hook for
// them). Scenes reach it through the plugin (implicit_euler.cpp).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <pdyn/force.hpp>
#include <pdyn/solver.hpp>
#include <string>
#include <utility>
#include <vector>

namespace pdyn::solvers {

/// How the linear system of a step is solved.
enum class LinearSolver {
  Auto,    ///< direct when every force has Jacobians and the cloth is small enough, else cg
  Direct,  ///< sparse block LDL^T factorisation (every force must supply Jacobians)
  Cg,      ///< preconditioned conjugate gradients (matrix-free forces allowed)
};

struct ImplicitEulerOptions {
  LinearSolver linear_solver = LinearSolver::Auto;
  /// Auto solves directly while the factor needs at most this many bytes,
  /// else by CG. On the stiff cloth the direct solve is the faster at every
  /// size measured (docs/solvers.md), so the bound is on memory only: the
  /// 316 x 316 cloth's factor takes 0.50 GB, the 1000 x 1000 one's would
  /// take several.
  std::int64_t direct_max_bytes = std::int64_t{1} << 30;
  /// CG stops when the residual r of (M - h df/dv - h^2 df/dx) dv = b
  /// satisfies r^T P^-1 r <= cg_tolerance^2 b^T P^-1 b, P the block-diagonal
  /// preconditioner (Baraff & Witkin's criterion). The default keeps the solve's error well below
  /// the method's own first-order error per step (docs/solvers.md has the measurement).
  double cg_tolerance = 1e-3;
  /// More iterations than this in one step is an error.
  std::int64_t cg_max_iterations = 1000;
};

/// Linearised backward Euler (Baraff & Witkin 1998): see implicit_euler_solver.cpp.
namespace detail {

/// Sparse LDL^T of a symmetric positive definite matrix of 3 x 3 blocks,
/// up-looking, one block row of L at a time (T. A. Davis, "Algorithm 849: a
/// concise sparse Cholesky factorization package", ACM TOMS 31 (2005), with
/// each scalar replaced by a 3 x 3 block), after an approximate minimum
/// degree ordering of the block graph (Eigen's AMD). analyze() does
/// everything that depends only on the pattern and allocates; factorize()
/// and solve() then reuse that storage, so they allocate nothing.
class BlockLdlt {
 public:
  /// The pattern: `particles` lists the unknowns' particle indices; block row
  /// r (of particle particles[r]) holds slots row_start[particles[r]] ..
  /// row_start[particles[r] + 1] - 1 of the caller's block-CSR matrix, slot s
  /// at column particle col[s]. `compact` maps a particle to its position in
  /// `particles` (-1: not an unknown; such columns must not appear).
  void analyze(const std::vector<Index>& particles, const std::vector<Index>& compact,
               const std::vector<Index>& row_start, const std::vector<Index>& col);
  /// Factorises the matrix whose block-CSR values are `val` (same slots as
  /// given to analyze). Returns -1, or the elimination step at which a pivot
  /// block was not positive definite.
  Index factorize(const std::vector<Eigen::Matrix3d>& val);
  /// x = A^-1 b on the unknowns' particles; other entries of x are not touched.
  void solve(const Eigen::VectorXd& b, Eigen::VectorXd& x);
  /// 3 x 3 blocks in L below the diagonal, known after analyze().
  std::size_t factor_blocks() const noexcept {
    return lp_.empty() ? 0 : static_cast<std::size_t>(lp_.back());
  }
  /// Memory factorize() needs, known after analyze().
  double factor_bytes() const noexcept;
  /// Floating-point operations of one factorize(), known after analyze():
  /// 54 per 3 x 3 block product (27 multiplies, 27 additions), for bench/.
  double factor_flops() const noexcept;

 private:
  std::vector<Index> order_;                      // elimination step -> particle
  std::vector<Index> ucol_start_, urow_, uslot_;  // A's upper triangle, permuted, by column
  std::vector<Index> parent_, lp_, lnz_, li_;     // elimination tree and L's columns
  // L's blocks and the work row are stored 4 x 3, the fourth row zero: a
  // column is then two SSE2 packets (one AVX one) and Eigen vectorises the
  // block products that make up nearly all of the factorisation's work.
  using Block = Eigen::Matrix<double, 4, 3>;
  std::vector<Block> lx_, y_;
  std::vector<Eigen::Matrix3d> dinv_;  // D^-1
  std::vector<Index> flag_, pattern_;
  std::vector<Eigen::Vector4d> z_;
  bool allocated_ = false;  // the storage above, by the first factorize() after analyze()
};

}  // namespace detail

class ImplicitEuler final : public Solver {
 public:
  explicit ImplicitEuler(const ImplicitEulerOptions& options) : o_(options) {}

  void step(System& sys, double h) override;

  /// CG iterations of the last step.
  std::int64_t last_cg_iterations() const noexcept { return last_iterations_; }
  /// CG iterations over all steps so far.
  std::int64_t total_cg_iterations() const noexcept { return total_iterations_; }
  /// Steps taken so far.
  std::int64_t steps() const noexcept { return steps_; }
  /// Whether the last step solved its linear system directly (else by CG).
  bool last_step_direct() const noexcept { return last_direct_; }
  /// 3 x 3 blocks in the direct solve's L (0 before its analysis).
  std::size_t factor_blocks() const noexcept { return ldlt_.factor_blocks(); }
  /// Floating-point operations of one factorisation (0 before its analysis).
  double factor_flops() const noexcept { return ldlt_.factor_flops(); }
  /// Wall time spent factorising so far, s (bench/ reads it; two clock
  /// reads per step cost nothing next to a factorisation).
  double factor_seconds() const noexcept { return factor_seconds_; }

 private:
  struct Block {
    Index i, j;
    Eigen::Matrix3d b;
  };
  // Collects the 3 x 3 blocks that forces report, in the order they come.
  class Sink final : public JacobianSink {
   public:
    void add_dfdx(Index i, Index j, const Eigen::Matrix3d& block) override {
      dfdx.push_back({i, j, block});
    }
    void add_dfdv(Index i, Index j, const Eigen::Matrix3d& block) override {
      dfdv.push_back({i, j, block});
    }
    std::vector<Block> dfdx, dfdv;
  };

  void collect_jacobians(const System& sys);
  bool pattern_matches(const System& sys) const;
  void build_pattern(const System& sys);
  void assemble(const System& sys, double h, bool precondition);
  void apply(const System& sys, double h, const Eigen::VectorXd& u, Eigen::VectorXd& out);
  void fd_jvp(const System& sys, const Eigen::VectorXd& dx, const Eigen::VectorXd& dv,
              Eigen::VectorXd& out);
  void precondition(const Eigen::VectorXd& r, Eigen::VectorXd& z) const;
  void solve(const System& sys, double h);
  void solve_direct(const System& sys);

  ImplicitEulerOptions o_;
  Sink sink_;
  std::vector<Force*> fd_forces_;  // forces without analytic Jacobians

  // A = M - h df/dv - h^2 df/dx on the free particles, in block-CSR form:
  // block row i holds slots row_start_[i] .. row_start_[i+1]-1, slot s is
  // the 3 x 3 block at column col_[s]. Rows and columns of fixed particles
  // are not stored (the constraint filter). The pattern is rebuilt only when
  // the sequence of (i, j) the forces report, or the set of fixed particles,
  // changes; slot_x_ / slot_v_ map each reported block to its slot (-1:
  // touches a fixed particle).
  std::vector<std::pair<Index, Index>> pattern_key_;
  std::vector<std::uint8_t> pattern_fixed_;
  std::vector<Index> row_start_, col_, diag_slot_;
  std::vector<std::ptrdiff_t> slot_x_, slot_v_;
  std::vector<Eigen::Matrix3d> val_;
  std::vector<Eigen::Matrix3d> precond_;  // inverses of the diagonal blocks; 0 if fixed
  std::vector<Index> free_, compact_;     // free particles; particle -> position in free_
  detail::BlockLdlt ldlt_;
  bool ldlt_analyzed_ = false;  // for the current pattern
  bool last_direct_ = false;

  Eigen::VectorXd x0_, v0_, f0_, b_, dv_, r_, z_, p_, q_, kxv_;
  Eigen::VectorXd ux_, uv_, fd_out_;  // finite-difference directions and result
  Matrix3X xp_, vp_, fp_, fm_;        // finite-difference states and forces
  std::int64_t last_iterations_ = 0, total_iterations_ = 0, steps_ = 0;
  double factor_seconds_ = 0.0;
};

}  // namespace pdyn::solvers
