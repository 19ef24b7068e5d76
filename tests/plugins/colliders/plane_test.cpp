// The plane collider with Coulomb friction (pdyn/contact.hpp), against
// closed forms:
//  - a block sliding on a level plane with friction mu decelerates at
//    mu g (kinetic friction mu |F_N| = mu m g), stops after v0 / (mu g) s
//    at v0^2 / (2 mu g) m, and then stays exactly where it stopped;
//  - on an incline of angle a it is held if tan a <= mu and slides with
//    g (sin a - mu cos a) otherwise;
//  - at an impact the tangential impulse is mu times the normal impulse,
//    never reversing the tangential velocity;
//  - friction 0 is the seed plane: bit-identical to the frictionless
//    collider pdyn shipped before friction existed (kept below as a
//    reference implementation).
#include <gtest/gtest.h>

#include <algorithm>
#include <iostream>
#include <numbers>

#include "pdyn/host/assembly.hpp"
#include "plugins/colliders/collider_support.hpp"

namespace pdyn {
namespace {

constexpr double kPlaneG = 9.81;  // m/s^2

Scene Slide(const Vec3& v0, double mu, const Vec3& normal, const Vec3& g) {
  return test::load_text(
      "simulation: { dt: 0.001, steps: 1, solver: { type: rk4 } }\n"
      "particles:\n"
      "  - { position: [0, 0, 0], velocity: " +
      test::Vec(v0) +
      ", mass: 0.5 }\n"
      "forces:\n"
      "  - { type: gravity, g: " +
      test::Vec(g) +
      " }\n"
      "colliders:\n"
      "  - { type: plane, normal: " +
      test::Vec(normal) + ", restitution: 0.5, friction: " + test::Num(mu) + " }\n");
}

TEST(PlaneFriction, SlidingBlockDeceleratesAtMuGThenStopsAndStays) {
  constexpr double kMu = 0.3, kV0 = 2.0, kDt = 1e-3;
  Scene scene = Slide({kV0, 0, 0}, kMu, {0, 0, 1}, {0, 0, -kPlaneG});
  System& sys = *scene.system;
  int k = 0;
  for (; k < 500; ++k) test::TakeStep(scene, k + 1, kDt);  // 0.5 s, before it stops (0.68 s)
  const double decel = (kV0 - sys.velocities()(0, 0)) / (k * kDt);
  int stopped_at = -1;
  for (; k < 1000; ++k) {
    test::TakeStep(scene, k + 1, kDt);
    if (stopped_at < 0 && sys.velocities()(0, 0) == 0.0) stopped_at = k + 1;
  }
  const Vec3 x_stop = sys.positions().col(0);
  double drift = 0.0;
  for (; k < 2000; ++k) {
    test::TakeStep(scene, k + 1, kDt);
    drift = std::max(
        {drift, (Vec3(sys.positions().col(0)) - x_stop).norm(), sys.velocities().col(0).norm()});
  }
  const double t_expected = kV0 / (kMu * kPlaneG), x_expected = kV0 * kV0 / (2 * kMu * kPlaneG);
  std::cout << "friction mu = 0.3 from 2 m/s: deceleration " << decel
            << " m/s^2 (mu g = " << kMu * kPlaneG << "), stopped at t = " << stopped_at * kDt
            << " s (" << t_expected << "), at x = " << x_stop.x() << " m (" << x_expected
            << "), drift afterwards " << drift << "\n";
  EXPECT_NEAR(decel / (kMu * kPlaneG), 1.0, 0.02);
  ASSERT_GT(stopped_at, 0) << "never stopped";
  EXPECT_NEAR(stopped_at * kDt / t_expected, 1.0, 0.02);
  EXPECT_NEAR(x_stop.x() / x_expected, 1.0, 0.02);
  EXPECT_EQ(drift, 0.0);
  EXPECT_NEAR(x_stop.z(), 0.0, 1e-4);
}

// An incline of 20 degrees (tan = 0.364): held by mu = 0.5, slides with
// g (sin a - mu cos a) for mu = 0.2.
TEST(PlaneFriction, InclineHoldsBelowTheFrictionAngleAndSlidesAbove) {
  const double a = 20.0 * std::numbers::pi / 180.0;
  const Vec3 n(0.0, std::sin(a), std::cos(a));  // the floor tilted about x: downhill is -y
  {
    Scene scene = Slide(Vec3::Zero(), 0.5, n, {0, 0, -kPlaneG});
    System& sys = *scene.system;
    double moved = 0.0;
    for (int k = 1; k <= 1000; ++k) {
      test::TakeStep(scene, k, 1e-3);
      moved = std::max(moved, sys.positions().col(0).norm() + sys.velocities().col(0).norm());
    }
    std::cout << "incline 20 deg, mu = 0.5: moved " << moved << " in 1 s\n";
    EXPECT_EQ(moved, 0.0);
  }
  {
    constexpr double kMu = 0.2;
    Scene scene = Slide(Vec3::Zero(), kMu, n, {0, 0, -kPlaneG});
    System& sys = *scene.system;
    for (int k = 1; k <= 1000; ++k) test::TakeStep(scene, k, 1e-3);
    const double accel = sys.velocities().col(0).norm() / 1.0;
    const double expected = kPlaneG * (std::sin(a) - kMu * std::cos(a));
    std::cout << "incline 20 deg, mu = 0.2: acceleration " << accel << " m/s^2, expected "
              << expected << "\n";
    EXPECT_NEAR(accel / expected, 1.0, 0.02);
    EXPECT_NEAR(sys.positions().col(0).dot(n), 0.0, 1e-4);
  }
}

// No gravity, so the resting rule stays out: V_N' = -kr V_N exactly, and the
// normal impulse per unit mass is (1 + kr) |V_N|.
TEST(PlaneFriction, ImpactTangentialImpulseIsMuTimesTheNormalImpulse) {
  const Vec3 v_in(3.0, 0.0, -2.0);
  for (double mu : {0.2, 2.0}) {
    Scene scene = Slide(v_in, mu, {0, 0, 1}, Vec3::Zero());
    scene.system->positions().col(0) = Vec3(0, 0, 0.0015);  // hits in the second step
    const test::Impact hit = test::FirstImpact(scene, 1e-3, 100);
    const double vt_expected = std::max(0.0, 3.0 - mu * (1.0 + 0.5) * 2.0);
    std::cout << "impact at (3, 0, -2) m/s, kr = 0.5, mu = " << mu
              << ": v_out = " << hit.v_out.transpose() << " (expected [" << vt_expected
              << ", 0, 1])\n";
    EXPECT_NEAR(hit.v_out.x(), vt_expected, 1e-12);
    EXPECT_NEAR(hit.v_out.z(), 1.0, 1e-12);
    EXPECT_GE(hit.v_out.x(), 0.0);  // never reversed
  }
}

// The seed plane collider, verbatim in behaviour: what friction 0 must
// reproduce bit for bit.
class SeedPlane final : public Collider {
 public:
  SeedPlane(const Vec3& point, const Vec3& normal, double kr, double eps)
      : p_(point), n_(normal.normalized()), kr_(kr), eps_(eps) {}
  void apply_contact_forces(const ParticleView& p, Eigen::Ref<Matrix3X> f) override {
    for (Index i = 0; i < p.size(); ++i) {
      if (p.fixed[i]) continue;
      const double fn = n_.dot(f.col(i));
      if (fn < 0.0 && (p.x.col(i) - p_).dot(n_) < eps_ && std::abs(n_.dot(p.v.col(i))) < eps_) {
        f.col(i) -= fn * n_;
      }
    }
  }
  void respond(MutableParticleView& p, double h) override {
    for (Index i = 0; i < p.size(); ++i) {
      if (p.fixed[i]) continue;
      const double depth = (p.x.col(i) - p_).dot(n_);
      if (depth >= eps_) continue;
      const double vn = n_.dot(p.v.col(i));
      if (vn < 0.0) {
        const double an = std::min(0.0, n_.dot(p.f.col(i)) / p.mass(i));
        const double vn_out = kr_ * -vn;
        p.v.col(i) += ((vn_out < -an * h ? 0.0 : vn_out) - vn) * n_;
      }
      if (depth < 0.0) p.x.col(i) -= depth * n_;
    }
  }

 private:
  Vec3 p_, n_;
  double kr_, eps_;
};

// A cloth with shear falling onto a tilted plane, a bouncing and a sliding
// particle: 1500 steps with friction 0 against the seed implementation.
TEST(PlaneFriction, FrictionZeroIsBitIdenticalToTheSeedPlane) {
  const std::string body = R"(
simulation: { dt: 0.002, steps: 1, solver: { type: rk4 } }
particles:
  - { position: [0, 0, 1], velocity: [0.3, 0, 0], mass: 0.2 }
  - { position: [0, 0.5, 0.2], velocity: [1, -0.5, 0], mass: 0.2 }
  - grid: { origin: [-0.3, -0.3, 0.5], u: [0.06, 0, 0.01], v: [0, 0.06, 0], nx: 8, ny: 8, mass: 0.01,
            springs: { structural: { ks: 40, kd: 0.05 }, shear: { ks: 10 } } }
forces:
  - { type: gravity, g: [0, 0, -9.81] }
)";
  Scene ours =
      test::load_text(body +
                      "colliders:\n  - { type: plane, point: [0, 0, 0.1], normal: [0, 0.1, 1], "
                      "restitution: 0.6, friction: 0, epsilon: 0.0001 }\n");
  Scene seed = test::load_text(body);
  SystemAssembly(*seed.system)
      .add_collider(std::make_shared<SeedPlane>(Vec3(0, 0, 0.1), Vec3(0, 0.1, 1), 0.6, 1e-4),
                    "seed plane");
  int differing = 0;
  for (int k = 1; k <= 1500; ++k) {
    test::TakeStep(ours, k, 2e-3);
    test::TakeStep(seed, k, 2e-3);
    if (ours.system->state() != seed.system->state()) ++differing;
  }
  const double lowest = ours.system->positions().row(2).minCoeff();
  std::cout << "friction 0 vs seed plane: " << differing << " of 1500 steps differ; lowest z "
            << lowest << " m\n";
  EXPECT_EQ(differing, 0);
  EXPECT_LT(lowest, 0.2);  // the cloth did reach the plane
}

}  // namespace
}  // namespace pdyn
