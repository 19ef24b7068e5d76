// @NAME@'s own tests (GoogleTest): the plugin's objects are linked into this
// program, so its descriptor is at hand without loading a library.
//
// The first three tests hold for any constraint written from this template,
// whatever its geometry: keep them as they are when you change it. The
// conformance kit compares J, c_t and b with finite differences of C; the
// motion test lets particles move under gravity and the constraint force the
// kernel derives from C, J and b (Witkin's), and asserts that they stay on
// the constraint and, when it does not move, keep their energy. The last
// test is the bowl's own exact solution: replace it with your geometry's
// (see its TODO).
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <pdyn/conformance.hpp>
#include <pdyn/plugin.hpp>
#include <vector>

namespace {

const pdyn::PluginDescriptor& descriptor() { return *pdyn_plugin_descriptor(); }

// A state of the test's few particles, and the constraint's rows there with
// a dense Jacobian (rows x 3N): entry e of row r is the gradient by particle
// pattern.particle[e], e in [row_begin[r], row_begin[r + 1]).
struct Motion {
  pdyn::Matrix3X x, v;   // m, m/s
  Eigen::VectorXd mass;  // kg
  std::vector<std::uint8_t> fixed;
  double t = 0.0;  // s

  pdyn::ParticleView view() const {
    const auto n = x.cols();
    return pdyn::ParticleView{t, {x.data(), 3, n}, {v.data(), 3, n}, {mass.data(), n}, fixed};
  }
};

struct Rows {
  Eigen::VectorXd value, rate, bias;
  Eigen::MatrixXd jacobian;
};

Rows rows_at(const pdyn::Constraint& c, const pdyn::ConstraintPattern& pattern, const Motion& s) {
  pdyn::ConstraintValues out;
  out.value = Eigen::VectorXd::Zero(pattern.rows());
  out.rate = Eigen::VectorXd::Zero(pattern.rows());
  out.bias = Eigen::VectorXd::Zero(pattern.rows());
  out.jacobian = pdyn::Matrix3X::Zero(3, pattern.entries());
  c.evaluate(s.view(), out);
  Rows r{out.value, out.rate, out.bias, Eigen::MatrixXd::Zero(pattern.rows(), 3 * s.x.cols())};
  for (pdyn::Index row = 0; row < pattern.rows(); ++row) {
    for (pdyn::Index e = pattern.row_begin[row]; e < pattern.row_begin[row + 1]; ++e) {
      r.jacobian.block<1, 3>(row, 3 * pattern.particle[e]) += out.jacobian.col(e).transpose();
    }
  }
  return r;
}

constexpr double kG = 9.81;  // m/s^2, along -z

// Witkin's constrained accelerations with no feedback: a = W (Q + J^T
// lambda), J W J^T lambda = -b - J W Q, Q gravity, W the inverse masses.
pdyn::Matrix3X accelerations(const Rows& r, const Motion& s) {
  const auto n = s.x.cols();
  Eigen::VectorXd w(3 * n), q(3 * n);
  for (pdyn::Index i = 0; i < n; ++i) {
    w.segment<3>(3 * i).setConstant(1.0 / s.mass[i]);
    q.segment<3>(3 * i) = pdyn::Vec3(0.0, 0.0, -s.mass[i] * kG);
  }
  const Eigen::MatrixXd jw = r.jacobian * w.asDiagonal();
  const Eigen::VectorXd lambda = (jw * r.jacobian.transpose()).ldlt().solve(-r.bias - jw * q);
  const Eigen::VectorXd a = w.asDiagonal() * (q + r.jacobian.transpose() * lambda);
  return Eigen::Map<const pdyn::Matrix3X>(a.data(), 3, n);
}

double energy(const Motion& s) {  // J: kinetic and gravity's potential
  double e = 0.0;
  for (pdyn::Index i = 0; i < s.x.cols(); ++i) {
    e += s.mass[i] * (0.5 * s.v.col(i).squaredNorm() + kG * s.x(2, i));
  }
  return e;
}

}  // namespace

TEST(@NAME@, PassesTheConformanceKit) {
  const auto results = pdyn::conformance::run_checks(descriptor(), {.seed = 1});
  ASSERT_FALSE(results.empty());
  for (const auto& r : results) {
    EXPECT_NE(r.verdict, pdyn::conformance::Verdict::Fail) << r.name << ": " << r.detail;
  }
}

TEST(@NAME@, DescriptorNamesThisPlugin) { EXPECT_EQ(descriptor().name, "@NAME@"); }

// Four particles (the constraint gets the kit's default parameters: its
// required ones at their samples, an IndexList [0, 1, 3]) made where they
// start, so C = 0 there; their velocities made tangent (J v + c_t = 0).
// One second of rk4 at 1 ms under gravity and the constraint force: every
// |C| stays below 1e-9 m, and a constraint that does not move (c_t = 0)
// keeps the energy to 1e-9 of its size, as a force normal to the
// constraint does no work. Holds for any geometry whose rows are independent
// at these positions; a failure means J or b does not belong to C (or the
// bound is too tight for your geometry's curvature: a smaller step shows
// which, the drift of a correct b falls as h^4).
TEST(@NAME@, ParticlesStayOnTheConstraintUnderGravity) {
  constexpr pdyn::Index n = 4;
  constexpr double h = 1e-3, duration = 1.0;  // s
  Motion s;
  s.x.resize(3, n);
  s.v.resize(3, n);
  s.x << 0.31, -0.47, 0.12, 0.58, -0.22, 0.36, -0.15, 0.44, 0.27, 0.61, -0.33, 0.05;
  s.v << 0.4, -0.2, 0.3, -0.1, 0.5, 0.2, 0.3, 0.1, -0.4, 0.2, -0.3, 0.1;
  s.mass = Eigen::Vector4d(1.0, 0.5, 2.0, 1.5);
  s.fixed.assign(n, 0);
  const pdyn::Params params = pdyn::conformance::default_params(descriptor(), n);
  const auto c = descriptor().create_constraint(params, pdyn::SceneContext{s.view()});
  ASSERT_TRUE(c);
  const pdyn::ConstraintPattern pattern = c->pattern();

  // v -= W J^T (J W J^T)^-1 (J v + c_t): the nearest tangent velocity.
  Rows r = rows_at(*c, pattern, s);
  ASSERT_LE(r.value.cwiseAbs().maxCoeff(), 1e-12) << "C != 0 where the constraint was made";
  Eigen::VectorXd w(3 * n);
  for (pdyn::Index i = 0; i < n; ++i) w.segment<3>(3 * i).setConstant(1.0 / s.mass[i]);
  const Eigen::MatrixXd jw = r.jacobian * w.asDiagonal();
  Eigen::Map<Eigen::VectorXd> v(s.v.data(), 3 * n);
  const Eigen::VectorXd mu = (jw * r.jacobian.transpose()).ldlt().solve(r.jacobian * v + r.rate);
  v -= jw.transpose() * mu;

  const double e0 = energy(s);
  bool moves = false;
  double worst = 0.0;
  for (int step = 0; step < static_cast<int>(std::lround(duration / h)); ++step) {
    // rk4 on (x, v): k = (v, a) at the start, twice at the middle, at the end.
    const Motion s0 = s;
    pdyn::Matrix3X dx = pdyn::Matrix3X::Zero(3, n), dv = pdyn::Matrix3X::Zero(3, n);
    const double stage[4] = {0.0, 0.5, 0.5, 1.0}, weight[4] = {1.0, 2.0, 2.0, 1.0};
    pdyn::Matrix3X kx = s0.v, kv;
    for (int k = 0; k < 4; ++k) {
      Motion at = s0;
      if (k > 0) {
        at.x = s0.x + stage[k] * h * kx;
        at.v = s0.v + stage[k] * h * kv;
        at.t = s0.t + stage[k] * h;
      }
      const Rows rk = rows_at(*c, pattern, at);
      moves = moves || rk.rate.cwiseAbs().maxCoeff() > 0.0;
      kx = at.v;
      kv = accelerations(rk, at);
      dx += weight[k] * kx;
      dv += weight[k] * kv;
    }
    s.x = s0.x + (h / 6.0) * dx;
    s.v = s0.v + (h / 6.0) * dv;
    s.t = s0.t + h;
    worst = std::max(worst, rows_at(*c, pattern, s).value.cwiseAbs().maxCoeff());
  }
  EXPECT_LE(worst, 1e-9) << "max |C| over the run, m";
  if (!moves) {
    EXPECT_LE(std::abs(energy(s) - e0), 1e-9 * std::max(1.0, std::abs(e0))) << e0;
  }
}

// TODO(@NAME@): this test is the bowl's exact solution; when you change the
// geometry, replace it with yours. Put one particle on your constraint with
// a velocity along it for which you know the acceleration (a bead on a
// helix of pitch angle alpha, released at rest under gravity along its
// axis: g sin(alpha) along the helix; a bead moving along a circle at speed
// v: v^2 / R towards the centre), build the constraint with that geometry
// given explicitly, and assert the acceleration that the
// constraint force gives, a = W (Q + J^T lambda), against it to 1e-12.
//
// Here: one bead of mass m at radius r in the bowl of radius R (bottom at z
// = 0), moving along the horizontal circle at the angular speed w = sqrt(g
// / R), under gravity Q = (0, 0, -m g). With one row, Witkin's multiplier is
//   lambda = (-b - J W Q) / (J W J^T),   W = 1/m,
// and the acceleration a = W (Q + J^T lambda) must be the circle's
// centripetal one, (-w^2 r, 0, 0): no vertical part, so the bead keeps its
// height.
TEST(@NAME@, ConstraintForceKeepsACircularOrbit) {
  const double g = 9.81, m = 2.0, big_r = 1.5, r = 0.7;  // m/s^2, kg, m, m
  const double w = std::sqrt(g / big_r);                 // 1/s
  pdyn::Matrix3X x(3, 1), v(3, 1);
  x.col(0) = pdyn::Vec3(r, 0.0, r * r / (2.0 * big_r));
  v.col(0) = pdyn::Vec3(0.0, w * r, 0.0);
  const Eigen::VectorXd mass = Eigen::VectorXd::Constant(1, m);
  const std::vector<std::uint8_t> fixed(1, 0);
  const pdyn::ParticleView p{0.0, {x.data(), 3, 1}, {v.data(), 3, 1}, {mass.data(), 1}, fixed};

  pdyn::Params params = pdyn::conformance::sample_params(descriptor(), 4);
  params.set("ids", std::vector<pdyn::Index>{0});
  params.set("radius", big_r);
  params.set("bottom", 0.0);
  const auto c = descriptor().create_constraint(params, pdyn::SceneContext{p});
  const pdyn::ConstraintPattern pattern = c->pattern();
  ASSERT_EQ(pattern.rows(), 1);
  pdyn::ConstraintValues out;
  out.value = Eigen::VectorXd::Zero(1);
  out.rate = Eigen::VectorXd::Zero(1);
  out.bias = Eigen::VectorXd::Zero(1);
  out.jacobian = pdyn::Matrix3X::Zero(3, 1);
  c->evaluate(p, out);

  EXPECT_NEAR(out.value[0], 0.0, 1e-15);                    // on the bowl, m
  EXPECT_NEAR(out.bias[0], -w * w * r * r / big_r, 1e-12);  // -|v|^2 / R, m/s^2
  const pdyn::Vec3 j = out.jacobian.col(pattern.row_begin[0]);
  const pdyn::Vec3 q(0.0, 0.0, -m * g);  // N
  const double lambda = (-out.bias[0] - j.dot(q) / m) / (j.squaredNorm() / m);
  const pdyn::Vec3 a = (q + j * lambda) / m;  // m/s^2
  EXPECT_NEAR(a.x(), -w * w * r, 1e-12);
  EXPECT_NEAR(a.y(), 0.0, 1e-12);
  EXPECT_NEAR(a.z(), 0.0, 1e-12);
}
