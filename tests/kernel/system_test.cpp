// The particle system's solver interface: state layout, gather, fixed particles.
#include "pdyn/system.hpp"

#include <gtest/gtest.h>

#include "support/test_support.hpp"

namespace pdyn {
namespace {

TEST(System, StateIsPositionsThenVelocitiesAndDerivativeIsVelocityThenAcceleration) {
  Scene s = test::load_text(R"(
simulation: { dt: 0.01, steps: 1 }
particles:
  - { position: [1, 2, 3], velocity: [4, 5, 6], mass: 2 }
  - { position: [7, 8, 9], velocity: [1, 1, 1], mass: 1, fixed: true }
forces:
  - { type: gravity, g: [0, 0, -10] }
)");
  System& sys = *s.system;
  ASSERT_EQ(sys.dimension(), 12);
  Eigen::VectorXd y(12);
  sys.get_state(y);
  Eigen::VectorXd expected(12);
  // Nailing zeroes the velocity of particle 1.
  expected << 1, 2, 3, 7, 8, 9, 4, 5, 6, 0, 0, 0;
  EXPECT_EQ(y, expected);
  Eigen::VectorXd dydt(12);
  sys.derivative(dydt);
  Eigen::VectorXd d_expected(12);
  d_expected << 4, 5, 6, 0, 0, 0, 0, 0, -10, 0, 0, 0;
  EXPECT_EQ(dydt, d_expected);
}

}  // namespace
}  // namespace pdyn
