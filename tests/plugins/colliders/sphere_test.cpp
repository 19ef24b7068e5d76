// The sphere collider (plugins/colliders/sphere): Witkin's collision rules
// of pdyn/contact.hpp against |X - C| = R, from outside and from inside.
//  - No particle ends a step inside the obstacle: put-back moves it by the
//    exact signed distance, so it lands on the sphere to round-off.
//  - A normal impact leaves with kr times the incoming speed; an oblique
//    one keeps its tangential velocity (frictionless) relative to the
//    normal at the contact point, u = (X - C) / |X - C|.
#include <gtest/gtest.h>

#include <algorithm>
#include <iostream>
#include <numbers>

#include "plugins/colliders/collider_support.hpp"

namespace pdyn {
namespace {

constexpr double kR = 0.5;  // m

// 300 particles thrown at the sphere from all sides at 1..5 m/s, aimed within
// ~0.4 rad of its centre, under gravity: h = 5 ms steps move them up to 2.5 cm.
TEST(SphereCollider, NoThrownParticleEndsAStepInsideFromOutside) {
  Scene scene = test::load_text(test::ThrowScene(
      300, 5e-3, 9.81, "{ type: sphere, center: [0, 0, 0], radius: 0.5, restitution: 0.6 }"));
  System& sys = *scene.system;
  std::mt19937_64 g(11);
  for (Index i = 0; i < sys.size(); ++i) {
    const Vec3 dir = test::RandomDirection(g);
    sys.positions().col(i) = dir * (1.0 + test::Uniform(g));
    sys.velocities().col(i) =
        -(1.0 + 4.0 * test::Uniform(g)) * (dir + 0.4 * test::RandomDirection(g)).normalized();
  }
  int contacts = 0;
  const double worst = test::WorstPenetration(
      scene, 400, 5e-3, [](const Vec3& x) { return x.norm() - kR; }, contacts);
  std::cout << "sphere outside: worst penetration " << worst << " m, " << contacts
            << " particles reached the surface\n";
  EXPECT_LE(worst, 1e-12);
  EXPECT_GT(contacts, 50);  // aimed up to ~22 degrees off centre: most miss, ~70-90 hit
}

// 300 particles inside the sphere at 1..5 m/s in random directions bounce
// off its inner wall: none ends a step outside it.
TEST(SphereCollider, NoParticleEndsAStepOutsideWhenKeptInside) {
  Scene scene = test::load_text(test::ThrowScene(
      300, 5e-3, 9.81,
      "{ type: sphere, center: [0, 0, 0], radius: 0.5, inside: true, restitution: 0.9 }"));
  System& sys = *scene.system;
  std::mt19937_64 g(12);
  for (Index i = 0; i < sys.size(); ++i) {
    sys.positions().col(i) = 0.45 * test::Uniform(g) * test::RandomDirection(g);
    sys.velocities().col(i) = (1.0 + 4.0 * test::Uniform(g)) * test::RandomDirection(g);
  }
  int contacts = 0;
  const double worst = test::WorstPenetration(
      scene, 400, 5e-3, [](const Vec3& x) { return kR - x.norm(); }, contacts);
  std::cout << "sphere inside: worst penetration " << worst << " m, " << contacts
            << " particles reached the surface\n";
  EXPECT_LE(worst, 1e-12);
  EXPECT_EQ(contacts, 300);  // every particle reaches the wall
}

TEST(SphereCollider, NormalImpactFromOutsideLeavesWithKrTimesTheSpeed) {
  Scene scene = test::OneParticle(
      {0, 0, 1}, {0, 0, -2}, "{ type: sphere, center: [0, 0, 0], radius: 0.5, restitution: 0.7 }");
  const test::Impact hit = test::FirstImpact(scene, 1e-3, 1000);
  std::cout << "sphere outside, normal impact at 2 m/s: |v_out|/|v_in| = " << hit.ratio
            << " (kr = 0.7)\n";
  EXPECT_NEAR(hit.ratio, 0.7, 0.007);
  EXPECT_GT(hit.v_out.z(), 0.0);
}

TEST(SphereCollider, NormalImpactFromInsideLeavesWithKrTimesTheSpeed) {
  Scene scene = test::OneParticle(
      {0.1, 0, 0}, {2, 0, 0},
      "{ type: sphere, center: [0, 0, 0], radius: 0.5, inside: true, restitution: 0.4 }");
  const test::Impact hit = test::FirstImpact(scene, 1e-3, 1000);
  std::cout << "sphere inside, normal impact at 2 m/s: |v_out|/|v_in| = " << hit.ratio
            << " (kr = 0.4)\n";
  EXPECT_NEAR(hit.ratio, 0.4, 0.004);
  EXPECT_LT(hit.v_out.x(), 0.0);
}

// Off-centre: the normal at the contact is u = X / |X|, not the direction
// of travel. V' = V_T - kr V_N with respect to u.
TEST(SphereCollider, ObliqueImpactReflectsAboutTheLocalNormalAndKeepsTheTangent) {
  Scene scene =
      test::OneParticle({0.3, 0.1, 1}, {0, 0, -2},
                        "{ type: sphere, center: [0, 0, 0], radius: 0.5, restitution: 0.7 }");
  const test::Impact hit = test::FirstImpact(scene, 1e-3, 1000);
  ASSERT_GT(hit.ratio, 0.0) << "no impact";
  const Vec3 u = hit.x.normalized();
  const Vec3 tin = hit.v_in - hit.v_in.dot(u) * u, tout = hit.v_out - hit.v_out.dot(u) * u;
  std::cout << "sphere oblique impact: |x| - R = " << hit.x.norm() - kR << " m, normal speed ratio "
            << -hit.v_out.dot(u) / hit.v_in.dot(u) << ", tangential change " << (tout - tin).norm()
            << " m/s\n";
  EXPECT_NEAR(hit.x.norm(), kR, 1e-12);
  EXPECT_NEAR(-hit.v_out.dot(u) / hit.v_in.dot(u), 0.7, 1e-12);
  EXPECT_LT((tout - tin).norm(), 1e-12);
}

// A particle dropped onto the top of the sphere under gravity comes to rest
// there (the resting rule and the contact force), exactly on the surface.
TEST(SphereCollider, DroppedParticleComesToRestOnTop) {
  Scene scene = test::load_text(R"(
simulation: { dt: 0.001, steps: 1 }
particles:
  - { position: [0, 0, 1], mass: 0.1 }
forces:
  - { type: gravity, g: [0, 0, -9.81] }
colliders:
  - { type: sphere, center: [0, 0, 0], radius: 0.5, restitution: 0.5 }
)");
  System& sys = *scene.system;
  for (int k = 1; k <= 3000; ++k) test::TakeStep(scene, k, 1e-3);
  std::cout << "sphere rest: z = " << sys.positions()(2, 0)
            << " m, |v| = " << sys.velocities().col(0).norm() << " m/s\n";
  EXPECT_NEAR(sys.positions()(2, 0), kR, 1e-4);
  EXPECT_LT(sys.velocities().col(0).norm(), 1e-3);
}

}  // namespace
}  // namespace pdyn
