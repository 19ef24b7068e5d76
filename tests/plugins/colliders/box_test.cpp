// The box collider (plugins/colliders/box): Witkin's collision rules of
// pdyn/contact.hpp against the axis-aligned box [min, max], as a solid
// block (inside: false, one exact signed distance) and as a container
// (inside: true, six walls).
#include <gtest/gtest.h>

#include <algorithm>
#include <iostream>
#include <numbers>

#include "plugins/colliders/collider_support.hpp"

namespace pdyn {
namespace {

const Vec3 kMin(-0.5, -0.4, -0.3), kMax(0.5, 0.4, 0.3);

// Signed distance to the box surface from outside: > 0 outside, < 0 inside.
double OutsideDistance(const Vec3& x) {
  const Vec3 c = 0.5 * (kMin + kMax), e = 0.5 * (kMax - kMin);
  const Vec3 q = (x - c).cwiseAbs() - e;
  return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
}
// Distance to the nearest wall from inside: > 0 inside.
double InsideDistance(const Vec3& x) {
  return std::min((x - kMin).minCoeff(), (kMax - x).minCoeff());
}

const std::string kBox = "type: box, min: [-0.5, -0.4, -0.3], max: [0.5, 0.4, 0.3]";

// 300 throws at 1..5 m/s from all sides, edges and corners included.
TEST(BoxCollider, NoThrownParticleEndsAStepInsideTheSolidBox) {
  Scene scene =
      test::load_text(test::ThrowScene(300, 5e-3, 9.81, "{ " + kBox + ", restitution: 0.6 }"));
  System& sys = *scene.system;
  std::mt19937_64 g(21);
  for (Index i = 0; i < sys.size(); ++i) {
    const Vec3 dir = test::RandomDirection(g);
    sys.positions().col(i) = dir * (1.0 + test::Uniform(g));
    sys.velocities().col(i) =
        -(1.0 + 4.0 * test::Uniform(g)) * (dir + 0.4 * test::RandomDirection(g)).normalized();
  }
  int contacts = 0;
  const double worst = test::WorstPenetration(scene, 400, 5e-3, OutsideDistance, contacts);
  std::cout << "box outside: worst penetration " << worst << " m, " << contacts
            << " particles reached the surface\n";
  EXPECT_LE(worst, 1e-12);
  EXPECT_GT(contacts, 50);  // aimed up to ~22 degrees off centre: most miss, ~70-90 hit
}

TEST(BoxCollider, NoParticleEndsAStepOutsideTheContainer) {
  Scene scene = test::load_text(
      test::ThrowScene(300, 5e-3, 9.81, "{ " + kBox + ", inside: true, restitution: 0.9 }"));
  System& sys = *scene.system;
  std::mt19937_64 g(22);
  for (Index i = 0; i < sys.size(); ++i) {
    for (int a = 0; a < 3; ++a) {
      sys.positions()(a, i) = 0.9 * (kMin[a] + test::Uniform(g) * (kMax[a] - kMin[a]));
    }
    sys.velocities().col(i) = (1.0 + 4.0 * test::Uniform(g)) * test::RandomDirection(g);
  }
  int contacts = 0;
  const double worst = test::WorstPenetration(scene, 400, 5e-3, InsideDistance, contacts);
  std::cout << "box inside: worst penetration " << worst << " m, " << contacts
            << " particles reached a wall\n";
  EXPECT_LE(worst, 1e-12);
  EXPECT_EQ(contacts, 300);  // every particle reaches the wall
}

TEST(BoxCollider, NormalImpactOnAFaceLeavesWithKrTimesTheSpeed) {
  Scene scene = test::OneParticle({0.1, 0.1, 1}, {0, 0, -2}, "{ " + kBox + ", restitution: 0.7 }");
  const test::Impact hit = test::FirstImpact(scene, 1e-3, 1000);
  std::cout << "box outside, normal impact on the top face at 2 m/s: |v_out|/|v_in| = " << hit.ratio
            << " (kr = 0.7), z = " << hit.x.z() << " m\n";
  EXPECT_NEAR(hit.ratio, 0.7, 0.007);
  EXPECT_NEAR(hit.x.z(), kMax.z(), 1e-12);
}

TEST(BoxCollider, NormalImpactOnAnInnerWallLeavesWithKrTimesTheSpeed) {
  Scene scene =
      test::OneParticle({0, 0, 0}, {0, 3, 0}, "{ " + kBox + ", inside: true, restitution: 0.3 }");
  const test::Impact hit = test::FirstImpact(scene, 1e-3, 1000);
  std::cout << "box inside, normal impact on the wall y = 0.4 at 3 m/s: |v_out|/|v_in| = "
            << hit.ratio << " (kr = 0.3)\n";
  EXPECT_NEAR(hit.ratio, 0.3, 0.003);
  EXPECT_NEAR(hit.x.y(), kMax.y(), 1e-12);
}

// Into a corner of the container along its diagonal (reached at t = 0.25 s):
// every wall crossed reflects its own velocity component, so 0.15 s later
// the particle is on its way straight back, inside the box.
TEST(BoxCollider, CornerOfTheContainerReflectsEveryComponent) {
  const Vec3 v0 = Vec3(0.5, 0.4, 0.3) * 4.0;
  Scene scene =
      test::OneParticle({0, 0, 0}, v0, "{ " + kBox + ", inside: true, restitution: 1.0 }");
  System& sys = *scene.system;
  double worst = -1.0;
  for (int k = 1; k <= 400; ++k) {
    test::TakeStep(scene, k, 1e-3);
    worst = std::max(worst, -InsideDistance(sys.positions().col(0)));
  }
  std::cout << "box corner: v after = " << sys.velocities().col(0).transpose()
            << ", worst penetration " << worst << " m\n";
  EXPECT_EQ(Vec3(sys.velocities().col(0)), Vec3(-v0));
  EXPECT_LE(worst, 1e-12);
}

// A particle dropped into the container with some sideways speed comes to
// rest on its floor: bounces die out (resting rule), friction stops the slide.
TEST(BoxCollider, DroppedParticleComesToRestOnTheContainerFloor) {
  Scene drop = test::load_text(R"(
simulation: { dt: 0.001, steps: 1 }
particles:
  - { position: [0.2, -0.1, 0.2], velocity: [0.5, 0, 0], mass: 0.1 }
forces:
  - { type: gravity, g: [0, 0, -9.81] }
colliders:
  - { type: box, min: [-0.5, -0.4, -0.3], max: [0.5, 0.4, 0.3], inside: true, restitution: 0.5, friction: 0.5 }
)");
  System& sys = *drop.system;
  for (int k = 1; k <= 3000; ++k) test::TakeStep(drop, k, 1e-3);
  std::cout << "box floor rest: x = " << sys.positions().col(0).transpose()
            << ", |v| = " << sys.velocities().col(0).norm() << " m/s\n";
  EXPECT_NEAR(sys.positions()(2, 0), kMin.z(), 1e-4);
  EXPECT_EQ(sys.velocities().col(0).norm(), 0.0);
}

}  // namespace
}  // namespace pdyn
