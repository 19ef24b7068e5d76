#include "rattle.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <pdyn/error.hpp>

namespace pdyn_verlet {
namespace {
// A pivot of J W J^T's LDL^T below this fraction of its row's diagonal: the
// matrix is singular (redundant rows).
constexpr double kSingularPivot = 1e-10;
// The regularisation then, relative to the largest diagonal.
constexpr double kShift = 1e-14;
// Solves refine until |rhs - A mu| <= kSolveGoal |rhs|, or until the part of
// the residual in A's range is below kRangeResidual of the right-hand side
// (in the preconditioner's norm), within kMaxRefinements iterations.
constexpr double kSolveGoal = 1e-10;
constexpr double kRangeResidual = 1e-13;
constexpr Index kMaxRefinements = 50;
// Backtracking halves a projection's step at most down to this fraction.
constexpr double kSmallestScale = 1.0 / 1024;
}  // namespace

void Rattle::begin(const pdyn::System& sys) {
  // The rows and factor the last step ended with (J(x1), for its velocity
  // stage) are J(x0) of this one, unless something wrote the state since.
  if (analysed_ && sys.state_version() == version_ && sys.time() == time_) return;
  factorise(sys, sys.evaluate_constraint_rows());
}

void Rattle::factorise(const pdyn::System& sys, const pdyn::ConstraintRows& rows) {
  const Index m = rows.rows();
  if (m == 0) return;
  if (!analysed_) {
    // The pattern of J W J^T: rows r and s couple through each particle
    // they share. Fixed for the run, as the constraints' patterns are.
    row_begin_ = rows.row_begin;
    particle_ = rows.particle;
    const Index entries = static_cast<Index>(particle_.size());
    std::vector<Index> row_of(static_cast<std::size_t>(entries));
    for (Index r = 0; r < m; ++r) {
      for (Index e = row_begin_[r]; e < row_begin_[r + 1]; ++e) row_of[e] = r;
    }
    std::vector<Index> order(static_cast<std::size_t>(entries));
    for (Index e = 0; e < entries; ++e) order[e] = e;
    std::stable_sort(order.begin(), order.end(),
                     [&](Index a, Index b) { return particle_[a] < particle_[b]; });
    std::vector<Eigen::Triplet<double>> triplets;
    for (std::size_t i = 0; i < order.size();) {
      std::size_t j = i;
      while (j < order.size() && particle_[order[j]] == particle_[order[i]]) ++j;
      for (std::size_t a = i; a < j; ++a) {
        for (std::size_t b = i; b < j; ++b) {
          pair_first_.push_back(order[a]);
          pair_second_.push_back(order[b]);
          triplets.emplace_back(row_of[order[a]], row_of[order[b]], 0.0);
        }
      }
      i = j;
    }
    a_.resize(m, m);
    a_.setFromTriplets(triplets.begin(), triplets.end());
    a_.makeCompressed();
    for (std::size_t k = 0; k < pair_first_.size(); ++k) {
      pair_slot_.push_back(static_cast<Index>(
          &a_.coeffRef(row_of[pair_first_[k]], row_of[pair_second_[k]]) - a_.valuePtr()));
    }
    for (Index r = 0; r < m; ++r) {
      diagonal_slot_.push_back(static_cast<Index>(&a_.coeffRef(r, r) - a_.valuePtr()));
    }
    active_.assign(static_cast<std::size_t>(m), 0);
  }
  jacobian_ = rows.jacobian;
  rate_ = rows.rate;
  fill_products(sys);
  double* values = a_.valuePtr();
  double largest = 0.0;
  for (Index r = 0; r < m; ++r) {
    double& d = values[diagonal_slot_[r]];
    active_[r] = d > 0.0 ? 1 : 0;
    largest = std::max(largest, d);
    if (d <= 0.0) d = 1.0;  // an identity row: its multiplier stays 0
  }
  if (!analysed_) {
    ldlt_.analyzePattern(a_);
    analysed_ = true;
  }
  // Once singular, the rows stay redundant (their pattern does not change):
  // later factorisations go straight to the shifted matrix.
  if (!singular_) {
    ldlt_.setShift(0.0);
    ldlt_.factorize(a_);
    singular_ = ldlt_.info() != Eigen::Success;
    const auto& order = ldlt_.permutationP().indices();
    const auto& pivots = ldlt_.vectorD();
    for (Index r = 0; r < m && !singular_; ++r) {
      singular_ = !(pivots(order(r)) > kSingularPivot * values[diagonal_slot_[r]]);
    }
  }
  if (singular_) {
    shift_ = kShift * largest;
    ldlt_.setShift(shift_);
    ldlt_.factorize(a_);
    if (ldlt_.info() != Eigen::Success) {
      throw pdyn::Error(
          "verlet (RATTLE): J W J^T + shift I could not be factorised (expected finite constraint "
          "Jacobians)");
    }
  }
}

void Rattle::apply(const Eigen::VectorXd& x, Eigen::VectorXd& y) const {
  y.noalias() = a_ * x;  // a_ holds both triangles
}

// For a nonsingular A the factor's solve; for a singular one
// (A + s I)^-1 A (A + s I)^-1, which maps A's null space (the redundant rows'
// self-stresses) to zero and its range onto itself, so conjugate gradients
// preconditioned by it stay in A's range: the minimum-norm solution, and
// a right-hand side's part outside the range (rows in conflict) is left in
// the residual rather than amplified by 1/s.
void Rattle::precondition(const Eigen::VectorXd& r, Eigen::VectorXd& z) {
  if (!singular_) {
    z = ldlt_.solve(r);
    return;
  }
  cg_t_ = ldlt_.solve(r);
  apply(cg_t_, z);
  cg_t_ = ldlt_.solve(z);
  z = cg_t_;
}

void Rattle::solve_min_norm(double goal) {
  precondition(rhs_, mu_);
  const double rzb = rhs_.dot(mu_);
  apply(mu_, cg_q_);
  cg_r_ = rhs_ - cg_q_;
  if (!(cg_r_.norm() > goal)) return;  // a nonsingular A: the factor's solve, as before
  precondition(cg_r_, cg_z_);
  cg_d_ = cg_z_;
  double rz = cg_r_.dot(cg_z_);
  for (Index it = 0; it < kMaxRefinements; ++it) {
    // Stop when the residual is small or its part in A's range is (rz is
    // its size in the preconditioner's norm): the rest lies outside.
    if (!(cg_r_.norm() > goal) || !(rz > kRangeResidual * kRangeResidual * rzb)) break;
    apply(cg_d_, cg_q_);
    const double dq = cg_d_.dot(cg_q_);
    if (!(dq > 0.0)) break;
    const double alpha = rz / dq;
    mu_ += alpha * cg_d_;
    cg_r_ -= alpha * cg_q_;
    precondition(cg_r_, cg_z_);
    const double rz_next = cg_r_.dot(cg_z_);
    cg_d_ = cg_z_ + (rz_next / rz) * cg_d_;
    rz = rz_next;
  }
}

double Rattle::largest_active(const Eigen::VectorXd& c) const {
  double largest = 0.0;
  for (Index r = 0; r < c.size(); ++r) {
    if (active_[r] != 0) largest = std::max(largest, std::abs(c(r)));
  }
  return largest;
}

void Rattle::project_positions(pdyn::System& sys, double h, pdyn::Matrix3X* half) {
  iterations_ = 0;
  if (sys.constraint_rows() == 0) return;
  auto x = sys.positions();
  auto v = sys.velocities();
  const double v_factor = (half != nullptr ? 2.0 : 1.0) / h;
  const Index m = sys.constraint_rows();
  double previous = std::numeric_limits<double>::infinity();
  bool projecting = false;
  double scale = 1.0;  // of the last correction, when projecting
  for (Index it = 0;; ++it) {
    const pdyn::ConstraintRows& rows = sys.evaluate_constraint_rows();
    const double error = largest_active(rows.value);
    if (error <= tolerance_) {
      iterations_ = it;
      factorise(sys, rows);  // J(x1) for the velocity stage
      return;
    }
    if (it == max_iterations_) {
      throw pdyn::Error(fmt::format(
          "verlet (RATTLE): a constraint is still off by {:.3g} after {} iterations (expected at "
          "most rattle_tolerance = {:.3g}: is the step too large for the constraints' motion, or "
          "are two constraints in conflict?)",
          error, it, tolerance_));
    }
    // A simplified Newton step that gains less than a factor 2 means that
    // RATTLE's equations have no solution near x along J(x0) (measured on a
    // cloth hung from a corner: Levenberg-Marquardt along J(x0) stalls at
    // |C| = 6e-9 m where a square of rods has sheared flat), or that it is
    // too far to reach: from here the step projects along the current
    // gradients, whose Gauss-Newton iteration converges quadratically.
    if (!projecting && error > 0.5 * previous) {
      projecting = true;
      ++projected_steps_;
    }
    if (projecting && error > previous && scale > kSmallestScale) {
      // Gauss-Newton overshot (a near-null direction of J W J^T, a taut
      // line's sideways motion): back to the last point, half the step.
      scale *= 0.5;
      for_each_correction(sys, [&](Index k, const pdyn::Vec3& d) {
        x.col(k) -= scale * d;
        v.col(k) -= (v_factor * scale) * d;
        if (half != nullptr) half->col(k) -= (scale / h) * d;
      });
      continue;
    }
    previous = error;
    scale = 1.0;
    if (projecting) factorise(sys, rows);  // J(x) W J(x)^T
    rhs_.resize(m);
    for (Index r = 0; r < m; ++r) rhs_(r) = active_[r] != 0 ? rows.value(r) : 0.0;
    solve_min_norm(kSolveGoal * rhs_.norm());
    require_finite_multipliers("position");
    // x <- x - W J^T mu: along the rows' gradients at the step's start (or
    // at x when projecting).
    for_each_correction(sys, [&](Index k, const pdyn::Vec3& d) {
      x.col(k) += d;
      v.col(k) += v_factor * d;
      if (half != nullptr) half->col(k) += d / h;
    });
  }
}

// A = J W J^T on its pattern: for each pair of entries on one particle,
// W_k times the two rows' gradients there.
void Rattle::fill_products(const pdyn::System& sys) {
  double* values = a_.valuePtr();
  std::fill(values, values + a_.nonZeros(), 0.0);
  for (std::size_t k = 0; k < pair_slot_.size(); ++k) {
    const Index e = pair_first_[k];
    values[pair_slot_[k]] +=
        sys.inverse_masses()(particle_[e]) * jacobian_.col(e).dot(jacobian_.col(pair_second_[k]));
  }
}

void Rattle::project_velocities(pdyn::System& sys) {
  const Index m = sys.constraint_rows();
  if (m == 0) return;
  auto v = sys.velocities();
  rhs_.resize(m);
  for (Index r = 0; r < m; ++r) {
    double cdot = rate_(r);
    for (Index e = row_begin_[r]; e < row_begin_[r + 1]; ++e)
      cdot += jacobian_.col(e).dot(v.col(particle_[e]));
    rhs_(r) = active_[r] != 0 ? cdot : 0.0;
  }
  solve_min_norm(kSolveGoal * rhs_.norm());
  require_finite_multipliers("velocity");
  for_each_correction(sys, [&](Index k, const pdyn::Vec3& d) { v.col(k) += d; });
}

void Rattle::require_finite_multipliers(const char* stage) const {
  if (mu_.allFinite()) return;
  throw pdyn::Error(fmt::format(
      "verlet (RATTLE): the {} stage produced a non-finite multiplier (expected independent "
      "constraints: are two constraints redundant or in conflict?)",
      stage));
}

}  // namespace pdyn_verlet
