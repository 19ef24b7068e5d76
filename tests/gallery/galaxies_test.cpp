// configs/galaxies.yaml: two clusters of 300 bodies (G = 1 units) collide
// and merge under direct-summation gravity with 10 cm softening, velocity
// Verlet at dt = 0.0025 for 6 s. The total momentum stays zero (pairwise
// forces are exact negatives), the centre of mass stays put, and the total
// energy stays within a stated bound through the close encounters.
#include <gtest/gtest.h>

#include <iostream>

#include "gallery/gallery_support.hpp"

namespace pdyn {
namespace {

TEST(GalleryGalaxies, MergeConservingMomentumAndEnergy) {
  Scene scene = test::LoadConfig("galaxies.yaml");
  ASSERT_EQ(scene.steps, 2400);
  System& sys = *scene.system;
  ASSERT_EQ(sys.size(), 600);
  const double m = sys.masses().sum();
  const Vec3 c0 = sys.positions() * sys.masses() / m;
  const double e0 = sys.kinetic_energy() + sys.potential_energy();
  ASSERT_LT(e0, 0.0) << "bound";
  double worst = 0.0, momentum = 0.0, closest = 1e300;
  test::RunAll(scene, [&](std::int64_t) {
    closest = std::min(closest, (sys.positions().leftCols(300).rowwise().mean() -
                                 sys.positions().rightCols(300).rowwise().mean())
                                    .norm());
    worst = std::max(worst, std::abs(sys.kinetic_energy() + sys.potential_energy() - e0) / -e0);
    momentum = std::max(momentum, (sys.velocities() * sys.masses()).norm());
  });
  const Vec3 c1 = sys.positions() * sys.masses() / m;
  std::cout << "galaxies: max |E - E0|/|E0| " << worst << ", max |P| " << momentum
            << ", centre moved " << (c1 - c0).norm() << " m, clusters' centres came within "
            << closest << " m\n";
  EXPECT_LT(worst, 1e-3);  // measured 4.7e-4
  EXPECT_LT(momentum, 1e-13);
  EXPECT_LT((c1 - c0).norm(), 1e-12);
  EXPECT_LT(closest, 0.5);  // they met (4.1 m apart at the start)
}

}  // namespace
}  // namespace pdyn
