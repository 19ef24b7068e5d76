// xpbd: extended position-based dynamics (Macklin, Muller & Chentanez 2016,
// "XPBD: Position-Based Simulation of Compliant Constrained Dynamics", MIG
// '16) with the substepping of Macklin, Storey, Lu, Terdiman, Chentanez,
// Jeschke & Muller 2019 ("Small Steps in Physics Simulation", SCA '19).
//
// A step of h is n substeps of h_s = h / n. Each substep, from x, v at t:
//
//   v  += h_s a(t, x, v)            the applied forces (gravity, drag, ...)
//   x_p = x;  x += h_s v;  t += h_s  the prediction (symplectic Euler)
//   lambda = 0; per iteration, per constraint row r (Gauss-Seidel):
//     d lambda_r = (-C_r - alpha~_r lambda_r) / (sum_k w_k |grad_k C_r|^2 + alpha~_r)
//     x_k += w_k grad_k C_r d lambda_r,   lambda_r += d lambda_r
//   v = (x - x_p) / h_s
//
// with w the inverse masses and alpha~ = alpha / h_s^2 (eq. 18 of the 2016
// paper). alpha, the scene's `compliance` of each constraint, is the inverse
// stiffness: the constraint then behaves as a spring of stiffness 1/alpha
// whatever h_s and the iteration count, and alpha = 0 is rigid. One
// iteration per substep is the 2019 paper's recommendation: many small
// substeps converge faster than many iterations of one large step, and the
// damping that too few iterations cause falls with h_s.
//
// The rows are evaluated all at once (pdyn/constraint.hpp: a plugin reports
// every row of its object together), so within one Gauss-Seidel sweep each
// row sees the corrections of the rows before it through its linearisation,
// C_r + sum_k grad_k C_r . dx_k, rather than by evaluating C again: the
// sweep is Gauss-Seidel on the linearised system (eq. 12 of the 2016 paper),
// and the next iteration or substep evaluates C afresh.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <pdyn/constraint.hpp>
#include <pdyn/constraint_solver.hpp>
#include <pdyn/plugin.hpp>
#include <pdyn/system.hpp>

namespace {

using pdyn::Index;

class Xpbd final : public pdyn::Solver, public pdyn::ConstraintSolver {
 public:
  Xpbd(Index substeps, Index iterations) : substeps_(substeps), iterations_(iterations) {}

  bool enforces_constraints() const noexcept override { return true; }
  bool honours_compliance() const noexcept override { return true; }

  void step(pdyn::System& sys, double h) override {
    const Index n = sys.size();
    const double hs = h / static_cast<double>(substeps_);
    const double t0 = sys.time();
    previous_.resize(3, n);
    if (delta_.cols() != n) delta_.setZero(3, n);
    for (Index s = 0; s < substeps_; ++s) {
      const pdyn::Matrix3X& a = sys.compute_accelerations();
      auto x = sys.positions();
      auto v = sys.velocities();
      v += hs * a;  // zero for fixed particles: they stay put
      previous_ = x;
      x += hs * v;
      // The substep's end time, computed rather than accumulated.
      sys.set_time(t0 + h * static_cast<double>(s + 1) / static_cast<double>(substeps_));
      if (sys.constraint_rows() > 0) project(sys, hs);
      auto x1 = sys.positions();
      auto v1 = sys.velocities();
      v1 = (x1 - previous_) / hs;
    }
  }

 private:
  void project(pdyn::System& sys, double hs) {
    const Index m = sys.constraint_rows();
    const Eigen::VectorXd& weight = sys.inverse_masses();  // 0 for fixed particles
    lambda_.setZero(m);
    for (Index it = 0; it < iterations_; ++it) {
      const pdyn::ConstraintRows& rows = sys.evaluate_constraint_rows();
      for (Index r = 0; r < m; ++r) {
        const double alpha = rows.compliance(r) / (hs * hs);
        double c = rows.value(r), denominator = alpha;
        for (Index e = rows.row_begin[r]; e < rows.row_begin[r + 1]; ++e) {
          const Index k = rows.particle[e];
          c += rows.jacobian.col(e).dot(delta_.col(k));
          denominator += weight(k) * rows.jacobian.col(e).squaredNorm();
        }
        if (!(denominator > 0.0)) continue;  // every particle fixed, or no gradient
        const double dlambda = (-c - alpha * lambda_(r)) / denominator;
        lambda_(r) += dlambda;
        for (Index e = rows.row_begin[r]; e < rows.row_begin[r + 1]; ++e) {
          const Index k = rows.particle[e];
          delta_.col(k) += (weight(k) * dlambda) * rows.jacobian.col(e);
        }
      }
      // Apply the sweep's displacements and clear them where they were set.
      auto x = sys.positions();
      for (const Index k : rows.particle) {
        x.col(k) += delta_.col(k);
        delta_.col(k).setZero();
      }
    }
  }

  Index substeps_, iterations_;
  pdyn::Matrix3X previous_;  // x at the substep's start
  pdyn::Matrix3X delta_;     // one sweep's displacements, zero outside it
  Eigen::VectorXd lambda_;   // per row: the substep's accumulated multiplier (N s^2 per unit)
};

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Solver;
  d.name = "xpbd";
  d.version = "1.0.0";
  d.description =
      "XPBD with small steps: substeps of symplectic Euler, each projecting the positions onto "
      "the constraints with their compliance; order 1";
  d.solver_traits.order = 1;
  d.solver_traits.symplectic = false;
  d.params = {
      pdyn::param::integer("substeps", 10, "substeps per step (Macklin et al. 2019)").at_least(1),
      pdyn::param::integer("iterations", 1, "Gauss-Seidel sweeps over the constraints per substep")
          .at_least(1)};
  d.create_solver = [](const pdyn::Params& p, const pdyn::SceneContext&) {
    return std::make_unique<Xpbd>(p.integer("substeps"), p.integer("iterations"));
  };
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
