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

}  // namespace

double rattle_virial(const pdyn::System& sys, double h, double tolerance) {
  const Index m = sys.constraint_rows();
  if (m == 0) return 0.0;
  // J0 and the pattern at the state itself (copied: the trial evaluations
  // below do not touch the System's gathered rows, but a copy is plain).
  const pdyn::ConstraintRows rows0 = sys.evaluate_constraint_rows();
  const Eigen::VectorXd& w = sys.inverse_masses();
  const auto& rb = rows0.row_begin;
  const auto& particle = rows0.particle;
  // Rows on fixed particles only cannot act (identity rows, as in rattle.cpp).
  std::vector<char> active(static_cast<std::size_t>(m), 0);
  for (Index r = 0; r < m; ++r) {
    double d = 0.0;
    for (Index e = rb[r]; e < rb[r + 1]; ++e)
      d += w(particle[e]) * rows0.jacobian.col(e).squaredNorm();
    active[r] = d > 0.0 ? 1 : 0;
  }
  // The unconstrained drift of velocity Verlet from this state.
  const pdyn::ParticleView p = sys.view();
  pdyn::Matrix3X x_pred = p.x + h * p.v;
  const pdyn::Matrix3X& f = sys.forces();
  for (Index k = 0; k < x_pred.cols(); ++k) x_pred.col(k) += (0.5 * h * h * w(k)) * f.col(k);

  Eigen::VectorXd mu = Eigen::VectorXd::Zero(m);
  pdyn::Matrix3X x = x_pred;
  Trial trial;
  Eigen::SparseLU<Eigen::SparseMatrix<double>> lu;
  std::vector<Eigen::Triplet<double>> triplets;
  // Pairs of entries on one particle couple their rows (J(x) W J0^T).
  std::vector<std::pair<Index, Index>> by_particle;
  for (Index r = 0; r < m; ++r) {
    for (Index e = rb[r]; e < rb[r + 1]; ++e) by_particle.emplace_back(particle[e], e);
  }
  std::sort(by_particle.begin(), by_particle.end());
  std::vector<Index> row_of(particle.size());
  for (Index r = 0; r < m; ++r) {
    for (Index e = rb[r]; e < rb[r + 1]; ++e) row_of[e] = r;
  }
  double previous = std::numeric_limits<double>::infinity(), error = 0.0;
  constexpr int kMaxIterations = 50;
  for (int it = 0;; ++it) {
    trial.evaluate(sys, x, p.t + h);
    error = 0.0;
    Eigen::VectorXd rhs(m);
    for (Index r = 0; r < m; ++r) {
      rhs(r) = active[r] != 0 ? trial.c(r) : 0.0;
      error = std::max(error, std::abs(rhs(r)));
    }
    // Newton converges quadratically down to rounding; stop where it no
    // longer halves the error.
    if (error == 0.0 || error > 0.5 * previous || it == kMaxIterations) break;
    previous = error;
    triplets.clear();
    for (std::size_t i = 0; i < by_particle.size();) {
      std::size_t j = i;
      while (j < by_particle.size() && by_particle[j].first == by_particle[i].first) ++j;
      const double wk = w(by_particle[i].first);
      for (std::size_t a = i; a < j && wk > 0.0; ++a) {
        for (std::size_t b = i; b < j; ++b) {
          const Index ea = by_particle[a].second, eb = by_particle[b].second;
          if (active[row_of[ea]] == 0 || active[row_of[eb]] == 0) continue;
          triplets.emplace_back(row_of[ea], row_of[eb],
                                wk * trial.jacobian.col(ea).dot(rows0.jacobian.col(eb)));
        }
      }
      i = j;
    }
    for (Index r = 0; r < m; ++r) {
      if (active[r] == 0) triplets.emplace_back(r, r, 1.0);
    }
    Eigen::SparseMatrix<double> a(m, m);
    a.setFromTriplets(triplets.begin(), triplets.end());
    a.makeCompressed();
    lu.compute(a);
    if (lu.info() != Eigen::Success) {
      throw pdyn::Error(
          "verlet (RATTLE): the constraint virial's J(x) W J0^T could not be factorised "
          "(expected independent constraints)");
    }
    const Eigen::VectorXd dmu = lu.solve(rhs);
    if (!dmu.allFinite()) {
      throw pdyn::Error("verlet (RATTLE): the constraint virial's multipliers are not finite");
    }
    mu += dmu;
    x = x_pred;
    for (Index r = 0; r < m; ++r) {
      for (Index e = rb[r]; e < rb[r + 1]; ++e) {
        const Index k = particle[e];
        x.col(k) -= (w(k) * mu(r)) * rows0.jacobian.col(e);
      }
    }
  }
  if (!(error <= tolerance)) {
    throw pdyn::Error(fmt::format(
        "verlet (RATTLE): the constraint virial's position stage stopped with a constraint off "
        "by {:.3g} (expected at most rattle_tolerance = {:.3g})",
        error, tolerance));
  }
  const Eigen::VectorXd lambda = (-2.0 / (h * h)) * mu;
  return pdyn::constraint_force_virial(p, rows0, lambda);
}

}  // namespace pdyn_verlet
