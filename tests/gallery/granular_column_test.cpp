// configs/granular_column.yaml: a 4 x 4 x 12 column of balls (radius 4.5 cm)
// collapses in a box tilted by 1 degree, under soft_contact (DEM). After
// 5 s the heap is at rest up to the creep that history-free friction allows,
// no two balls overlap by more than 10% of a radius while falling or 5% at
// rest, none left the box, and the column spread along the box.
#include <gtest/gtest.h>

#include <iostream>

#include "gallery/gallery_support.hpp"

namespace pdyn {
namespace {

TEST(GalleryGranularColumn, CollapsesAndComesToRest) {
  Scene scene = test::LoadConfig("granular_column.yaml");
  ASSERT_EQ(scene.steps, 25000);
  System& sys = *scene.system;
  ASSERT_EQ(sys.size(), 192);
  const double u0 = sys.potential_energy();
  const double front0 = sys.positions().row(0).maxCoeff();
  double deepest = 0.0;
  test::RunAll(scene, [&](std::int64_t k) {
    if (k % 100 == 0) deepest = std::max(deepest, test::DeepestOverlap(sys, 0.09));
  });
  const double resting = test::DeepestOverlap(sys, 0.09);  // the heap at rest
  const double lost = u0 - sys.potential_energy();
  const double front = sys.positions().row(0).maxCoeff();
  std::cout << "granular_column: kinetic " << sys.kinetic_energy() << " J after losing " << lost
            << " J; deepest overlap " << deepest / 0.045 << " radius while falling, "
            << resting / 0.045 << " at rest; front " << front0 << " -> " << front << " m\n";
  EXPECT_LT(sys.kinetic_energy(), 1e-4 * lost);  // measured 8e-4 J of 88 J
  EXPECT_LT(deepest, 0.1 * 0.045);               // impacts while falling (measured 7.2%)
  EXPECT_LT(resting, 0.05 * 0.045);              // the heap's weight at rest
  EXPECT_GT(front, front0 + 0.3);
  EXPECT_GE(sys.positions().minCoeff(), 0.0);
  EXPECT_LE(sys.positions().row(0).maxCoeff(), 1.2);
  EXPECT_LE(sys.positions().row(1).maxCoeff(), 0.4);
}

}  // namespace
}  // namespace pdyn
