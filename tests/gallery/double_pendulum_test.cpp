// configs/double_pendulum.yaml: two rigid rods (distance constraints under
// Witkin's constraint force, rk4 at 1 ms) against the double pendulum's
// equations of motion in its two angles, integrated here by rk4 at 10 us.
// With the angles theta1, theta2 from the downward vertical (Lagrange's
// equations; e.g. Goldstein, Classical Mechanics, ch. 1-2):
//   D = 2 m1 + m2 - m2 cos(2 theta1 - 2 theta2)
//   theta1'' = (-g (2 m1 + m2) sin theta1 - m2 g sin(theta1 - 2 theta2)
//               - 2 sin(theta1 - theta2) m2 (w2^2 L2 + w1^2 L1 cos(theta1 - theta2))) / (L1 D)
//   theta2'' = 2 sin(theta1 - theta2) (w1^2 L1 (m1 + m2) + g (m1 + m2) cos theta1
//               + w2^2 L2 m2 cos(theta1 - theta2)) / (L2 D)
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <iostream>

#include "gallery/gallery_support.hpp"

namespace pdyn {
namespace double_pendulum_test {

using State = std::array<double, 4>;  // theta1, theta2, w1, w2

struct Pendulum {
  double m1, m2, l1, l2, g;
  State rate(const State& s) const {
    const double d = s[0] - s[1];
    const double den = 2 * m1 + m2 - m2 * std::cos(2 * d);
    const double a1 = (-g * (2 * m1 + m2) * std::sin(s[0]) - m2 * g * std::sin(s[0] - 2 * s[1]) -
                       2 * std::sin(d) * m2 * (s[3] * s[3] * l2 + s[2] * s[2] * l1 * std::cos(d))) /
                      (l1 * den);
    const double a2 = 2 * std::sin(d) *
                      (s[2] * s[2] * l1 * (m1 + m2) + g * (m1 + m2) * std::cos(s[0]) +
                       s[3] * s[3] * l2 * m2 * std::cos(d)) /
                      (l2 * den);
    return {s[2], s[3], a1, a2};
  }
  State step(const State& s, double h) const {
    auto add = [](const State& a, const State& b, double c) {
      return State{a[0] + c * b[0], a[1] + c * b[1], a[2] + c * b[2], a[3] + c * b[3]};
    };
    const State k1 = rate(s), k2 = rate(add(s, k1, h / 2)), k3 = rate(add(s, k2, h / 2)),
                k4 = rate(add(s, k3, h));
    State out;
    for (int i = 0; i < 4; ++i) out[i] = s[i] + h / 6 * (k1[i] + 2 * k2[i] + 2 * k3[i] + k4[i]);
    return out;
  }
};

TEST(GalleryDoublePendulum, RodsFollowTheEquationsInTheAnglesForOneSecond) {
  Scene scene = test::LoadConfig("double_pendulum.yaml");
  ASSERT_EQ(scene.solver_name, "rk4");
  System& sys = *scene.system;
  ASSERT_EQ(sys.constraint_rows(), 2);
  const Pendulum ref{sys.masses()(1), sys.masses()(2), 1.0, 0.7, 9.81};
  State s{M_PI / 2, M_PI / 2, 0.0, 0.0};  // both rods horizontal, at rest
  const std::int64_t steps = 1000;        // 1 s at 1 ms
  const int sub = 100;                    // the reference at 10 us
  double worst = 0.0, worst_rod = 0.0;
  for (std::int64_t k = 1; k <= steps; ++k) {
    test::TakeStep(scene, k, scene.dt);
    for (int i = 0; i < sub; ++i) s = ref.step(s, scene.dt / sub);
    const Vec3 x1(ref.l1 * std::sin(s[0]), 0.0, -ref.l1 * std::cos(s[0]));
    const Vec3 x2 = x1 + Vec3(ref.l2 * std::sin(s[1]), 0.0, -ref.l2 * std::cos(s[1]));
    worst = std::max(
        {worst, (sys.positions().col(1) - x1).norm(), (sys.positions().col(2) - x2).norm()});
    worst_rod =
        std::max({worst_rod, std::abs(sys.positions().col(1).norm() - ref.l1),
                  std::abs((sys.positions().col(2) - sys.positions().col(1)).norm() - ref.l2)});
  }
  std::cout << "double pendulum: over 1 s, max |x - x_ref| = " << worst
            << " m, max rod length error = " << worst_rod << " m\n";
  EXPECT_LE(worst, 1e-6);
  EXPECT_LE(worst_rod, 1e-8);
}

}  // namespace double_pendulum_test
}  // namespace pdyn
