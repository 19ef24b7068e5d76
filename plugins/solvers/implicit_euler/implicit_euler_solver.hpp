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

#include "supernodal_cholesky.hpp"

namespace pdyn::solvers {

/// How the linear system of a step is solved.
enum class LinearSolver {
  Auto,    ///< direct when every force has Jacobians and the cloth is small enough, else cg
  Direct,  ///< sparse supernodal Cholesky factorisation (every force must supply Jacobians)
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
  std::size_t factor_blocks() const noexcept { return cholesky_.factor_blocks(); }
  /// Memory of the direct solve's factor, bytes (0 before its analysis).
  double factor_bytes() const noexcept { return cholesky_.factor_bytes(); }
  /// Floating-point operations of one factorisation (0 before its analysis).
  double factor_flops() const noexcept { return cholesky_.factor_flops(); }
  /// Wall time of each part of the steps so far, s (bench/ reads it: a few
  /// clock reads per step cost nothing next to a factorisation).
  struct PartSeconds {
    double forces = 0.0;         ///< f0 (every force and collider)
    double jacobians = 0.0;      ///< the forces' Jacobians, entered into A
    double analysis = 0.0;       ///< the factor's symbolic analysis (once per pattern)
    double factorisation = 0.0;  ///< the numeric factorisation
    double solve = 0.0;          ///< right side, triangular solves or CG, the update
  };
  const PartSeconds& part_seconds() const noexcept { return parts_; }
  /// Wall time spent factorising so far, s.
  double factor_seconds() const noexcept { return parts_.factorisation; }
  /// The last step's linear system A dv = b, for bench/ (another
  /// factorisation timed on the same matrices): A on the free particles in
  /// block-CSR form, as SupernodalCholesky::analyze() and factorize() take
  /// it (kg; b in kg m/s, dv in m/s, over all particles). Valid until the
  /// next step.
  struct LinearSystem {
    const std::vector<Index>& free;           ///< the unknowns' particles
    const std::vector<Index>& compact;        ///< particle -> position in `free`, or -1
    const std::vector<Index>& row_start;      ///< particle i's blocks: slots row_start[i] ..
    const std::vector<Index>& col;            ///< each slot's column particle
    const std::vector<Eigen::Matrix3d>& val;  ///< each slot's 3 x 3 block
    const Eigen::VectorXd& b;                 ///< right side, 3 per particle (0 if fixed)
    const Eigen::VectorXd& dv;                ///< the step's solution
  };
  LinearSystem linear_system() const noexcept {
    return {free_, compact_, row_start_, col_, val_, b_, dv_};
  }

 private:
  struct Key {
    Index i, j;
    int kind;  // 0: df/dx, 1: df/dv
    bool operator==(const Key&) const = default;
  };
  struct Block {
    Index i, j;
    int kind;
    Eigen::Matrix3d b;
  };
  // Takes the 3 x 3 blocks that forces report: while `assembling`, enters
  // each straight into A as long as they come as `key` says (else sets
  // `missed`); otherwise records them in the order they come.
  class Sink final : public JacobianSink {
   public:
    void add_dfdx(Index i, Index j, const Eigen::Matrix3d& block) override { add(i, j, 0, block); }
    void add_dfdv(Index i, Index j, const Eigen::Matrix3d& block) override { add(i, j, 1, block); }
    std::vector<Block> blocks;
    bool assembling = false, missed = false;
    std::size_t cursor = 0;
    const Key* key = nullptr;  // the last step's pattern, key_size blocks
    std::size_t key_size = 0;
    const std::ptrdiff_t* slot = nullptr;
    Eigen::Matrix3d* val = nullptr;
    double* kxv = nullptr;
    const double* v0 = nullptr;
    double scale[2] = {0.0, 0.0};  // h^2 for df/dx, h for df/dv

   private:
    void add(Index i, Index j, int kind, const Eigen::Matrix3d& block);
    void record(Index i, Index j, int kind, const Eigen::Matrix3d& block);
  };

  void collect_jacobians(const System& sys, double h);
  void ask_forces(const System& sys);
  void begin_assembly(const System& sys);
  void build_pattern(const System& sys);
  void invert_diagonal_blocks(const System& sys);
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
  // changes; slot_ maps each reported block to its slot (-1: touches a
  // fixed particle).
  std::vector<Key> pattern_key_;
  bool have_pattern_ = false;
  std::vector<std::uint8_t> pattern_fixed_;
  std::vector<Index> row_start_, col_, diag_slot_;
  std::vector<std::ptrdiff_t> slot_;
  std::vector<Eigen::Matrix3d> val_;
  std::vector<Eigen::Matrix3d> precond_;  // inverses of the diagonal blocks; 0 if fixed
  std::vector<Index> free_, compact_;     // free particles; particle -> position in free_
  detail::SupernodalCholesky cholesky_;
  bool cholesky_analyzed_ = false;  // for the current pattern
  bool last_direct_ = false;

  Eigen::VectorXd x0_, v0_, f0_, b_, dv_, r_, z_, p_, q_, kxv_;
  Eigen::VectorXd ux_, uv_, fd_out_;  // finite-difference directions and result
  Matrix3X xp_, vp_, fp_, fm_;        // finite-difference states and forces
  std::int64_t last_iterations_ = 0, total_iterations_ = 0, steps_ = 0;
  PartSeconds parts_;
};

}  // namespace pdyn::solvers
