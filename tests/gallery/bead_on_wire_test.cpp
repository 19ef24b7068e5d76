// configs/bead_on_wire.yaml: a bead on a vertical circular wire (Witkin's
// constrained-dynamics example), released at rest 120 degrees from the
// bottom, integrated by rk4 with Witkin's constraint force. It is a rigid
// pendulum, whose exact period at amplitude theta0 is
//   T = 4 sqrt(L/g) K(k),  k = sin(theta0 / 2)
// (K the complete elliptic integral of the first kind, std::comp_ellint_1).
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <vector>

#include "gallery/gallery_support.hpp"

namespace pdyn {
namespace bead_on_wire_test {

// The time in [t0, t0 + h] where the cubic Hermite interpolant of x (values
// x0, x1, slopes v0, v1) crosses zero: accurate to O(h^4), below rk4's own
// error at this step.
double Crossing(double t0, double h, double x0, double v0, double x1, double v1) {
  auto x = [&](double s) {
    const double s2 = s * s, s3 = s2 * s;
    return (2 * s3 - 3 * s2 + 1) * x0 + (s3 - 2 * s2 + s) * h * v0 + (-2 * s3 + 3 * s2) * x1 +
           (s3 - s2) * h * v1;
  };
  double lo = 0.0, hi = 1.0;
  for (int i = 0; i < 60; ++i) {
    const double mid = 0.5 * (lo + hi);
    ((x(lo) > 0) == (x(mid) > 0) ? lo : hi) = mid;
  }
  return t0 + 0.5 * (lo + hi) * h;
}

TEST(GalleryBeadOnWire, PeriodIsTheExactLargeAmplitudeOneTo1e6) {
  Scene scene = test::LoadConfig("bead_on_wire.yaml");
  ASSERT_EQ(scene.solver_name, "rk4");
  System& sys = *scene.system;
  ASSERT_EQ(sys.constraint_rows(), 2);  // in the plane, on the circle
  const Vec3 x0 = sys.positions().col(0);
  const double length = x0.norm();
  const double theta0 = std::atan2(x0.x(), -x0.z());
  const double g = 9.81;
  const double exact = 4.0 * std::sqrt(length / g) * std::comp_ellint_1(std::sin(theta0 / 2));
  // Downward crossings of the bottom (x from + to -): successive ones are
  // one period apart.
  std::vector<double> crossings;
  double max_drift = 0.0, max_off_plane = 0.0;
  double t = 0.0, xp = x0.x(), vp = 0.0;
  const double e0 = sys.kinetic_energy() + sys.potential_energy();
  double max_de = 0.0;
  test::RunAll(scene, [&](std::int64_t) {
    const double x = sys.positions()(0, 0), v = sys.velocities()(0, 0);
    if (xp > 0 && x <= 0) crossings.push_back(Crossing(t, scene.dt, xp, vp, x, v));
    t += scene.dt;
    xp = x;
    vp = v;
    max_drift = std::max(max_drift, std::abs(sys.positions().col(0).norm() - length));
    max_off_plane = std::max(max_off_plane, std::abs(sys.positions()(1, 0)));
    max_de = std::max(max_de, std::abs(sys.kinetic_energy() + sys.potential_energy() - e0));
  });
  ASSERT_GE(crossings.size(), 3u);
  const double period =
      (crossings.back() - crossings.front()) / static_cast<double>(crossings.size() - 1);
  std::cout << "bead on wire: theta0 = " << theta0 << " rad, T = " << period << " s, exact "
            << exact << " s, relative error " << std::abs(period - exact) / exact
            << "; max | |x| - L | = " << max_drift << " m, max |y| = " << max_off_plane
            << " m, max |E - E0| = " << max_de << " J\n";
  EXPECT_NEAR(theta0, 2.0 * M_PI / 3.0, 1e-15);
  EXPECT_LE(std::abs(period - exact) / exact, 1e-6);
  // rk4's error at h = 1 ms, with no feedback (ks = kd = 0): the drift off
  // the wire and the energy error stay far below the period's bound.
  EXPECT_LE(max_drift, 2e-8);       // measured 5.0e-9
  EXPECT_LE(max_off_plane, 1e-15);  // nothing pushes it out of the plane
  EXPECT_LE(max_de, 2e-8);          // measured 6.3e-9
}

}  // namespace bead_on_wire_test
}  // namespace pdyn
