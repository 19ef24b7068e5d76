// A particle on Witkin's damped spring tied to a fixed particle, moving along
// the spring's axis, against the closed-form underdamped oscillator of
// support/oscillator.hpp.
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

#include "support/oscillator.hpp"
#include "support/test_support.hpp"

namespace pdyn {
namespace {

constexpr double kDampedDt = 1e-3;   // s
constexpr int kDampedSteps = 5000;   // 5 s, about five periods
constexpr double kTolerance = 1e-9;  // m and m/s; rk4 achieves ~1.5e-10 here

// m = 0.5 kg, ks = 20 N/m, kd = 0.4 N s/m, r = 1 m; initial stretch 0.3 m
// and stretch rate 0.5 m/s along `axis`, anchored at `anchor`.
test::Oscillator Damped(const Vec3& anchor, const Vec3& axis) {
  test::Oscillator o = test::Oscillator::Along(axis, 0.3, 0.5);
  o.mass = 0.5;
  o.ks = 20.0;
  o.kd = 0.4;
  o.rest = 1.0;
  o.anchor = anchor;
  return o;
}

std::string Timing() {
  return "dt: " + test::Num(kDampedDt) + ", steps: " + std::to_string(kDampedSteps);
}

// Runs the oscillator along `axis` (anchored at `anchor`) and returns the
// largest deviation from the closed form, max over steps of the position
// and velocity errors.
double MaxDeviation(const Vec3& anchor, const Vec3& axis) {
  const test::Oscillator exact = Damped(anchor, axis);
  Scene scene = test::load_text(exact.scene("{ type: rk4 }", Timing()));
  System& sys = *scene.system;
  double worst = 0.0, min_length = exact.rest;
  for (int k = 1; k <= kDampedSteps; ++k) {
    test::TakeStep(scene, k, kDampedDt);
    const double t = k * kDampedDt;
    worst = std::max({worst, (sys.positions().col(1) - exact.x(t)).lpNorm<Eigen::Infinity>(),
                      (sys.velocities().col(1) - exact.v(t)).lpNorm<Eigen::Infinity>()});
    min_length = std::min(min_length, (sys.positions().col(1) - anchor).norm());
    // The anchor is nailed: it must not move at all.
    EXPECT_EQ(sys.positions().col(0), anchor) << "step " << k;
  }
  EXPECT_GT(min_length, 0.5 * exact.rest);  // the premise of the 1-D closed form
  return worst;
}

TEST(DampedOscillator, Rk4MatchesTheUnderdampedClosedFormAlongX) {
  const double d = MaxDeviation(Vec3::Zero(), Vec3::UnitX());
  std::cout << "rk4 damped oscillator along x, dt = " << kDampedDt << ": max deviation " << d
            << "\n";
  EXPECT_LT(d, kTolerance);
}

// The same motion along an oblique axis from an anchor off the origin: the
// spring's vector algebra (dx, dv . dx / L, dx / L) must not favour an axis.
TEST(DampedOscillator, Rk4MatchesTheUnderdampedClosedFormAlongAnObliqueAxis) {
  const double d = MaxDeviation(Vec3(1.0, -2.0, 0.5), Vec3(1.0, 2.0, -2.0));
  std::cout << "rk4 damped oscillator along (1, 2, -2)/3, dt = " << kDampedDt << ": max deviation "
            << d << "\n";
  EXPECT_LT(d, kTolerance);
}

// The kernel's energy report (kinetic + the spring's potential) against the
// closed form's E(t) = m u'(t)^2 / 2 + ks u(t)^2 / 2 at every step. Damping
// only removes energy, dE/dt = -kd u'^2 <= 0, so E must never increase.
TEST(DampedOscillator, ReportedEnergyMatchesTheClosedForm) {
  const test::Oscillator exact = Damped(Vec3::Zero(), Vec3::UnitX());
  Scene scene = test::load_text(exact.scene("{ type: rk4 }", Timing()));
  System& sys = *scene.system;
  EXPECT_NEAR(sys.kinetic_energy() + sys.potential_energy(), exact.energy(0.0), 1e-14);
  double previous = exact.energy(0.0);
  for (int k = 1; k <= kDampedSteps; ++k) {
    test::TakeStep(scene, k, kDampedDt);
    const double e = sys.kinetic_energy() + sys.potential_energy();
    EXPECT_NEAR(e, exact.energy(k * kDampedDt), 1e-9) << "step " << k;
    EXPECT_LE(e, previous + 1e-12) << "damping must not add energy, step " << k;
    previous = e;
  }
}

}  // namespace
}  // namespace pdyn
