// A particle on Witkin's damped spring tied to a fixed particle, moving along
// the spring's axis, against the closed-form underdamped oscillator.
//
// With the free particle at a + e (r + u) (anchor a, unit axis e, rest
// length r) and its velocity along e, the spring force is -(ks u + kd u') e,
// so the stretch u obeys m u'' + kd u' + ks u = 0, whose underdamped
// solution is
//   u(t) = e^{-gamma t} (A cos(w_d t) + B sin(w_d t)),
//   gamma = kd / (2 m),  w_d = sqrt(ks / m - gamma^2),
//   A = u0,  B = (u0' + gamma u0) / w_d.
// The amplitude stays well below r, so the spring never passes through zero
// length (where its direction, and this 1-D reduction, would break down).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>

#include "support/physics_support.hpp"
#include "support/test_support.hpp"

namespace pdyn {
namespace {

constexpr double kMass = 0.5;        // kg
constexpr double kKs = 20.0;         // N/m
constexpr double kKd = 0.4;          // N s/m
constexpr double kRest = 1.0;        // m
constexpr double kU0 = 0.3;          // initial stretch, m
constexpr double kUDot0 = 0.5;       // initial stretch rate, m/s
constexpr double kDt = 1e-3;         // s
constexpr int kSteps = 5000;         // 5 s, about five periods
constexpr double kTolerance = 1e-9;  // m and m/s; rk4 achieves ~1.5e-10 here

struct Oscillator {
  double gamma = kKd / (2.0 * kMass);
  double wd = std::sqrt(kKs / kMass - gamma * gamma);
  double a = kU0;
  double b = (kUDot0 + gamma * kU0) / wd;

  double u(double t) const {
    return std::exp(-gamma * t) * (a * std::cos(wd * t) + b * std::sin(wd * t));
  }
  double u_dot(double t) const {
    return std::exp(-gamma * t) *
           ((b * wd - gamma * a) * std::cos(wd * t) - (a * wd + gamma * b) * std::sin(wd * t));
  }
};

// Runs the oscillator along `axis` (anchored at `anchor`) and returns the
// largest deviation from the closed form, max over steps of the position
// and velocity errors.
double MaxDeviation(const Vec3& anchor, const Vec3& axis) {
  const Vec3 e = axis.normalized();
  Scene scene = test::load_text(
      "simulation: { dt: " + test::Num(kDt) + ", steps: " + std::to_string(kSteps) +
      ", solver: { type: rk4 } }\n"
      "particles:\n"
      "  - { position: " +
      test::Vec(anchor) +
      ", mass: 1, fixed: true }\n"
      "  - { position: " +
      test::Vec(anchor + (kRest + kU0) * e) + ", velocity: " + test::Vec(kUDot0 * e) +
      ", mass: " + test::Num(kMass) +
      " }\n"
      "forces:\n"
      "  - { type: spring, pairs: [[1, 0]], ks: " +
      test::Num(kKs) + ", kd: " + test::Num(kKd) + ", rest: [" + test::Num(kRest) + "] }\n");
  System& sys = *scene.system;
  const Oscillator exact;
  double worst = 0.0, min_length = kRest;
  for (int k = 1; k <= kSteps; ++k) {
    test::TakeStep(scene, k, kDt);
    const double t = k * kDt;
    const Vec3 x = anchor + (kRest + exact.u(t)) * e;
    const Vec3 v = exact.u_dot(t) * e;
    worst = std::max({worst, (sys.positions().col(1) - x).lpNorm<Eigen::Infinity>(),
                      (sys.velocities().col(1) - v).lpNorm<Eigen::Infinity>()});
    min_length = std::min(min_length, (sys.positions().col(1) - anchor).norm());
    // The anchor is nailed: it must not move at all.
    EXPECT_EQ(sys.positions().col(0), anchor) << "step " << k;
  }
  EXPECT_GT(min_length, 0.5 * kRest);  // the premise of the 1-D closed form
  return worst;
}

TEST(DampedOscillator, Rk4MatchesTheUnderdampedClosedFormAlongX) {
  const double d = MaxDeviation(Vec3::Zero(), Vec3::UnitX());
  std::cout << "rk4 damped oscillator along x, dt = " << kDt << ": max deviation " << d << "\n";
  EXPECT_LT(d, kTolerance);
}

// The same motion along an oblique axis from an anchor off the origin: the
// spring's vector algebra (dx, dv . dx / L, dx / L) must not favour an axis.
TEST(DampedOscillator, Rk4MatchesTheUnderdampedClosedFormAlongAnObliqueAxis) {
  const double d = MaxDeviation(Vec3(1.0, -2.0, 0.5), Vec3(1.0, 2.0, -2.0));
  std::cout << "rk4 damped oscillator along (1, 2, -2)/3, dt = " << kDt << ": max deviation " << d
            << "\n";
  EXPECT_LT(d, kTolerance);
}

// The kernel's energy report (kinetic + the spring's potential) against the
// closed form's E(t) = m u'(t)^2 / 2 + ks u(t)^2 / 2 at every step. Damping
// only removes energy, dE/dt = -kd u'^2 <= 0, so E must never increase.
TEST(DampedOscillator, ReportedEnergyMatchesTheClosedForm) {
  Scene scene = test::load_text(
      "simulation: { dt: " + test::Num(kDt) + ", steps: " + std::to_string(kSteps) +
      ", solver: { type: rk4 } }\n"
      "particles:\n"
      "  - { position: [0, 0, 0], mass: 1, fixed: true }\n"
      "  - { position: [" +
      test::Num(kRest + kU0) + ", 0, 0], velocity: [" + test::Num(kUDot0) +
      ", 0, 0], mass: " + test::Num(kMass) +
      " }\n"
      "forces:\n"
      "  - { type: spring, pairs: [[0, 1]], ks: " +
      test::Num(kKs) + ", kd: " + test::Num(kKd) + ", rest: [" + test::Num(kRest) + "] }\n");
  System& sys = *scene.system;
  const Oscillator exact;
  auto energy = [&](double t) {
    return 0.5 * kMass * exact.u_dot(t) * exact.u_dot(t) + 0.5 * kKs * exact.u(t) * exact.u(t);
  };
  EXPECT_NEAR(sys.kinetic_energy() + sys.potential_energy(), energy(0.0), 1e-14);
  double previous = energy(0.0);
  for (int k = 1; k <= kSteps; ++k) {
    test::TakeStep(scene, k, kDt);
    const double e = sys.kinetic_energy() + sys.potential_energy();
    EXPECT_NEAR(e, energy(k * kDt), 1e-9) << "step " << k;
    EXPECT_LE(e, previous + 1e-12) << "damping must not add energy, step " << k;
    previous = e;
  }
}

}  // namespace
}  // namespace pdyn
