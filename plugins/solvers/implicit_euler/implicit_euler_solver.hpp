// The implicit_euler solver class, declared here rather than inside the
// plugin's translation unit so that bench/ can build it directly and read
// its conjugate-gradient statistics (the Solver interface has no hook for
// them). Scenes reach it through the plugin (implicit_euler.cpp).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <pdyn/force.hpp>
#include <pdyn/solver.hpp>
#include <utility>
#include <vector>

namespace pdyn::solvers {

struct ImplicitEulerOptions {
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
  void assemble(const System& sys, double h);
  void apply(const System& sys, double h, const Eigen::VectorXd& u, Eigen::VectorXd& out);
  void fd_jvp(const System& sys, const Eigen::VectorXd& dx, const Eigen::VectorXd& dv,
              Eigen::VectorXd& out);
  void precondition(const Eigen::VectorXd& r, Eigen::VectorXd& z) const;
  void solve(const System& sys, double h);

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

  Eigen::VectorXd x0_, v0_, f0_, b_, dv_, r_, z_, p_, q_, kxv_;
  Eigen::VectorXd ux_, uv_, fd_out_;  // finite-difference directions and result
  Matrix3X xp_, vp_, fp_, fm_;        // finite-difference states and forces
  std::int64_t last_iterations_ = 0, total_iterations_ = 0, steps_ = 0;
};

}  // namespace pdyn::solvers
