#include "constraint_force.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "pdyn/error.hpp"

namespace pdyn {

void ConstraintForce::add(const Constraint& c, const std::string& label, Index n,
                          double compliance) {
  const ConstraintPattern pat = c.pattern();
  const Index rows = pat.rows();
  const Index entries = pat.entries();
  if (rows < 0 || pat.row_begin.front() != 0 || pat.row_begin.back() != entries ||
      !std::is_sorted(pat.row_begin.begin(), pat.row_begin.end())) {
    throw Error(
        fmt::format("{}: malformed constraint pattern (expected row_begin to rise from 0 "
                    "to the number of entries, {})",
                    label, entries));
  }
  for (Index r = 0; r < rows; ++r) {
    for (Index e = pat.row_begin[r]; e < pat.row_begin[r + 1]; ++e) {
      const Index k = pat.particle[e];
      if (k < 0 || k >= n) {
        throw Error(fmt::format("{}: constraint row {} names particle {} (expected 0 to {})", label,
                                r, k, n - 1));
      }
      for (Index e2 = pat.row_begin[r]; e2 < e; ++e2) {
        if (pat.particle[e2] == k) {
          throw Error(
              fmt::format("{}: constraint row {} names particle {} twice (expected "
                          "distinct particles per row)",
                          label, r, k));
        }
      }
    }
  }
  Block b;
  b.first_row = this->rows();
  b.first_entry = static_cast<Index>(slot_.size());
  b.values.value = Eigen::VectorXd::Zero(rows);
  b.values.rate = Eigen::VectorXd::Zero(rows);
  b.values.bias = Eigen::VectorXd::Zero(rows);
  b.values.jacobian = Matrix3X::Zero(3, entries);
  blocks_.push_back(std::move(b));
  for (Index r = 0; r < rows; ++r)
    rows_.row_begin.push_back(rows_.row_begin.back() + pat.row_begin[r + 1] - pat.row_begin[r]);
  rows_.particle.insert(rows_.particle.end(), pat.particle.begin(), pat.particle.end());
  for (const Index k : pat.particle) {
    if (static_cast<Index>(slot_of_.size()) <= k)
      slot_of_.resize(static_cast<std::size_t>(k) + 1, -1);
    if (slot_of_[k] < 0) {
      slot_of_[k] = static_cast<Index>(involved_.size());
      involved_.push_back(k);
    }
    slot_.push_back(slot_of_[k]);
    max_particle_ = std::max(max_particle_, k);
  }
  const Index m = this->rows() + rows;
  rows_.value.conservativeResize(m);
  rows_.rate.conservativeResize(m);
  rows_.bias.conservativeResize(m);
  rows_.compliance.conservativeResize(m);
  rows_.value.tail(rows).setZero();
  rows_.rate.tail(rows).setZero();
  rows_.bias.tail(rows).setZero();
  rows_.compliance.tail(rows).setConstant(compliance);
  rows_.jacobian.conservativeResize(3, static_cast<Index>(slot_.size()));
  rows_.jacobian.rightCols(entries).setZero();
  analysed_ = false;  // new rows: J W J^T's pattern changes
  singular_ = false;
}

ConstraintValues& ConstraintForce::prepare(std::size_t k) {
  ConstraintValues& v = blocks_[k].values;
  v.rate.setZero();
  v.bias.setZero();
  return v;
}

std::string ConstraintForce::gather(std::size_t k) {
  const Block& b = blocks_[k];
  const ConstraintValues& v = b.values;
  const Index rows =
      (k + 1 < blocks_.size() ? blocks_[k + 1].first_row : this->rows()) - b.first_row;
  const Index entries =
      (k + 1 < blocks_.size() ? blocks_[k + 1].first_entry : static_cast<Index>(slot_.size())) -
      b.first_entry;
  if (v.value.size() != rows || v.rate.size() != rows || v.bias.size() != rows ||
      v.jacobian.cols() != entries || v.jacobian.rows() != 3) {
    return fmt::format(
        "evaluate resized its values (expected {} rows and {} Jacobian entries, as "
        "its pattern says)",
        rows, entries);
  }
  for (Index r = 0; r < rows; ++r) {
    if (!std::isfinite(v.value(r)) || !std::isfinite(v.rate(r)) || !std::isfinite(v.bias(r))) {
      return fmt::format("produced a non-finite value in row {}: C = {}, c_t = {}, b = {}", r,
                         v.value(r), v.rate(r), v.bias(r));
    }
  }
  if (!v.jacobian.allFinite()) {
    Index e = 0;
    while (v.jacobian.col(e).allFinite()) ++e;
    return fmt::format("produced a non-finite Jacobian entry {}: [{}, {}, {}]", e, v.jacobian(0, e),
                       v.jacobian(1, e), v.jacobian(2, e));
  }
  rows_.value.segment(b.first_row, rows) = v.value;
  rows_.rate.segment(b.first_row, rows) = v.rate;
  rows_.bias.segment(b.first_row, rows) = v.bias;
  rows_.jacobian.middleCols(b.first_entry, entries) = v.jacobian;
  return {};
}

double ConstraintForce::max_error() const {
  return rows() == 0 ? 0.0 : rows_.value.cwiseAbs().maxCoeff();
}

// out = J W J^T lambda, through u = W J^T lambda on the involved particles.
void ConstraintForce::apply(const Eigen::VectorXd& lambda, Eigen::VectorXd& out) {
  const Index m = rows();
  u_.setZero();
  for (Index r = 0; r < m; ++r) {
    for (Index e = rows_.row_begin[r]; e < rows_.row_begin[r + 1]; ++e)
      u_.col(slot_[e]) += rows_.jacobian.col(e) * lambda(r);
  }
  for (Index s = 0; s < u_.cols(); ++s) u_.col(s) *= w_slot_(s);
  for (Index r = 0; r < m; ++r) {
    double y = 0.0;
    for (Index e = rows_.row_begin[r]; e < rows_.row_begin[r + 1]; ++e)
      y += rows_.jacobian.col(e).dot(u_.col(slot_[e]));
    out(r) = diag_(r) > 0.0 ? y : 0.0;
  }
}

void ConstraintForce::analyse() {
  // Rows r and s couple through each particle they share (slot).
  const Index m = rows();
  const Index entries = static_cast<Index>(slot_.size());
  std::vector<Index> row_of(static_cast<std::size_t>(entries));
  for (Index r = 0; r < m; ++r) {
    for (Index e = rows_.row_begin[r]; e < rows_.row_begin[r + 1]; ++e) row_of[e] = r;
  }
  std::vector<Index> order(static_cast<std::size_t>(entries));
  for (Index e = 0; e < entries; ++e) order[e] = e;
  std::stable_sort(order.begin(), order.end(),
                   [&](Index a, Index b) { return slot_[a] < slot_[b]; });
  pair_first_.clear();
  pair_second_.clear();
  pair_slot_.clear();
  diagonal_slot_.clear();
  std::vector<Eigen::Triplet<double>> triplets;
  for (std::size_t i = 0; i < order.size();) {
    std::size_t j = i;
    while (j < order.size() && slot_[order[j]] == slot_[order[i]]) ++j;
    for (std::size_t a = i; a < j; ++a) {
      for (std::size_t b = i; b < j; ++b) {
        pair_first_.push_back(order[a]);
        pair_second_.push_back(order[b]);
        triplets.emplace_back(row_of[order[a]], row_of[order[b]], 0.0);
      }
    }
    i = j;
  }
  for (Index r = 0; r < m; ++r) triplets.emplace_back(r, r, 0.0);  // rows without entries
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
  ldlt_.analyzePattern(a_);
  analysed_ = true;
  singular_ = false;
}

// Redundant rows (a triangle of rods and a fourth on one of its edges, a
// cloth of structural, shear and bend rods) make A singular: a pivot of its
// LDL^T then falls to rounding, ~1e-16 of its row's diagonal. A + s I is
// then factorised instead, s = 1e-14 of the largest diagonal, and stays so
// while the rows are the same (redundancy is structural).
void ConstraintForce::factorise() {
  if (!analysed_) analyse();
  const Index m = rows();
  double* values = a_.valuePtr();
  std::fill(values, values + a_.nonZeros(), 0.0);
  for (std::size_t k = 0; k < pair_slot_.size(); ++k) {
    const Index e = pair_first_[k];
    values[pair_slot_[k]] +=
        w_slot_(slot_[e]) * rows_.jacobian.col(e).dot(rows_.jacobian.col(pair_second_[k]));
  }
  double largest = 0.0;
  for (Index r = 0; r < m; ++r) {
    double& d = values[diagonal_slot_[r]];
    largest = std::max(largest, d);
    if (!(diag_(r) > 0.0)) d = 1.0;  // cannot act: an identity row, lambda 0
  }
  if (!singular_) {
    ldlt_.setShift(0.0);
    ldlt_.factorize(a_);
    singular_ = ldlt_.info() != Eigen::Success;
    const auto& order = ldlt_.permutationP().indices();
    const auto& pivots = ldlt_.vectorD();
    for (Index r = 0; r < m && !singular_; ++r) {
      singular_ = !(pivots(order(r)) > 1e-10 * values[diagonal_slot_[r]]);
    }
  }
  if (singular_) {
    ldlt_.setShift(1e-14 * largest);
    ldlt_.factorize(a_);
  }
}

void ConstraintForce::precondition(const Eigen::VectorXd& r, Eigen::VectorXd& z) {
  z = ldlt_.solve(r);
  if (singular_) {
    t_.noalias() = a_ * z;
    z = ldlt_.solve(t_);
  }
  for (Index k = 0; k < z.size(); ++k) {
    if (!(diag_(k) > 0.0)) z(k) = 0.0;
  }
}

// Witkin's constraint force (SIGGRAPH '97 notes "Constrained Dynamics",
// eq. for lambda): with the accelerations a = W (f + J^T lambda), requiring
// Cddot = J a + b = -ks C - kd Cdot gives
//   J W J^T lambda = -b - J W f - ks C - kd Cdot.
// J W J^T is symmetric positive semi-definite; conjugate gradients solve it,
// preconditioned by its sparse LDL^T (factorised at every evaluation, its
// pattern analysed once): one iteration when it is nonsingular, where
// Jacobi's preconditioner took hundreds on a cloth (7.4 us per row per step,
// issue 42). A row whose particles are all fixed (W = 0) has a zero diagonal
// and cannot act: its lambda stays 0. Redundant rows make the matrix
// singular but the system consistent: the preconditioner then keeps CG in
// A's range, so lambda is the minimum-norm solution. Conflicting rows leave
// a residual outside the range, which no iteration reduces: CG stops when
// the part inside is solved. Each solve starts from lambda = 0 and nothing
// is carried between evaluations, so a run gives the same bits whatever
// happened before it (a resume included).
void ConstraintForce::add_force(const ParticleView& p, const Eigen::VectorXd& w,
                                const ConstraintFeedback& fb, Eigen::Ref<Matrix3X> f) {
  const Index m = rows();
  if (m == 0) return;
  const Index slots = static_cast<Index>(involved_.size());
  w_slot_.resize(slots);
  for (Index s = 0; s < slots; ++s) w_slot_(s) = w(involved_[s]);
  diag_.resize(m);
  rhs_.resize(m);
  u_.resize(3, slots);
  double scale2 = 0.0;  // the size of the terms that cancel in rhs, for the stopping test
  for (Index r = 0; r < m; ++r) {
    double d = 0.0, jwf = 0.0, jv = 0.0;
    for (Index e = rows_.row_begin[r]; e < rows_.row_begin[r + 1]; ++e) {
      const Index s = slot_[e];
      const auto j = rows_.jacobian.col(e);
      d += w_slot_(s) * j.squaredNorm();
      jwf += w_slot_(s) * j.dot(f.col(involved_[s]));
      jv += j.dot(p.v.col(involved_[s]));
    }
    const double cdot = jv + rows_.rate(r);
    diag_(r) = d;
    rhs_(r) = d > 0.0 ? -rows_.bias(r) - jwf - fb.ks * rows_.value(r) - fb.kd * cdot : 0.0;
    const double size = std::abs(rows_.bias(r)) + std::abs(jwf) + std::abs(fb.ks * rows_.value(r)) +
                        std::abs(fb.kd * cdot);
    if (d > 0.0) scale2 += size * size;
  }
  lambda_ = Eigen::VectorXd::Zero(m);
  const double goal = fb.tolerance * std::sqrt(scale2);
  if (rhs_.norm() > goal) {
    factorise();
    r_ = rhs_;
    z_.resize(m);
    precondition(r_, z_);
    d_ = z_;
    q_.resize(m);
    double rz = r_.dot(z_);
    const double rz0 = rz;
    const Index limit = fb.max_iterations > 0 ? fb.max_iterations : 10 * m + 100;
    Index it = 0;
    for (; it < limit; ++it) {
      // The residual's part in A's range solved to rounding (rz is its size
      // in the preconditioner's norm): the rest is outside, nothing to gain.
      if (!(rz > 1e-26 * rz0)) break;
      apply(d_, q_);
      const double dq = d_.dot(q_);
      if (!(dq > 0.0)) break;  // d in the null space: nothing more to gain
      const double alpha = rz / dq;
      lambda_ += alpha * d_;
      r_ -= alpha * q_;
      if (r_.norm() <= goal) break;
      precondition(r_, z_);
      const double rz_next = r_.dot(z_);
      d_ = z_ + (rz_next / rz) * d_;
      rz = rz_next;
    }
    if (!(r_.norm() <= goal)) {
      throw Error(fmt::format(
          "constraints: the constraint force's conjugate gradients stopped after {} iterations "
          "at a residual {:.3g} times the right-hand side's size (expected {:.3g}: are two "
          "constraints in conflict, e.g. a particle pinned to two points?)",
          it, r_.norm() / std::sqrt(scale2), fb.tolerance));
    }
  }
  for (Index r = 0; r < m; ++r) {
    for (Index e = rows_.row_begin[r]; e < rows_.row_begin[r + 1]; ++e) {
      f.col(involved_[slot_[e]]) += rows_.jacobian.col(e) * lambda_(r);
    }
  }
}

}  // namespace pdyn
