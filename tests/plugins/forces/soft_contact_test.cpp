// soft_contact (DEM, linear spring-dashpot with Coulomb friction): a
// head-on collision and a ball dropped on a nailed ball bounce with the
// configured restitution (within 2%), the force is refused without radii,
// and a heap of balls poured into a box comes to rest without deep overlaps.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "pdyn/error.hpp"
#include "pdyn/resolve.hpp"
#include "pdyn/stepper.hpp"
#include "pdyn/system.hpp"
#include "support/physics_support.hpp"
#include "support/test_support.hpp"

namespace pdyn {
namespace {

const PluginRegistry& plugins() { return test::shipped_plugins(); }

std::shared_ptr<Force> make(const char* kind_name, const System& sys, const Params& given) {
  const auto& d = *plugins().find(PluginKind::Force, kind_name)->descriptor;
  const Resolved r = resolve(d.params, given);
  EXPECT_TRUE(r.problems.empty());
  return d.create_force(r.params, SceneContext{sys.view(), nullptr});
}

std::unique_ptr<Solver> verlet(const System& sys) {
  const auto& d = *plugins().find(PluginKind::Solver, "verlet")->descriptor;
  return d.create_solver(resolve(d.params, {}).params, SceneContext{sys.view(), nullptr});
}

Params contact(double e, double mu) {
  Params p;
  p.set("stiffness", 1e5);
  p.set("restitution", e);
  p.set("friction", mu);
  return p;
}

// Two balls of radius 0.05 m and 1 kg meet head-on at 1 m/s each: the
// relative speed after / before is e.
double head_on(double e) {
  System sys;
  Matrix3X x(3, 2), v(3, 2);
  x << -0.06, 0.06, 0, 0, 0, 0;
  v << 1, -1, 0, 0, 0, 0;
  sys.set_particles(x, v, Eigen::VectorXd::Ones(2), {0, 0});
  sys.set_radii({0.05, 0.05});
  sys.add_force(make("soft_contact", sys, contact(e, 0.3)), "soft_contact");
  auto solver = verlet(sys);
  Stepper stepper(sys, *solver, "verlet");
  for (int k = 1; k <= 2000; ++k) EXPECT_TRUE(stepper.step_to(k * 1e-5).has_value());
  return (sys.velocities()(0, 1) - sys.velocities()(0, 0)) / 2.0;
}

TEST(SoftContact, AHeadOnCollisionBouncesWithTheRestitution) {
  for (const double e : {0.3, 0.5, 0.9, 1.0}) {
    const double measured = head_on(e);
    std::cout << "soft_contact head-on: e = " << e << ", measured " << measured << "\n";
    EXPECT_NEAR(measured, e, 0.02 * e);
  }
}

// A ball dropped from 0.2 m above the top of a nailed ball (gravity 9.81):
// it leaves the contact with e times its impact speed.
TEST(SoftContact, ABallDroppedOnANailedBallBouncesWithTheRestitution) {
  const double e = 0.6;
  System sys;
  Matrix3X x(3, 2);
  x << 0, 0, 0, 0, 0, 0.3;
  sys.set_particles(x, Matrix3X::Zero(3, 2), Eigen::VectorXd::Constant(2, 0.2), {1, 0});
  sys.set_radii({0.05, 0.05});
  sys.add_force(make("soft_contact", sys, contact(e, 0.0)), "soft_contact");
  Params g;
  g.set("g", Vec3(0, 0, -9.81));
  sys.add_force(make("gravity", sys, g), "gravity");
  auto solver = verlet(sys);
  Stepper stepper(sys, *solver, "verlet");
  double impact = 0.0, rebound = 0.0;
  bool touching = false;
  for (int k = 1; k <= 30000 && rebound == 0.0; ++k) {
    const double vz = sys.velocities()(2, 1);
    ASSERT_TRUE(stepper.step_to(k * 1e-5).has_value());
    const bool now = sys.positions()(2, 1) < 0.1;
    if (now && !touching) impact = -vz;
    if (!now && touching) rebound = sys.velocities()(2, 1);
    touching = now;
  }
  const double expected_impact = std::sqrt(2 * 9.81 * 0.2);
  EXPECT_NEAR(impact, expected_impact, 1e-3 * expected_impact);
  std::cout << "soft_contact drop: impact " << impact << " m/s, rebound " << rebound
            << " m/s, ratio " << rebound / impact << " (e = " << e << ")\n";
  EXPECT_NEAR(rebound / impact, e, 0.02 * e);
}

TEST(SoftContact, WithoutRadiiTheForceIsRefusedNamingTheKey) {
  System sys;
  sys.set_particles(Matrix3X::Zero(3, 2), Matrix3X::Zero(3, 2), Eigen::VectorXd::Ones(2), {0, 0});
  try {
    make("soft_contact", sys, Params{});
    ADD_FAILURE() << "no error";
  } catch (const ParamError& e) {
    EXPECT_EQ(e.param(), "radius");
    EXPECT_EQ(std::string(e.what()),
              "is needed: no particle has a radius (expected `radius:` on the particles, "
              "`particle_radius:` on a builder, or this force's `radius:`)");
  }
  Params given;
  given.set("radius", 0.1);  // the force's own radius for every particle
  EXPECT_NE(make("soft_contact", sys, given), nullptr);
}

// 125 balls (radius 0.05 m, 0.1 kg) poured into a box 0.4 m wide under
// gravity: after 6 s the kinetic energy is below 1e-5 of the potential
// energy they lost (measured 2.7e-6: an rms speed of about 3 mm/s, the
// creep that history-free friction allows), and no pair overlaps by more
// than 5% of the radius (measured 0.6%).
TEST(SoftContact, APouredHeapComesToRestWithoutDeepOverlaps) {
  const double radius = 0.05;
  std::string particles;
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> jitter(-0.005, 0.005);
  for (int a = 0; a < 5; ++a)
    for (int b = 0; b < 5; ++b)
      for (int c = 0; c < 5; ++c) {
        particles += "  - { position: " +
                     test::Vec(Vec3(-0.16 + 0.08 * a + jitter(rng), -0.16 + 0.08 * b + jitter(rng),
                                    0.1 + 0.12 * c)) +
                     ", mass: 0.1 }\n";
      }
  Scene scene = test::load_text(
      "simulation: { dt: 0.0002, steps: 1, solver: { type: verlet } }\n"
      "particles:\n" +
      particles +
      "forces:\n"
      "  - { type: gravity, g: [0, 0, -9.81] }\n"
      "  - { type: soft_contact, radius: 0.05, stiffness: 2e4, restitution: 0.3, friction: 0.5 }\n"
      "colliders:\n"
      "  - { type: box, min: [-0.25, -0.25, 0.05], max: [0.25, 0.25, 2], inside: true, "
      "restitution: 0.3, friction: 0.5 }\n");
  System& sys = *scene.system;
  const double z0 = sys.positions().row(2).sum();
  Stepper stepper(sys, *scene.solver, scene.solver_label);
  for (int k = 1; k <= 30000; ++k) ASSERT_TRUE(stepper.step_to(k * 0.0002).has_value()) << k;
  const double lost = 0.1 * 9.81 * (z0 - sys.positions().row(2).sum());
  double worst = 0.0;
  for (Index i = 0; i < sys.size(); ++i) {
    for (Index j = i + 1; j < sys.size(); ++j) {
      worst =
          std::max(worst, 2 * radius - (sys.positions().col(i) - sys.positions().col(j)).norm());
    }
  }
  std::cout << "soft_contact heap: kinetic " << sys.kinetic_energy() << " J after losing " << lost
            << " J; deepest overlap " << worst / radius << " radius\n";
  EXPECT_GT(lost, 0.5);
  EXPECT_LT(sys.kinetic_energy(), 1e-5 * lost);
  EXPECT_LT(worst, 0.05 * radius);
}

}  // namespace
}  // namespace pdyn
