// A ball on the plane collider (Witkin, "Bouncing off the Walls"), against
// closed forms:
//  - a bounce reverses the normal velocity scaled by kr, V' = V_T - kr V_N,
//    so the speed leaving the plane after bounce n is kr^n sqrt(2 g h0) and
//    the apex of the n-th flight is (kr^n sqrt(2 g h0))^2 / (2 g) = kr^(2n) h0;
//  - the bounces are a geometric series, so the ball comes to rest (after
//    finite time, sum of flight times = sqrt(2 h0 / g) (1 + kr) / (1 - kr));
//  - the plane is frictionless: the contact force removes only the normal
//    part of the applied force, so tangential motion is free.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <vector>

#include "pdyn/host/assembly.hpp"
#include "support/physics_support.hpp"
#include "support/test_support.hpp"

namespace pdyn {
namespace {

constexpr double kBallG = 9.81;    // m/s^2, along -z
constexpr double kEpsilon = 1e-4;  // the collider's contact tolerance, m and m/s

Scene Ball(double h0, const Vec3& v0, double kr, double dt, int steps) {
  return test::load_text("simulation: { dt: " + test::Num(dt) +
                         ", steps: " + std::to_string(steps) +
                         ", solver: { type: rk4 } }\n"
                         "particles:\n"
                         "  - { position: [0, 0, " +
                         test::Num(h0) + "], velocity: " + test::Vec(v0) +
                         ", mass: 0.2 }\n"
                         "forces:\n"
                         "  - { type: gravity, g: [0, 0, " +
                         test::Num(-kBallG) +
                         "] }\n"
                         "colliders:\n"
                         "  - { type: plane, point: [0, 0, 0], normal: [0, 0, 1], restitution: " +
                         test::Num(kr) + ", epsilon: " + test::Num(kEpsilon) + " }\n");
}

class BouncingBall : public ::testing::TestWithParam<double> {};

// Apexes: the highest sampled height between two impacts. An impact is a
// step after which the normal velocity points out of the plane while it
// pointed in before. At dt = 1e-4 a step moves the ball at most ~4.4e-4 m,
// so the collider's projection back onto the plane changes an apex by a
// relative ~1e-3 at most, and sampling the apex at steps by g dt^2 / 8
// ~1e-8 m: 1% leaves room, a wrong restitution law (kr instead of kr^2 per
// apex, or energy lost in the response) does not fit in it.
TEST_P(BouncingBall, ApexHeightsFollowKrToThe2nTimesH0) {
  const double kr = GetParam();
  constexpr double kH0 = 1.0, kDt = 1e-4;
  // Time to the third apex: the fall plus 2.5 flights of the geometric series.
  const double t_fall = std::sqrt(2.0 * kH0 / kBallG);
  const double t_end = t_fall * (1.0 + 2.0 * (kr + kr * kr) + 1.2 * kr * kr * kr);
  const int steps = static_cast<int>(t_end / kDt);
  Scene scene = Ball(kH0, Vec3::Zero(), kr, kDt, steps);
  System& sys = *scene.system;
  std::vector<double> apexes;
  double apex = -1.0;  // < 0: still falling from h0
  for (int k = 1; k <= steps; ++k) {
    const double vz_before = sys.velocities()(2, 0);
    test::TakeStep(scene, k, kDt);
    const double z = sys.positions()(2, 0), vz = sys.velocities()(2, 0);
    if (vz_before < 0.0 && vz > 0.0) {  // a bounce: close the previous flight
      if (apex >= 0.0) apexes.push_back(apex);
      apex = z;
    } else if (apex >= 0.0) {
      apex = std::max(apex, z);
    }
  }
  if (apex >= 0.0 && sys.velocities()(2, 0) < 0.0) apexes.push_back(apex);  // falling again
  ASSERT_GE(apexes.size(), 3u) << "expected three bounces before t = " << t_end;
  for (std::size_t n = 1; n <= 3; ++n) {
    const double expected = std::pow(kr, 2.0 * static_cast<double>(n)) * kH0;
    const double rel = (apexes[n - 1] - expected) / expected;
    std::cout << "kr = " << kr << ", apex " << n << ": " << apexes[n - 1] << " m, expected "
              << expected << " m, relative error " << rel << "\n";
    EXPECT_LT(std::abs(rel), 0.01) << "apex " << n;
  }
}

INSTANTIATE_TEST_SUITE_P(Restitution, BouncingBall, ::testing::Values(0.5, 0.8),
                         [](const auto& test_info) {
                           return "kr" + std::to_string(static_cast<int>(test_info.param * 10));
                         });

// With kr = 0.5 the bounces die out after ~1.35 s (the series above); the
// collider must then hold the ball on the plane: at rest, and never more
// than epsilon inside the obstacle at the end of any step on the way.
TEST(BouncingBallAtRest, ComesToRestOnThePlaneAndNeverSinksIntoIt) {
  constexpr double kDt = 1e-3;
  constexpr int kSteps = 3000;  // 3 s
  Scene scene = Ball(1.0, Vec3::Zero(), 0.5, kDt, kSteps);
  System& sys = *scene.system;
  double lowest = 1.0;
  for (int k = 1; k <= kSteps; ++k) {
    test::TakeStep(scene, k, kDt);
    const double z = sys.positions()(2, 0);
    lowest = std::min(lowest, z);
    ASSERT_GE(z, -kEpsilon) << "inside the plane after step " << k << " (t = " << k * kDt << ")";
  }
  const double speed = sys.velocities().col(0).norm();
  const double z = sys.positions()(2, 0);
  std::cout << "kr = 0.5 ball after 3 s: |v| = " << speed << " m/s, z = " << z
            << " m, lowest z = " << lowest << " m\n";
  EXPECT_LT(speed, 1e-3);
  EXPECT_LE(std::abs(z), kEpsilon);
}

// A particle moving along the plane while gravity presses it into it: the
// contact force cancels the normal force during every derivative
// evaluation, nothing acts tangentially, so it keeps its velocity exactly and
// stays on the plane. It must stay there during the solver's step already,
// not only after the collision response has put it back.
TEST(PlaneContact, SlidingParticleKeepsItsTangentialVelocityAndStaysOnThePlane) {
  constexpr double kDt = 1e-3;
  constexpr int kSteps = 2000;
  const Vec3 v0(1.5, -0.7, 0.0);
  Scene scene = Ball(0.0, v0, 0.5, kDt, kSteps);
  System& sys = *scene.system;
  for (int k = 1; k <= kSteps; ++k) {
    scene.solver->step(sys, kDt);
    // Before the response: the contact force alone has held the particle.
    ASSERT_EQ(sys.positions()(2, 0), 0.0) << "sank during step " << k;
    ASSERT_EQ(sys.velocities()(2, 0), 0.0) << "sank during step " << k;
    sys.set_time(k * kDt);
    SystemAssembly(sys).respond_to_collisions(kDt);
    const double t = k * kDt;
    ASSERT_NEAR(sys.positions()(2, 0), 0.0, kEpsilon) << "left the plane at step " << k;
    ASSERT_NEAR((sys.velocities().col(0) - v0).norm(), 0.0, 1e-12) << "step " << k;
    ASSERT_NEAR(sys.positions()(0, 0), v0.x() * t, 1e-12) << "step " << k;
    ASSERT_NEAR(sys.positions()(1, 0), v0.y() * t, 1e-12) << "step " << k;
  }
}

// Witkin's contact condition, at the level of one derivative evaluation:
// the normal part of the force is removed only for a particle that is on the
// plane (within epsilon), not moving along the normal (within epsilon) and
// pushed into it. Everywhere else the acceleration is the free one, g.
TEST(PlaneContact, ContactForceActsOnlyOnParticlesRestingOnThePlane) {
  Scene scene = test::load_text(R"(
simulation: { dt: 0.001, steps: 1 }
particles:
  - { position: [0, 0, 0], velocity: [1, 0, 0], mass: 1 }          # resting: held
  - { position: [0, 0, 0.5], velocity: [1, 0, 0], mass: 1 }        # in the air
  - { position: [0, 0, 0], velocity: [0, 0, 0.1], mass: 1 }        # leaving the plane
  - { position: [0, 0, 0.00005], velocity: [0, 2, 0], mass: 3 }    # within epsilon: held
forces:
  - { type: gravity, g: [0.5, 0, -9.81] }
colliders:
  - { type: plane, point: [0, 0, 0], normal: [0, 0, 1], restitution: 0.5, epsilon: 0.0001 }
)");
  System& sys = *scene.system;
  Eigen::VectorXd dydt(sys.dimension());
  sys.derivative(dydt);
  const Eigen::Map<const Matrix3X> a(dydt.data() + 3 * sys.size(), 3, sys.size());
  const Vec3 g(0.5, 0.0, -9.81), g_t(0.5, 0.0, 0.0);
  EXPECT_EQ(a.col(0), g_t);
  EXPECT_EQ(a.col(1), g);
  EXPECT_EQ(a.col(2), g);
  EXPECT_EQ(a.col(3), g_t);

  // A force pulling a resting particle off the plane is not resisted: the
  // wall only pushes (N.F < 0), it never holds on.
  Scene pulled = test::load_text(R"(
simulation: { dt: 0.001, steps: 1 }
particles:
  - { position: [0, 0, 0], mass: 2 }
forces:
  - { type: gravity, g: [0.5, 0, 9.81] }
colliders:
  - { type: plane, point: [0, 0, 0], normal: [0, 0, 1], restitution: 0.5, epsilon: 0.0001 }
)");
  Eigen::VectorXd d(pulled.system->dimension());
  pulled.system->derivative(d);
  EXPECT_EQ(Vec3(d.tail<3>()), Vec3(0.5, 0.0, 9.81));
}

// The same on a tilted plane (normal (0, 1, 1)/sqrt(2) through the origin):
// the contact force removes the normal part of gravity, the tangential part
// g_T = g - (g.n) n accelerates the particle down the frictionless incline,
// x(t) = x0 + v0 t + g_T t^2 / 2, exactly a parabola in the plane.
TEST(PlaneContact, SlidesDownAFrictionlessInclineWithTheTangentialPartOfGravity) {
  constexpr double kDt = 1e-3;
  constexpr int kSteps = 1000;
  const Vec3 n = Vec3(0.0, 1.0, 1.0).normalized();
  const Vec3 g(0.0, 0.0, -kBallG);
  const Vec3 g_t = g - g.dot(n) * n;
  const Vec3 v0(0.8, 0.0, 0.0);  // along the plane, across the slope
  Scene scene = test::load_text(
      "simulation: { dt: " + test::Num(kDt) + ", steps: " + std::to_string(kSteps) +
      ", solver: { type: rk4 } }\n"
      "particles:\n"
      "  - { position: [0, 0, 0], velocity: " +
      test::Vec(v0) +
      ", mass: 0.2 }\n"
      "forces:\n"
      "  - { type: gravity, g: " +
      test::Vec(g) +
      " }\n"
      "colliders:\n"
      "  - { type: plane, point: [0, 0, 0], normal: [0, 1, 1], restitution: 0.5, epsilon: " +
      test::Num(kEpsilon) + " }\n");
  System& sys = *scene.system;
  double worst = 0.0;
  for (int k = 1; k <= kSteps; ++k) {
    test::TakeStep(scene, k, kDt);
    const double t = k * kDt;
    ASSERT_NEAR(sys.positions().col(0).dot(n), 0.0, kEpsilon) << "left the plane at step " << k;
    worst = std::max({worst, (sys.positions().col(0) - (v0 * t + 0.5 * g_t * t * t)).norm(),
                      (sys.velocities().col(0) - (v0 + g_t * t)).norm()});
  }
  std::cout << "incline: max deviation from x0 + v0 t + g_T t^2/2: " << worst << "\n";
  EXPECT_LT(worst, 1e-12);
}

}  // namespace
}  // namespace pdyn
