// configs/rope_over_sphere.yaml: a rope with bending stiffness draped over a
// ball. The sphere collider must keep every particle outside the ball at
// the end of every step, and the rope must actually drape: its middle
// resting on the top of the ball, its ends hanging below.
#include <gtest/gtest.h>

#include <iostream>

#include "support/physics_support.hpp"
#include "support/test_support.hpp"

namespace pdyn {
namespace {

TEST(RopeOverSphere, NeverEntersTheSphereAndDrapesOverIt) {
  Scene scene =
      load_scene(test::source_path("configs/rope_over_sphere.yaml"), test::shipped_plugins());
  System& sys = *scene.system;
  constexpr double kR = 0.5;  // the scene's sphere, centred at the origin
  ASSERT_EQ(sys.size(), 30);
  double worst = -1.0;
  for (std::int64_t k = 1; k <= scene.steps; ++k) {
    test::TakeStep(scene, k, scene.dt);
    worst = std::max(worst, kR - sys.positions().colwise().norm().minCoeff());
  }
  const double middle_z = 0.5 * (sys.positions()(2, 14) + sys.positions()(2, 15));
  const double end_z = std::max(sys.positions()(2, 0), sys.positions()(2, 29));
  std::cout << "rope over sphere: worst penetration " << worst << " m; after " << scene.end_time
            << " s the middle is at z = " << middle_z << " m, the ends at z <= " << end_z << " m\n";
  EXPECT_LE(worst, 1e-12);
  EXPECT_NEAR(middle_z, kR, 0.01);  // resting on top of the ball
  EXPECT_LT(end_z, 0.3);            // hanging down its sides (0.17 m when written)
}

}  // namespace
}  // namespace pdyn
