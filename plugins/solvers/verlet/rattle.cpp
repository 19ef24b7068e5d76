#include "rattle.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <pdyn/error.hpp>

namespace pdyn_verlet {

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
  fill_products(sys, jacobian_, a_);
  double* values = a_.valuePtr();
  for (Index r = 0; r < m; ++r) {
    double& d = values[diagonal_slot_[r]];
    active_[r] = d > 0.0 ? 1 : 0;
    if (d <= 0.0) d = 1.0;  // an identity row: its multiplier stays 0
  }
  if (!analysed_) {
    ldlt_.analyzePattern(a_);
    analysed_ = true;
  }
  ldlt_.factorize(a_);
  if (ldlt_.info() != Eigen::Success) {
    throw pdyn::Error(
        "verlet (RATTLE): J W J^T could not be factorised (expected independent constraints: "
        "are two constraints redundant or in conflict?)");
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
  bool newton = false;
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
    rhs_.resize(m);
    for (Index r = 0; r < m; ++r) rhs_(r) = active_[r] != 0 ? rows.value(r) : 0.0;
    newton = newton || error > 0.25 * previous;
    previous = error;
    if (newton) {
      factorise_newton(sys, rows);
      mu_ = lu_.solve(rhs_);
    } else {
      mu_ = ldlt_.solve(rhs_);
    }
    require_finite_multipliers("position");
    // x <- x - W J0^T mu: along the rows' gradients at the step's start.
    for_each_correction(sys, [&](Index k, const pdyn::Vec3& d) {
      x.col(k) += d;
      v.col(k) += v_factor * d;
      if (half != nullptr) half->col(k) += d / h;
    });
  }
}

// target = left W J0^T on J W J^T's pattern: for each pair of entries on
// one particle, W_k times row r's gradient in `left` against row s's at the
// step's start (jacobian_).
void Rattle::fill_products(const pdyn::System& sys, const pdyn::Matrix3X& left,
                           Eigen::SparseMatrix<double>& target) const {
  double* values = target.valuePtr();
  std::fill(values, values + target.nonZeros(), 0.0);
  for (std::size_t k = 0; k < pair_slot_.size(); ++k) {
    const Index e = pair_first_[k];
    values[pair_slot_[k]] +=
        sys.inverse_masses()(particle_[e]) * left.col(e).dot(jacobian_.col(pair_second_[k]));
  }
}

void Rattle::factorise_newton(const pdyn::System& sys, const pdyn::ConstraintRows& rows) {
  // Same pattern as J W J^T: the pairs of entries on one particle, row r's
  // gradient now against row s's at the step's start.
  if (newton_.rows() == 0) newton_ = a_;
  fill_products(sys, rows.jacobian, newton_);
  double* values = newton_.valuePtr();
  for (Index r = 0; r < rows.rows(); ++r) {
    if (active_[r] == 0) values[diagonal_slot_[r]] = 1.0;
  }
  if (!lu_analysed_) {
    lu_.analyzePattern(newton_);
    lu_analysed_ = true;
  }
  lu_.factorize(newton_);
  if (lu_.info() != Eigen::Success) {
    throw pdyn::Error(
        "verlet (RATTLE): J(x) W J0^T could not be factorised (expected independent "
        "constraints: are two constraints redundant or in conflict?)");
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
  mu_ = ldlt_.solve(rhs_);
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
