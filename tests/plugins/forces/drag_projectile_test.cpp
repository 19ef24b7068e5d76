// A projectile under gravity and linear drag, m dv/dt = m g - k v, against
// its closed-form solution (a linear ODE with constant coefficients):
//   v(t) = v_inf + (v0 - v_inf) e^{-k t / m},            v_inf = m g / k,
//   x(t) = x0 + v_inf t + (v0 - v_inf) (m / k) (1 - e^{-k t / m}).
// Two particles of different mass share one drag object, so each must relax
// with its own time constant m / k towards its own terminal velocity.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <iostream>

#include "support/physics_support.hpp"
#include "support/test_support.hpp"

namespace pdyn {
namespace {

struct Launch {
  Vec3 x0, v0;  // m, m/s
  double mass;  // kg
};

TEST(DragProjectile, Rk4MatchesTheClosedFormWithinOneNanometre) {
  const Vec3 g(0.0, 0.0, -9.81);  // m/s^2
  constexpr double kDrag = 0.5;   // kg/s
  constexpr double kDt = 1e-3;    // s
  constexpr int kSteps = 2000;    // 2 s: several time constants for the light particle
  const std::array<Launch, 2> launches = {{
      {Vec3(0.0, 0.0, 1.0), Vec3(3.0, 1.0, 10.0), 1.0},
      {Vec3(-1.0, 2.0, 0.0), Vec3(-2.0, 0.0, 5.0), 3.0},
  }};
  std::string yaml = "simulation: { dt: " + test::Num(kDt) + ", steps: " + std::to_string(kSteps) +
                     ", solver: { type: rk4 } }\nparticles:\n";
  for (const Launch& l : launches) {
    yaml += "  - { position: " + test::Vec(l.x0) + ", velocity: " + test::Vec(l.v0) +
            ", mass: " + test::Num(l.mass) + " }\n";
  }
  yaml += "forces:\n  - { type: gravity, g: " + test::Vec(g) + " }\n" +
          "  - { type: drag, k: " + test::Num(kDrag) + " }\n";
  Scene scene = test::load_text(yaml);
  System& sys = *scene.system;

  double max_dx = 0.0, max_dv = 0.0;
  for (int k = 1; k <= kSteps; ++k) {
    test::TakeStep(scene, k, kDt);
    const double t = k * kDt;
    for (Index i = 0; i < 2; ++i) {
      const Launch& l = launches[static_cast<std::size_t>(i)];
      const Vec3 v_inf = l.mass * g / kDrag;
      const double decay = std::exp(-kDrag * t / l.mass);
      const Vec3 v = v_inf + (l.v0 - v_inf) * decay;
      const Vec3 x = l.x0 + v_inf * t + (l.v0 - v_inf) * (l.mass / kDrag) * (1.0 - decay);
      max_dx = std::max(max_dx, (sys.positions().col(i) - x).lpNorm<Eigen::Infinity>());
      max_dv = std::max(max_dv, (sys.velocities().col(i) - v).lpNorm<Eigen::Infinity>());
    }
  }
  std::cout << "rk4 drag projectile, dt = " << kDt << ": max |x - exact| = " << max_dx
            << " m, max |v - exact| = " << max_dv << " m/s\n";
  EXPECT_LT(max_dx, 1e-9);
  EXPECT_LT(max_dv, 1e-9);
}

}  // namespace
}  // namespace pdyn
