// Free fall under constant gravity against the exact parabola
//   x(t) = x0 + v0 t + g t^2 / 2,   v(t) = v0 + g t.
// The acceleration is constant, so the solution is a polynomial of degree 2
// in t: every Runge-Kutta method of order >= 2 reproduces it exactly (up to
// round-off), and forward Euler misses it by a known closed-form amount.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <string>

#include "support/physics_support.hpp"
#include "support/test_support.hpp"

namespace pdyn {
namespace {

const Vec3 kX0(0.5, -1.0, 2.0);   // m
const Vec3 kV0(1.5, -0.5, 4.0);   // m/s, nonzero in every component
const Vec3 kG(0.3, 0.0, -9.81);   // m/s^2, not along an axis
constexpr double kMass = 2.0;     // kg: f = m g, a = g whatever the mass
constexpr double kFallDt = 1e-3;  // s
constexpr int kFallSteps = 1000;

Scene FreeFall(const std::string& solver) {
  return test::load_text(
      "simulation: { dt: " + test::Num(kFallDt) + ", steps: " + std::to_string(kFallSteps) +
      ", solver: { type: " + solver + " } }\n" +
      "particles:\n"
      "  - { position: " +
      test::Vec(kX0) + ", velocity: " + test::Vec(kV0) + ", mass: " + test::Num(kMass) + " }\n" +
      "forces:\n"
      "  - { type: gravity, g: " +
      test::Vec(kG) + " }\n");
}

// Largest deviation from the exact parabola over every step (m and m/s).
struct Deviation {
  double x = 0.0, v = 0.0;
};

Deviation RunAgainstParabola(const std::string& solver) {
  Scene scene = FreeFall(solver);
  System& sys = *scene.system;
  Deviation d;
  for (int k = 1; k <= kFallSteps; ++k) {
    test::TakeStep(scene, k, kFallDt);
    const double t = k * kFallDt;
    const Vec3 x = kX0 + kV0 * t + 0.5 * kG * t * t;
    const Vec3 v = kV0 + kG * t;
    d.x = std::max(d.x, (sys.positions().col(0) - x).lpNorm<Eigen::Infinity>());
    d.v = std::max(d.v, (sys.velocities().col(0) - v).lpNorm<Eigen::Infinity>());
  }
  return d;
}

TEST(FreeFall, Rk4FollowsTheExactParabola) {
  const Deviation d = RunAgainstParabola("rk4");
  std::cout << "rk4 free fall: max |x - exact| = " << d.x << " m, max |v - exact| = " << d.v
            << " m/s over " << kFallSteps << " steps\n";
  EXPECT_LT(d.x, 1e-12);
  EXPECT_LT(d.v, 1e-12);
}

// The midpoint rule is second order, so it too is exact on a parabola:
// x1 = x0 + h (v0 + g h/2) = x0 + v0 h + g h^2/2.
TEST(FreeFall, MidpointFollowsTheExactParabola) {
  const Deviation d = RunAgainstParabola("midpoint");
  EXPECT_LT(d.x, 1e-12);
  EXPECT_LT(d.v, 1e-12);
}

// Forward Euler: v_n = v0 + g t_n exactly, but x_n = x0 + h sum_{k<n} v_k
// = x0 + v0 t_n + g h^2 n(n-1)/2 = exact(t_n) - g h t_n / 2. The test checks
// that closed form of its error, so a solver that is better than Euler (or
// worse) fails it too.
TEST(FreeFall, EulerLagsTheParabolaByGHTOverTwo) {
  Scene scene = FreeFall("euler");
  System& sys = *scene.system;
  double dx = 0.0, dv = 0.0;
  for (int k = 1; k <= kFallSteps; ++k) {
    test::TakeStep(scene, k, kFallDt);
    const double t = k * kFallDt;
    const Vec3 x = kX0 + kV0 * t + 0.5 * kG * t * t - 0.5 * kG * kFallDt * t;
    const Vec3 v = kV0 + kG * t;
    dx = std::max(dx, (sys.positions().col(0) - x).lpNorm<Eigen::Infinity>());
    dv = std::max(dv, (sys.velocities().col(0) - v).lpNorm<Eigen::Infinity>());
  }
  EXPECT_LT(dx, 1e-12);
  EXPECT_LT(dv, 1e-12);
}

// The same parabola through the kernel's runner, with a duration that is
// not a multiple of dt: the runner must shorten the last step so the run ends
// exactly at t = 1 s, where rk4 is still exact.
TEST(FreeFall, RunnerEndsExactlyOnTheDurationOnTheParabola) {
  Scene scene = test::load_text(
      "simulation: { dt: 0.003, duration: 1, solver: { type: rk4 } }\n"
      "particles:\n"
      "  - { position: " +
      test::Vec(kX0) + ", velocity: " + test::Vec(kV0) + ", mass: " + test::Num(kMass) + " }\n" +
      "forces:\n"
      "  - { type: gravity, g: " +
      test::Vec(kG) + " }\n");
  const RunResult result = run_scene(scene);
  ASSERT_EQ(result.exit_code, 0) << result.message;
  EXPECT_EQ(result.steps_done, 334);  // 333 steps of 3 ms and one of 1 ms
  EXPECT_DOUBLE_EQ(result.time, 1.0);
  const Vec3 x = kX0 + kV0 + 0.5 * kG, v = kV0 + kG;
  EXPECT_LT((scene.system->positions().col(0) - x).lpNorm<Eigen::Infinity>(), 1e-12);
  EXPECT_LT((scene.system->velocities().col(0) - v).lpNorm<Eigen::Infinity>(), 1e-12);
}

}  // namespace
}  // namespace pdyn
