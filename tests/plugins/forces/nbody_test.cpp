// nbody: a two-body Kepler orbit (eccentricity 0.5) closes after one period
// with verlet and rk45 to stated tolerances, conserving energy and momentum;
// forces are bit-identical for 1-4 threads on a cluster of 5,000 bodies.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "pdyn/parallel.hpp"
#include "pdyn/resolve.hpp"
#include "pdyn/stepper.hpp"
#include "support/physics_support.hpp"
#include "support/test_support.hpp"

namespace pdyn {
namespace {

constexpr double kM1 = 1.0, kM2 = 1e-3, kA = 1.0, kE = 0.5;  // G = 1 units

double period() { return 2 * std::numbers::pi * std::sqrt(kA * kA * kA / (kM1 + kM2)); }

// Both bodies at pericentre, centre of mass at rest at the origin.
Scene kepler(const std::string& solver, double dt) {
  const double m = kM1 + kM2, rp = kA * (1 - kE);
  const double vp = std::sqrt(m * (1 + kE) / (kA * (1 - kE)));
  const Vec3 r(rp, 0, 0), v(0, vp, 0);
  return test::load_text("simulation: { dt: " + test::Num(dt) + ", steps: 1, solver: " + solver +
                         " }\nparticles:\n  - { position: " + test::Vec(-kM2 / m * r) +
                         ", velocity: " + test::Vec(-kM2 / m * v) + ", mass: " + test::Num(kM1) +
                         " }\n  - { position: " + test::Vec(kM1 / m * r) +
                         ", velocity: " + test::Vec(kM1 / m * v) + ", mass: " + test::Num(kM2) +
                         " }\nforces:\n  - { type: nbody, G: 1 }\n");
}

struct Closure {
  double position, energy, momentum;
};

Closure one_period(Scene& s, int steps) {
  System& sys = *s.system;
  const Matrix3X x0 = sys.positions();
  const double e0 = sys.kinetic_energy() + sys.potential_energy();
  Stepper stepper(sys, *s.solver, s.solver_label);
  const double t = period();
  if (s.solver->adaptive()) {
    EXPECT_TRUE(stepper.advance(t, t / 100).has_value());
    while (sys.time() < t) EXPECT_TRUE(stepper.advance(t, t / 100).has_value());
  } else {
    for (int k = 1; k <= steps; ++k) EXPECT_TRUE(stepper.step_to(t * k / steps).has_value());
  }
  const Vec3 p = sys.velocities() * sys.masses();
  return {(sys.positions() - x0).colwise().norm().maxCoeff() / kA,
          std::abs(sys.kinetic_energy() + sys.potential_energy() - e0) / std::abs(e0), p.norm()};
}

TEST(NBody, AKeplerOrbitClosesAfterOnePeriod) {
  Scene verlet = kepler("{ type: verlet }", period() / 4000);
  const Closure v = one_period(verlet, 4000);
  Scene rk45 = kepler("{ type: rk45, rtol: 1e-10, atol: 1e-12 }", period() / 100);
  const Closure r = one_period(rk45, 0);
  std::cout << "Kepler e = 0.5, one period: verlet (4000 steps) closes to " << v.position
            << " a, |dE/E| " << v.energy << "; rk45 (rtol 1e-10) to " << r.position << " a, |dE/E| "
            << r.energy << "\n";
  // Measured: verlet 1.1e-4 a and 3.7e-13, rk45 4.3e-9 a and 1.6e-10.
  EXPECT_LT(v.position, 3e-4);
  EXPECT_LT(v.energy, 1e-10);
  EXPECT_LT(r.position, 2e-8);
  EXPECT_LT(r.energy, 1e-9);
  EXPECT_LT(v.momentum, 1e-15);
  EXPECT_LT(r.momentum, 1e-15);
}

TEST(NBody, ForcesAreBitIdenticalForOneToFourThreads) {
  std::string particles;
  std::mt19937 rng(4);
  std::normal_distribution<double> u(0.0, 1.0);
  for (int i = 0; i < 5000; ++i) {
    particles +=
        "  - { position: " + test::Vec(Vec3(u(rng), u(rng), u(rng))) + ", mass: 0.0002 }\n";
  }
  Scene s = test::load_text("simulation: { dt: 0.01, steps: 1 }\nparticles:\n" + particles +
                            "forces:\n  - { type: nbody, G: 1, softening: 0.05 }\n");
  Matrix3X reference;
  for (const int threads : {1, 2, 3, 4}) {
    set_threads(threads);
    Matrix3X f = Matrix3X::Constant(3, s.system->size(), 0.5);
    s.system->force_objects()[0].force->add_forces(s.system->view(), f);
    if (threads == 1) {
      reference = f;
    } else {
      EXPECT_TRUE(f.cwiseEqual(reference).all()) << threads << " threads";
    }
  }
  set_threads(available_threads());
}

}  // namespace
}  // namespace pdyn
