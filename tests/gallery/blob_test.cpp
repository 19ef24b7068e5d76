// configs/blob.yaml: a 2-D soft blob (a ring with area springs) dropped on a
// floor with friction. Its enclosed area, by the shoelace formula in its
// x-z plane, must stay within 10% of the rest area at every step, while it
// lands, squashes and comes to rest; and it must stay on the floor.
#include <gtest/gtest.h>

#include <iostream>

#include "support/physics_support.hpp"
#include "support/test_support.hpp"

namespace pdyn {
namespace {

double LoopArea(const Matrix3X& x) {
  double twice = 0.0;
  for (Index i = 0; i < x.cols(); ++i) {
    const Index j = (i + 1) % x.cols();
    twice += x(0, i) * x(2, j) - x(0, j) * x(2, i);
  }
  return 0.5 * std::abs(twice);
}

TEST(Blob, KeepsItsAreaWithinTenPercentOnTheFloor) {
  Scene scene = load_scene(test::source_path("configs/blob.yaml"), test::shipped_plugins());
  System& sys = *scene.system;
  ASSERT_EQ(sys.size(), 24);
  const double rest = LoopArea(sys.positions());
  double worst = 0.0, lowest = 1.0;
  for (std::int64_t k = 1; k <= scene.steps; ++k) {
    test::TakeStep(scene, k, scene.dt);
    worst = std::max(worst, std::abs(LoopArea(sys.positions()) / rest - 1.0));
    lowest = std::min(lowest, sys.positions().row(2).minCoeff());
  }
  const double speed = sys.velocities().colwise().norm().maxCoeff();
  std::cout << "blob: rest area " << rest << " m^2, worst area change " << 100 * worst
            << "%, lowest z " << lowest << " m, fastest particle at the end " << speed << " m/s\n";
  EXPECT_LT(worst, 0.10);
  EXPECT_GE(lowest, -1e-12);
  EXPECT_NEAR(sys.positions().row(2).minCoeff(), 0.0, 1e-3);  // on the floor
}

}  // namespace
}  // namespace pdyn
