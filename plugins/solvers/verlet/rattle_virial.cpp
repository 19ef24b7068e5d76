#include "rattle_virial.hpp"

#include <fmt/format.h>

#include <Eigen/SparseCore>
#include <Eigen/SparseLU>
#include <algorithm>
#include <cmath>
#include <limits>
#include <pdyn/constraint.hpp>
#include <pdyn/error.hpp>
#include <pdyn/thermo.hpp>
#include <utility>
#include <vector>

namespace pdyn_verlet {

namespace {

using pdyn::Index;

// Every constraint object evaluated at the positions `x` and time `t`,
// gathered in the order of System::evaluate_constraint_rows (scene order):
// the values C and the Jacobian J(x).
struct Trial {
  std::vector<pdyn::ConstraintValues> values;  // per object
  Eigen::VectorXd c;
  pdyn::Matrix3X jacobian;

  void evaluate(const pdyn::System& sys, const pdyn::Matrix3X& x, double t) {
    const pdyn::ParticleView now = sys.view();
    const pdyn::ParticleView at{t,          Eigen::Map<const pdyn::Matrix3X>(x.data(), 3, x.cols()),
                                now.v,      now.mass,
                                now.fixed,  now.domain,
                                now.radius, now.type};
    const auto& objects = sys.constraint_objects();
    values.resize(objects.size());
    Index row = 0, entry = 0;
    c.resize(sys.constraint_rows());
    for (std::size_t k = 0; k < objects.size(); ++k) {
      pdyn::ConstraintValues& v = values[k];
      if (v.value.size() == 0) {
        const pdyn::ConstraintPattern pat = objects[k].constraint->pattern();
        v.value = Eigen::VectorXd::Zero(pat.rows());
        v.jacobian = pdyn::Matrix3X::Zero(3, pat.entries());
      }
      v.rate = Eigen::VectorXd::Zero(v.value.size());
      v.bias = Eigen::VectorXd::Zero(v.value.size());
      objects[k].constraint->evaluate(at, v);
      c.segment(row, v.value.size()) = v.value;
      jacobian.conservativeResize(3, entry + v.jacobian.cols());
      jacobian.middleCols(entry, v.jacobian.cols()) = v.jacobian;
      row += v.value.size();
      entry += v.jacobian.cols();
    }
  }
};

// RATTLE's position stage from the state of `sys`, solved apart from it.
class PositionStage {
 public:
  PositionStage(const pdyn::System& sys, double h)
      : sys_(sys), h_(h), rows0_(sys.evaluate_constraint_rows()), w_(sys.inverse_masses()) {
    const Index m = rows0_.rows();
    const auto& rb = rows0_.row_begin;
    // Rows on fixed particles only cannot act (identity rows, as in rattle.cpp).
    active_.assign(static_cast<std::size_t>(m), 0);
    row_of_.resize(rows0_.particle.size());
    for (Index r = 0; r < m; ++r) {
      double d = 0.0;
      for (Index e = rb[r]; e < rb[r + 1]; ++e) {
        row_of_[e] = r;
        d += w_(rows0_.particle[e]) * rows0_.jacobian.col(e).squaredNorm();
        by_particle_.emplace_back(rows0_.particle[e], e);
      }
      active_[r] = d > 0.0 ? 1 : 0;
    }
    // Pairs of entries on one particle couple their rows in J(x) W J0^T.
    std::sort(by_particle_.begin(), by_particle_.end());
    // The unconstrained drift of velocity Verlet: x + h v + h^2/2 W f.
    const pdyn::ParticleView p = sys.view();
    const pdyn::Matrix3X& f = sys.forces();
    x_pred_ = p.x + h * p.v;
    for (Index k = 0; k < x_pred_.cols(); ++k) x_pred_.col(k) += (0.5 * h * h * w_(k)) * f.col(k);
    x_ = x_pred_;
    mu_ = Eigen::VectorXd::Zero(m);
  }

  // Newton's iteration until |C| no longer halves (rounding); the largest
  // |C| left.
  double solve() {
    constexpr int kMaxIterations = 50;
    double previous = std::numeric_limits<double>::infinity();
    for (int it = 0;; ++it) {
      const double error = residual();
      if (error == 0.0 || error > 0.5 * previous || it == kMaxIterations) return error;
      previous = error;
      newton_step();
    }
  }

  // Lambda = -2 mu / h^2, the multipliers as forces along J0.
  double virial() const {
    const Eigen::VectorXd lambda = (-2.0 / (h_ * h_)) * mu_;
    return pdyn::constraint_force_virial(sys_.view(), rows0_, lambda);
  }

 private:
  double residual() {
    trial_.evaluate(sys_, x_, sys_.time() + h_);
    const Index m = rows0_.rows();
    rhs_.resize(m);
    double error = 0.0;
    for (Index r = 0; r < m; ++r) {
      rhs_(r) = active_[r] != 0 ? trial_.c(r) : 0.0;
      error = std::max(error, std::abs(rhs_(r)));
    }
    return error;
  }

  // (J(x) W J0^T) dmu = C(x), then x = x_pred - W J0^T mu.
  void newton_step() {
    const Index m = rows0_.rows();
    triplets_.clear();
    for (std::size_t i = 0; i < by_particle_.size();) {
      std::size_t j = i;
      while (j < by_particle_.size() && by_particle_[j].first == by_particle_[i].first) ++j;
      const double wk = w_(by_particle_[i].first);
      for (std::size_t a = i; a < j && wk > 0.0; ++a) {
        for (std::size_t b = i; b < j; ++b) {
          const Index ea = by_particle_[a].second, eb = by_particle_[b].second;
          if (active_[row_of_[ea]] == 0 || active_[row_of_[eb]] == 0) continue;
          triplets_.emplace_back(row_of_[ea], row_of_[eb],
                                 wk * trial_.jacobian.col(ea).dot(rows0_.jacobian.col(eb)));
        }
      }
      i = j;
    }
    for (Index r = 0; r < m; ++r) {
      if (active_[r] == 0) triplets_.emplace_back(r, r, 1.0);
    }
    Eigen::SparseMatrix<double> a(m, m);
    a.setFromTriplets(triplets_.begin(), triplets_.end());
    a.makeCompressed();
    lu_.compute(a);
    if (lu_.info() != Eigen::Success) {
      throw pdyn::Error(
          "verlet (RATTLE): the constraint virial's J(x) W J0^T could not be factorised "
          "(expected independent constraints)");
    }
    const Eigen::VectorXd dmu = lu_.solve(rhs_);
    if (!dmu.allFinite()) {
      throw pdyn::Error("verlet (RATTLE): the constraint virial's multipliers are not finite");
    }
    mu_ += dmu;
    x_ = x_pred_;
    for (Index r = 0; r < m; ++r) {
      for (Index e = rows0_.row_begin[r]; e < rows0_.row_begin[r + 1]; ++e) {
        const Index k = rows0_.particle[e];
        x_.col(k) -= (w_(k) * mu_(r)) * rows0_.jacobian.col(e);
      }
    }
  }

  const pdyn::System& sys_;
  double h_;
  const pdyn::ConstraintRows rows0_;                  // J0 and the pattern at the state (a copy)
  const Eigen::VectorXd& w_;                          // inverse masses
  std::vector<char> active_;                          // per row
  std::vector<Index> row_of_;                         // per entry
  std::vector<std::pair<Index, Index>> by_particle_;  // (particle, entry), sorted
  pdyn::Matrix3X x_pred_, x_;
  Eigen::VectorXd mu_, rhs_;
  Trial trial_;
  std::vector<Eigen::Triplet<double>> triplets_;
  Eigen::SparseLU<Eigen::SparseMatrix<double>> lu_;
};

}  // namespace

double rattle_virial(const pdyn::System& sys, double h, double tolerance) {
  if (sys.constraint_rows() == 0) return 0.0;
  PositionStage stage(sys, h);
  const double error = stage.solve();
  if (!(error <= tolerance)) {
    throw pdyn::Error(fmt::format(
        "verlet (RATTLE): the constraint virial's position stage stopped with a constraint off "
        "by {:.3g} (expected at most rattle_tolerance = {:.3g})",
        error, tolerance));
  }
  return stage.virial();
}

}  // namespace pdyn_verlet
