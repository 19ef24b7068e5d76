// The force plugins' physical laws, checked on random states:
//  - spring (Witkin's damped spring): an internal, central force, so the
//    forces on all particles sum to zero (momentum) and so do their moments
//    sum x_i x f_i (angular momentum); with kd = 0 it is conservative, f =
//    -grad U for the potential U = ks (L - r)^2 / 2 it reports; coincident
//    ends (no direction) add nothing, and never NaN.
//  - gravity: f = m g and f = -grad U for U = -sum m g.x.
//  - drag: f = -k v, so f.v = -k |v|^2 <= 0 (it never does positive work).
// Every force must also only add into the accumulator it is handed.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <iomanip>
#include <iostream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "pdyn/system.hpp"
#include "plugins/forces/force_support.hpp"
#include "support/test_support.hpp"

namespace pdyn {
namespace {

using test::Cloud;

// The forces (3 x N) that force object `index` of `sys` alone adds to zero.
Matrix3X ForcesOf(const System& sys, std::size_t index) {
  Matrix3X f = Matrix3X::Zero(3, sys.size());
  sys.force_objects().at(index).force->add_forces(sys.view(), f);
  return f;
}

// -grad U of force object `index` by central differences of its reported
// potential energy, step `h` in every coordinate of every particle.
Matrix3X MinusGradient(System& sys, std::size_t index, double h) {
  const Force& force = *sys.force_objects().at(index).force;
  Matrix3X g(3, sys.size());
  for (Index i = 0; i < sys.size(); ++i) {
    for (int c = 0; c < 3; ++c) {
      const double saved = sys.positions()(c, i);
      sys.positions()(c, i) = saved + h;
      const double up = force.potential_energy(sys.view()).value();
      sys.positions()(c, i) = saved - h;
      const double down = force.potential_energy(sys.view()).value();
      sys.positions()(c, i) = saved;
      g(c, i) = -(up - down) / (2.0 * h);
    }
  }
  return g;
}

// Largest column norm: the scale relative errors are measured against.
double MaxNorm(const Matrix3X& f) { return f.colwise().norm().maxCoeff(); }

// A random spring network on `cloud`: `count` distinct pairs with random
// rest lengths, as one spring force object.
std::string RandomSprings(Cloud& cloud, int count, double ks, double kd) {
  const int n = static_cast<int>(cloud.x.size());
  std::uniform_int_distribution<int> pick(0, n - 1);
  std::uniform_real_distribution<double> rest(0.2, 1.5);
  std::string pairs, rests;
  for (int s = 0; s < count; ++s) {
    int i = pick(cloud.rng), j = pick(cloud.rng);
    while (j == i) j = pick(cloud.rng);
    pairs += (s ? ", [" : "[") + std::to_string(i) + ", " + std::to_string(j) + "]";
    rests += (s ? ", " : "") + test::Num(rest(cloud.rng));
  }
  return "  - { type: spring, pairs: [" + pairs + "], ks: " + test::Num(ks) +
         ", kd: " + test::Num(kd) + ", rest: [" + rests + "] }\n";
}

TEST(SpringForce, ConservesMomentumAndAngularMomentum) {
  for (unsigned seed : {1u, 2u, 3u}) {
    Cloud cloud(8, seed);
    const std::string springs = RandomSprings(cloud, 14, 30.0, 2.5);  // kd > 0: damped
    Scene scene = test::load_text(cloud.Yaml() + "forces:\n" + springs);
    const System& sys = *scene.system;
    const Matrix3X f = ForcesOf(sys, 0);
    ASSERT_GT(MaxNorm(f), 1.0) << "the random springs should be far from rest";
    // Scales for "relative": the sum of magnitudes each sum is made of.
    double f_scale = 0.0, torque_scale = 0.0;
    Vec3 momentum = Vec3::Zero(), torque = Vec3::Zero();
    for (Index i = 0; i < sys.size(); ++i) {
      momentum += f.col(i);
      torque += sys.positions().col(i).cross(f.col(i));
      f_scale += f.col(i).norm();
      torque_scale += sys.positions().col(i).norm() * f.col(i).norm();
    }
    std::cout << "springs, seed " << seed << ": |sum f| / sum |f| = " << momentum.norm() / f_scale
              << ", |sum x x f| / sum |x||f| = " << torque.norm() / torque_scale << "\n";
    EXPECT_LE(momentum.norm(), 1e-12 * f_scale) << "seed " << seed;
    EXPECT_LE(torque.norm(), 1e-12 * torque_scale) << "seed " << seed;
  }
}

TEST(SpringForce, UndampedForceIsMinusTheGradientOfItsPotential) {
  for (unsigned seed : {4u, 5u, 6u}) {
    Cloud cloud(8, seed);
    const std::string springs = RandomSprings(cloud, 14, 30.0, 0.0);
    Scene scene = test::load_text(cloud.Yaml() + "forces:\n" + springs);
    System& sys = *scene.system;
    const Matrix3X f = ForcesOf(sys, 0);
    const Matrix3X minus_grad = MinusGradient(sys, 0, 1e-6);
    // Central differences err by O(h^2 U''') + O(eps U / h), ~1e-9 here.
    const double rel = MaxNorm(f - minus_grad) / MaxNorm(f);
    std::cout << "springs, seed " << seed << ": max |f + grad U| / max |f| = " << rel << "\n";
    EXPECT_LE(rel, 1e-6) << "seed " << seed;
  }
}

// The reported potential is ks (L - r)^2 / 2 per spring, checked on one
// spring whose length is known exactly.
TEST(SpringForce, PotentialIsHalfKsStretchSquared) {
  Scene scene = test::load_text(R"(
simulation: { dt: 0.001, steps: 1 }
particles:
  - { position: [0, 0, 0], mass: 1 }
  - { position: [3, 4, 0], mass: 1 }
forces:
  - { type: spring, pairs: [[0, 1]], ks: 8, rest: [4.5] }
)");
  // L = 5, stretch 0.5: U = 8 * 0.25 / 2 = 1 J; |f| = ks (L - r) = 4 N along
  // (3, 4)/5, pulling particle 0 towards particle 1.
  EXPECT_DOUBLE_EQ(scene.system->potential_energy(), 1.0);
  const Matrix3X f = ForcesOf(*scene.system, 0);
  EXPECT_NEAR((f.col(0) - Vec3(2.4, 3.2, 0.0)).norm(), 0.0, 1e-15);
  EXPECT_NEAR((f.col(1) + Vec3(2.4, 3.2, 0.0)).norm(), 0.0, 1e-15);
}

// Two coincident particles: the spring has no direction. Whether its rest
// length is 0 (the default: the initial distance) or not, it must add
// nothing, produce no NaN, and let a solver step on.
TEST(SpringForce, ZeroLengthSpringAddsNoForceAndNoNaN) {
  for (const char* rest : {"", ", rest: [0.5]"}) {
    Scene scene = test::load_text(std::string(R"(
simulation: { dt: 0.001, steps: 10, solver: { type: rk4 } }
particles:
  - { position: [0.3, -0.2, 0.7], velocity: [1, 0, 0], mass: 1 }
  - { position: [0.3, -0.2, 0.7], velocity: [0, 2, 0], mass: 2 }
forces:
  - { type: spring, pairs: [[0, 1]], ks: 50, kd: 3)") +
                                  rest + " }\n");
    System& sys = *scene.system;
    const Matrix3X f = ForcesOf(sys, 0);
    EXPECT_TRUE(f.allFinite()) << "rest" << rest;
    EXPECT_EQ(f, Matrix3X::Zero(3, 2)) << "rest" << rest;
    EXPECT_TRUE(std::isfinite(sys.potential_energy())) << "rest" << rest;
    Eigen::VectorXd dydt(sys.dimension());
    sys.derivative(dydt);
    EXPECT_TRUE(dydt.allFinite()) << "rest" << rest;
    for (int k = 1; k <= 10; ++k) scene.solver->step(sys, 0.001);
    EXPECT_TRUE(sys.state().allFinite()) << "rest" << rest;
  }
}

TEST(GravityForce, IsMassTimesGAndMinusTheGradientOfItsPotential) {
  Cloud cloud(6, 7);
  const Vec3 g(0.3, -0.2, -9.81);
  Scene scene =
      test::load_text(cloud.Yaml() + "forces:\n  - { type: gravity, g: " + test::Vec(g) + " }\n");
  System& sys = *scene.system;
  const Matrix3X f = ForcesOf(sys, 0);
  double u = 0.0;
  for (Index i = 0; i < sys.size(); ++i) {
    const double m = cloud.m[static_cast<std::size_t>(i)];
    EXPECT_NEAR((f.col(i) - m * g).norm(), 0.0, 1e-14 * m * g.norm()) << "particle " << i;
    u -= m * g.dot(sys.positions().col(i));
  }
  // U = -sum m g.x (its zero is at the origin, as the plugin documents).
  EXPECT_NEAR(sys.potential_energy(), u, 1e-13);
  EXPECT_LE(MaxNorm(f - MinusGradient(sys, 0, 1e-6)), 1e-6 * MaxNorm(f));
}

TEST(DragForce, IsMinusKVAndNeverDoesPositiveWork) {
  Cloud cloud(6, 8);
  constexpr double kDrag = 0.7;
  Scene scene =
      test::load_text(cloud.Yaml() + "forces:\n  - { type: drag, k: " + test::Num(kDrag) + " }\n");
  const System& sys = *scene.system;
  const Matrix3X f = ForcesOf(sys, 0);
  for (Index i = 0; i < sys.size(); ++i) {
    const Vec3 v = sys.velocities().col(i);
    EXPECT_NEAR((f.col(i) + kDrag * v).norm(), 0.0, 1e-15 * kDrag * v.norm()) << "particle " << i;
    EXPECT_LE(f.col(i).dot(v), 0.0) << "particle " << i;
  }
  // Drag has no potential: the kernel's energy report must not invent one.
  EXPECT_FALSE(sys.force_objects()[0].force->potential_energy(sys.view()).has_value());
}

// The Force contract: add_forces adds into `f`, it never overwrites what
// other force objects put there first.
TEST(ForcePlugins, OnlyAddIntoTheAccumulator) {
  Cloud cloud(6, 9);
  const std::string springs = RandomSprings(cloud, 8, 10.0, 1.0);
  Scene scene = test::load_text(cloud.Yaml() + "forces:\n" + springs +
                                "  - { type: gravity }\n  - { type: drag, k: 0.3 }\n");
  const System& sys = *scene.system;
  std::mt19937 rng(10);
  std::uniform_real_distribution<double> junk(-5.0, 5.0);
  Matrix3X before(3, sys.size());
  for (Index i = 0; i < before.size(); ++i) before.data()[i] = junk(rng);
  for (std::size_t k = 0; k < sys.force_objects().size(); ++k) {
    const Matrix3X alone = ForcesOf(sys, k);
    Matrix3X f = before;
    sys.force_objects()[k].force->add_forces(sys.view(), f);
    EXPECT_LE(MaxNorm(f - before - alone), 1e-13 * (MaxNorm(before) + MaxNorm(alone)))
        << sys.force_objects()[k].label;
  }
}

}  // namespace
}  // namespace pdyn
