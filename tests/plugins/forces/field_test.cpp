// The field plugin (forces from expressions, muParser), checked against
// closed-form solutions:
//  - f = -k x in all three components, one particle of mass m: an isotropic
//    harmonic oscillator, x(t) = x0 cos(w t) + v0/w sin(w t), w = sqrt(k/m),
//    followed by rk4 to t = 10 s; the reported potential k |x|^2 / 2 keeps
//    the total energy constant;
//  - f = -m w^2 x uses the variable m: two particles of different masses
//    move alike;
//  - f = [A sin(w t), 0, 0] from rest: x(t) = A/(m w) (t - sin(w t)/w);
//  - f = -c vx: vx(t) = vx0 exp(-c t / m);
//  - bad expressions and constants are refused with their position.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

#include "pdyn/host/scene.hpp"
#include "plugins/forces/force_support.hpp"

namespace pdyn {
namespace {

std::string FieldMessage(const std::string& yaml) {
  try {
    test::load_text(yaml);
  } catch (const SceneError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(FieldForce, HarmonicFieldMatchesTheAnalyticOscillator) {
  const double k = 2.0, m = 0.5, w = std::sqrt(k / m), h = 0.01;
  const Vec3 x0(1.0, 0.0, -0.5), v0(0.0, 0.6, 0.2);
  Scene scene = test::load_text(
      "simulation: { dt: 0.01, steps: 1000, solver: { type: rk4 } }\n"
      "particles:\n  - { position: " +
      test::Vec(x0) + ", velocity: " + test::Vec(v0) +
      ", mass: 0.5 }\n"
      "forces:\n  - { type: field, constants: { k: 2 }, force: [\"-k*x\", \"-k*y\", \"-k*z\"],"
      " potential: \"k*(x^2 + y^2 + z^2)/2\" }\n");
  System& sys = *scene.system;
  const double e0 = sys.kinetic_energy() + sys.potential_energy();
  EXPECT_NEAR(e0, 0.5 * m * v0.squaredNorm() + 0.5 * k * x0.squaredNorm(), 1e-15);
  double worst = 0.0, drift = 0.0;
  for (int s = 1; s <= 1000; ++s) {
    test::TakeStep(scene, s, h);
    const double t = s * h;
    const Vec3 exact = x0 * std::cos(w * t) + v0 / w * std::sin(w * t);
    worst = std::max(worst, (Vec3(sys.positions().col(0)) - exact).norm());
    drift = std::max(drift, std::abs(sys.kinetic_energy() + sys.potential_energy() - e0));
  }
  std::cout << "field harmonic oscillator, rk4 h = 0.01 s to 10 s: max |x - x_exact| = " << worst
            << " m, max |E - E0| = " << drift << " J\n";
  // rk4's global error ~ t h^4 w^5 / 120 ~ 4e-8 m here.
  EXPECT_LE(worst, 2e-7);
  EXPECT_LE(drift, 1e-7);
}

TEST(FieldForce, MassVariableGivesTheSameMotionForEveryMass) {
  Scene scene = test::load_text(R"(
simulation: { dt: 0.01, steps: 100, solver: { type: rk4 } }
particles:
  - { position: [1, 0, 0], mass: 0.25 }
  - { position: [1, 0, 0], mass: 4 }
forces:
  - { type: field, constants: { w: 3 }, force: ["-m*w^2*x", "0", "0"] }
)");
  for (int s = 1; s <= 100; ++s) test::TakeStep(scene, s, 0.01);
  const auto& x = scene.system->positions();
  EXPECT_NEAR(x(0, 0), x(0, 1), 1e-15);
  EXPECT_NEAR(x(0, 0), std::cos(3.0), 1e-7);
}

TEST(FieldForce, TimeDependentFieldMatchesTheHandIntegration) {
  const double A = 3.0, w = 2.0, m = 1.5, h = 0.005;
  Scene scene = test::load_text(R"yaml(
simulation: { dt: 0.005, steps: 800, solver: { type: rk4 } }
particles:
  - { position: [0, 0, 0], mass: 1.5 }
forces:
  - type: field
    constants: { A: 3, w: 2 }
    force: ["A*sin(w*t)", "0", "0"]
)yaml");
  double worst = 0.0;
  for (int s = 1; s <= 800; ++s) {
    test::TakeStep(scene, s, h);
    const double t = s * h;
    const double exact = A / (m * w) * (t - std::sin(w * t) / w);
    worst = std::max(worst, std::abs(scene.system->positions()(0, 0) - exact));
  }
  std::cout << "field A sin(w t), rk4 h = 0.005 s to 4 s: max |x - x_exact| = " << worst << " m\n";
  EXPECT_LE(worst, 1e-9);
  EXPECT_EQ(scene.system->positions()(1, 0), 0.0);
}

TEST(FieldForce, VelocityVariableGivesExponentialDecay) {
  Scene scene = test::load_text(R"(
simulation: { dt: 0.01, steps: 100, solver: { type: rk4 } }
particles:
  - { position: [0, 0, 0], velocity: [2, 0, 0], mass: 0.5 }
forces:
  - { type: field, constants: { c: 0.25 }, force: ["-c*vx", "0", "0"] }
)");
  for (int s = 1; s <= 100; ++s) test::TakeStep(scene, s, 0.01);
  EXPECT_NEAR(scene.system->velocities()(0, 0), 2.0 * std::exp(-0.25 * 1.0 / 0.5), 1e-9);
}

const char* kOne =
    "simulation: { dt: 0.01, steps: 1 }\nparticles:\n  - { position: [0, 0, 0], "
    "mass: 1 }\nforces:\n";

TEST(FieldForce, RefusesBadExpressionsWithTheirPosition) {
  EXPECT_EQ(
      FieldMessage(std::string(kOne) +
                   "  - { type: field, constants: { k: 4 }, force: [\"0\", \"-k**y\", \"0\"] }\n"),
      "test.yaml:5:54: forces[0].force[1]: unexpected operator '*' at position 3 in "
      "\"-k**y\" (expected an expression in the variables x, y, z, vx, vy, vz, t, m or the "
      "constants k and functions such as sin, exp, sqrt; a power is written x^2, not "
      "x**2)");
  EXPECT_EQ(
      FieldMessage(std::string(kOne) + "  - { type: field, force: [\"q*x\", \"0\", \"0\"] }\n"),
      "test.yaml:5:28: forces[0].force[0]: unknown variable 'q' at position 0 in \"q*x\" "
      "(expected one of the variables x, y, z, vx, vy, vz, t, m)");
  const std::string few =
      FieldMessage(std::string(kOne) + "  - { type: field, force: [\"x\", \"y\"] }\n");
  EXPECT_NE(few.find("forces[0].force: has 2 expressions (expected 3: [fx, fy, fz], in N)"),
            std::string::npos)
      << few;
  const std::string clash =
      FieldMessage(std::string(kOne) +
                   "  - { type: field, constants: { x: 1 }, force: [\"x\", \"0\", \"0\"] }\n");
  EXPECT_NE(
      clash.find("test.yaml:5:31: forces[0].constants: constant 'x' is named like a variable"),
      std::string::npos)
      << clash;
  const std::string open =
      FieldMessage(std::string(kOne) + "  - { type: field, force: [\"sin(x\", \"0\", \"0\"] }\n");
  EXPECT_NE(open.find("forces[0].force[0]: "), std::string::npos) << open;
  EXPECT_NE(open.find("in \"sin(x\""), std::string::npos) << open;
  const std::string two =
      FieldMessage(std::string(kOne) + "  - { type: field, force: [\"1, 2\", \"0\", \"0\"] }\n");
  EXPECT_NE(two.find("forces[0].force[0]: \"1, 2\" gives 2 values"), std::string::npos) << two;
  const std::string key =
      FieldMessage(std::string(kOne) +
                   "  - { type: field, constants: { 2k: 1 }, force: [\"0\", \"0\", \"0\"] }\n");
  EXPECT_NE(key.find("forces[0].constants: '2k' is not a name"), std::string::npos) << key;
}

}  // namespace
}  // namespace pdyn
