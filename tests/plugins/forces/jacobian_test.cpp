// The analytic Jacobians of spring, drag and gravity against central finite
// differences of their add_forces(): column k of df/dx is
// [f(x + e u_k) - f(x - e u_k)] / 2e, likewise for v. They must agree to a
// relative 1e-6 (of the largest entry) wherever the force reports its exact
// derivative; the spring's two documented departures (geometric stiffness
// clamped under compression, damping's position derivative left out) are
// checked for what they are instead.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <iostream>
#include <random>

#include "plugins/forces/force_support.hpp"
#include "support/test_support.hpp"

namespace pdyn {
namespace {

using Dense = Eigen::MatrixXd;
using test::DenseSink;

struct State {
  double t = 0.0;
  Matrix3X x, v;
  Eigen::VectorXd mass;
  std::vector<std::uint8_t> fixed;
  ParticleView view() const {
    return ParticleView{t, Eigen::Map<const Matrix3X>(x.data(), 3, x.cols()),
                        Eigen::Map<const Matrix3X>(v.data(), 3, v.cols()),
                        Eigen::Map<const Eigen::VectorXd>(mass.data(), mass.size()),
                        std::span<const std::uint8_t>(fixed.data(), fixed.size())};
  }
};

Eigen::VectorXd Forces(Force& force, const State& s) {
  Matrix3X f = Matrix3X::Zero(3, s.x.cols());
  force.add_forces(s.view(), f);
  return Eigen::Map<const Eigen::VectorXd>(f.data(), f.size());
}

// Central differences with respect to x (wrt_x) or v.
Dense FiniteDifference(Force& force, const State& s, bool wrt_x) {
  const Index n3 = 3 * s.x.cols();
  Dense j(n3, n3);
  constexpr double e = 1e-6;
  for (Index k = 0; k < n3; ++k) {
    State plus = s, minus = s;
    (wrt_x ? plus.x : plus.v).data()[k] += e;
    (wrt_x ? minus.x : minus.v).data()[k] -= e;
    j.col(k) = (Forces(force, plus) - Forces(force, minus)) / (2 * e);
  }
  return j;
}

// Largest entry of the difference over the largest entry of the reference.
double RelativeDifference(const Dense& a, const Dense& ref) {
  const double scale = ref.cwiseAbs().maxCoeff();
  return (a - ref).cwiseAbs().maxCoeff() / (scale > 0 ? scale : 1.0);
}

// The force object of a one-force scene with `n` particles at `s`.
std::shared_ptr<Force> MakeForce(const std::string& yaml_force, Index n) {
  std::string text = "simulation: { dt: 0.01, steps: 1 }\nparticles:\n";
  for (Index i = 0; i < n; ++i) {
    text += "  - { position: [" + std::to_string(i) + ", 0, 0], mass: 1 }\n";
  }
  text += "forces:\n  - " + yaml_force + "\n";
  static std::vector<Scene> keep;  // the scene owns the plugin library's objects
  keep.push_back(test::load_text(text));
  return keep.back().system->force_objects().at(0).force;
}

State RandomState(Index n, unsigned seed, bool equal_velocities = false) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  State s;
  s.x.resize(3, n);
  s.v.resize(3, n);
  for (Index i = 0; i < n; ++i) {
    s.x.col(i) = Vec3(static_cast<double>(i), 0.5 * static_cast<double>(i % 2), 0.0) +
                 0.2 * Vec3(u(rng), u(rng), u(rng));
    s.v.col(i) = equal_velocities ? Vec3(0.3, -0.2, 0.7) : Vec3(u(rng), u(rng), u(rng));
  }
  s.mass = Eigen::VectorXd::LinSpaced(n, 0.5, 2.0);
  s.fixed.assign(static_cast<std::size_t>(n), 0);
  return s;
}

struct Check {
  double dx, dv;
};

Check Compare(Force& force, const State& s, const char* what) {
  DenseSink sink(s.x.cols());
  EXPECT_TRUE(force.add_jacobians(s.view(), sink)) << what;
  const Check c{RelativeDifference(sink.dfdx, FiniteDifference(force, s, true)),
                RelativeDifference(sink.dfdv, FiniteDifference(force, s, false))};
  std::cout << what << ": df/dx off by " << c.dx << ", df/dv off by " << c.dv
            << " (relative to the largest entry)\n";
  return c;
}

// Four particles, five springs, every spring stretched (rest length 0.25 m;
// RandomState keeps neighbours at least 0.42 m apart); kd = 0, so the
// reported Jacobians are exact.
TEST(Jacobians, StretchedSpringsMatchFiniteDifferences) {
  auto spring = MakeForce(
      "{ type: spring, pairs: [[0, 1], [1, 2], [2, 3], [0, 2], [3, 1]], ks: 50, rest: [0.25] }", 4);
  const Check c = Compare(*spring, RandomState(4, 1), "spring, stretched, kd = 0");
  EXPECT_LT(c.dx, 1e-6);
  EXPECT_LT(c.dv, 1e-6);
}

// With damping, df/dv = -kd n n^T is exact in every state; df/dx is exact
// when the ends move together (dv = 0), where the omitted term vanishes.
TEST(Jacobians, DampedSpringsMatchFiniteDifferencesWhenTheEndsMoveTogether) {
  auto spring = MakeForce(
      "{ type: spring, pairs: [[0, 1], [1, 2], [2, 3], [0, 2], [3, 1]], ks: 50, kd: 3, "
      "rest: [0.25] }",
      4);
  const Check rigid = Compare(*spring, RandomState(4, 2, true), "spring, kd = 3, dv = 0");
  EXPECT_LT(rigid.dx, 1e-6);
  EXPECT_LT(rigid.dv, 1e-6);
  const Check moving = Compare(*spring, RandomState(4, 3), "spring, kd = 3, dv != 0");
  EXPECT_LT(moving.dv, 1e-6);
  // The omitted -(kd/L)[n dv^T P + (dv.n) P] shows up only in df/dx.
  EXPECT_GT(moving.dx, 1e-3);
}

// Under compression the exact df/dx has a positive eigenvalue (the
// geometric stiffness ks (1 - r/L) < 0 across the spring); the reported one
// clamps it and stays negative semidefinite, and differs from the exact one
// by exactly that clamped term.
TEST(Jacobians, CompressedSpringKeepsDfdxNegativeSemidefinite) {
  auto spring = MakeForce("{ type: spring, pairs: [[0, 1]], ks: 50, rest: [2] }", 2);
  State s = RandomState(2, 4);
  s.x.col(0) = Vec3(0, 0, 0);
  s.x.col(1) = Vec3(0.6, 0.8, 0);  // L = 1 < r = 2
  DenseSink sink(2);
  ASSERT_TRUE(spring->add_jacobians(s.view(), sink));
  const Dense exact = FiniteDifference(*spring, s, true);
  const double reported_max =
      Eigen::SelfAdjointEigenSolver<Dense>(sink.dfdx).eigenvalues().maxCoeff();
  const double exact_max = Eigen::SelfAdjointEigenSolver<Dense>(exact).eigenvalues().maxCoeff();
  std::cout << "compressed spring (L = 1, r = 2, ks = 50): largest eigenvalue of df/dx "
            << reported_max << " reported, " << exact_max << " exact\n";
  EXPECT_LE(reported_max, 1e-9);
  EXPECT_NEAR(exact_max, 2 * 50 * (2.0 / 1.0 - 1.0), 1e-4);  // 2 ks (r/L - 1)
  // exact - reported = -ks (1 - r/L) P in the [[1, -1], [-1, 1]] pattern.
  const Vec3 n(0.6, 0.8, 0);
  const Eigen::Matrix3d p = Eigen::Matrix3d::Identity() - n * n.transpose();
  Dense geometric(6, 6);
  const Eigen::Matrix3d b = -50 * (1.0 - 2.0) * p;
  geometric << b, -b, -b, b;
  EXPECT_LT(RelativeDifference(exact - sink.dfdx, geometric), 1e-6);
}

TEST(Jacobians, DragMatchesFiniteDifferences) {
  auto drag = MakeForce("{ type: drag, k: 0.7 }", 3);
  const Check c = Compare(*drag, RandomState(3, 5), "drag");
  EXPECT_LT(c.dx, 1e-6);
  EXPECT_LT(c.dv, 1e-6);
}

TEST(Jacobians, GravityHasNone) {
  auto gravity = MakeForce("{ type: gravity, g: [0.3, -1, -9.81] }", 3);
  const State s = RandomState(3, 6);
  DenseSink sink(3);
  EXPECT_TRUE(gravity->add_jacobians(s.view(), sink));
  EXPECT_EQ(sink.dfdx.cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(sink.dfdv.cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(FiniteDifference(*gravity, s, true).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(FiniteDifference(*gravity, s, false).cwiseAbs().maxCoeff(), 0.0);
}

}  // namespace
}  // namespace pdyn
