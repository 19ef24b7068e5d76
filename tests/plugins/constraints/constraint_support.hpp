// Helpers shared by the constraint plugins' tests: a constraint object's
// values at the system's state, its Jacobian as a dense matrix, the same by
// central differences of C, and C's first and second derivatives along the
// unaccelerated motion x(s) = x + v s, t(s) = t + s, which are J v + c_t
// and the bias b (pdyn/constraint.hpp).
#pragma once

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <limits>
#include <string>

#include "pdyn/constraint.hpp"
#include "pdyn/system.hpp"
#include "support/test_support.hpp"

namespace pdyn::test {

/// The constraint object `index` of a loaded scene.
inline const Constraint& ConstraintOf(const Scene& scene, std::size_t index = 0) {
  return *scene.system->constraint_objects().at(index).constraint;
}

/// What `c` writes at the system's state. Every member starts as NaN, so
/// that a value the plugin leaves unwritten shows.
inline ConstraintValues EvaluateAt(const Constraint& c, const System& sys) {
  const ConstraintPattern pattern = c.pattern();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  ConstraintValues out;
  out.value = Eigen::VectorXd::Constant(pattern.rows(), nan);
  out.rate = Eigen::VectorXd::Constant(pattern.rows(), nan);
  out.bias = Eigen::VectorXd::Constant(pattern.rows(), nan);
  out.jacobian = Matrix3X::Constant(3, pattern.entries(), nan);
  c.evaluate(sys.view(), out);
  return out;
}

/// The reported Jacobian as a dense rows x 3N matrix (unit/m).
inline Eigen::MatrixXd DenseJacobian(const Constraint& c, const ConstraintValues& values, Index n) {
  const ConstraintPattern pattern = c.pattern();
  Eigen::MatrixXd j = Eigen::MatrixXd::Zero(pattern.rows(), 3 * n);
  for (Index r = 0; r < pattern.rows(); ++r) {
    for (Index e = pattern.row_begin[static_cast<std::size_t>(r)];
         e < pattern.row_begin[static_cast<std::size_t>(r) + 1]; ++e) {
      const Index k = pattern.particle[static_cast<std::size_t>(e)];
      j.block<1, 3>(r, 3 * k) += values.jacobian.col(e).transpose();
    }
  }
  return j;
}

/// dC/dx by central differences of C, step `h` (m) in every coordinate.
inline Eigen::MatrixXd JacobianByDifferences(const Constraint& c, System& sys, double h) {
  Eigen::MatrixXd j(c.pattern().rows(), 3 * sys.size());
  for (Index i = 0; i < sys.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      const double saved = sys.positions()(k, i);
      sys.positions()(k, i) = saved + h;
      const Eigen::VectorXd up = EvaluateAt(c, sys).value;
      sys.positions()(k, i) = saved - h;
      const Eigen::VectorXd down = EvaluateAt(c, sys).value;
      sys.positions()(k, i) = saved;
      j.col(3 * i + k) = (up - down) / (2.0 * h);
    }
  }
  return j;
}

/// dC/ds and d2C/ds2 along x(s) = x + v s, t(s) = t + s, by five-point
/// central differences of step `h` (s): J v + c_t and b, since a = 0.
struct AlongMotion {
  Eigen::VectorXd rate, acceleration;
};
inline AlongMotion DerivativesAlongMotion(const Constraint& c, System& sys, double h) {
  const Matrix3X x = sys.positions();
  const Matrix3X v = sys.velocities();
  const double t = sys.time();
  auto at = [&](double s) {
    sys.positions() = x + s * v;
    sys.set_time(t + s);
    return EvaluateAt(c, sys).value;
  };
  const Eigen::VectorXd m2 = at(-2 * h), m1 = at(-h), c0 = at(0), p1 = at(h), p2 = at(2 * h);
  sys.positions() = x;
  sys.set_time(t);
  return {(m2 - 8 * m1 + 8 * p1 - p2) / (12 * h),
          (-m2 + 16 * m1 - 30 * c0 + 16 * p1 - p2) / (12 * h * h)};
}

/// A 3 x N matrix (velocities) as the 3N-vector the Jacobian multiplies.
inline Eigen::VectorXd Stacked(const Matrix3X& m) {
  return Eigen::Map<const Eigen::VectorXd>(m.data(), m.size());
}

/// Largest |a - b| over two vectors or matrices of the same shape.
template <class A, class B>
double MaxDifference(const A& a, const B& b) {
  return (a - b).cwiseAbs().maxCoeff();
}

/// At the system's state: every value finite, J against central differences
/// of C (step 1e-6 m), J v + c_t against C's rate along the motion (to 1e-8,
/// relative beyond 1) and b against its second derivative (step 1e-3 s, to
/// 1e-6 relative). Returns
/// the values there.
inline ConstraintValues ExpectDerivativesOfC(const Constraint& c, System& sys) {
  const ConstraintValues v = EvaluateAt(c, sys);
  EXPECT_TRUE(v.value.allFinite() && v.rate.allFinite() && v.bias.allFinite() &&
              v.jacobian.allFinite());
  const Eigen::MatrixXd j = DenseJacobian(c, v, sys.size());
  EXPECT_LE(MaxDifference(j, JacobianByDifferences(c, sys, 1e-6)), 1e-8) << "J = dC/dx";
  const AlongMotion m = DerivativesAlongMotion(c, sys, 1e-3);
  // Central differences of step h err by h^2/6 times C's third derivative,
  // which an angle turning at a few rad/s makes larger than a length's:
  // relative beyond 1.
  EXPECT_LE(MaxDifference(m.rate, j * Stacked(sys.velocities()) + v.rate),
            1e-8 * std::max(1.0, m.rate.cwiseAbs().maxCoeff()))
      << "Cdot = J v + c_t";
  EXPECT_LE(MaxDifference(m.acceleration, v.bias),
            1e-6 * std::max(1.0, v.bias.cwiseAbs().maxCoeff()))
      << "b = Cddot at a = 0";
  return v;
}

}  // namespace pdyn::test
