// configs/lj_liquid.yaml: 256 Lennard-Jones atoms in a periodic box, fcc at
// density 0.8442 and T = 1.44, velocity Verlet (one force evaluation per
// step) for 2000 steps of 0.005. The crystal melts (half the kinetic energy
// goes into the potential), the total energy stays within a bound, the
// momentum stays zero and every atom stays in the box.
#include <gtest/gtest.h>

#include <iostream>

#include "gallery/gallery_support.hpp"

namespace pdyn {
namespace {

TEST(GalleryLjLiquid, MeltsConservingEnergyAndMomentum) {
  Scene scene = test::LoadConfig("lj_liquid.yaml");
  ASSERT_EQ(scene.steps, 2000);
  System& sys = *scene.system;
  ASSERT_EQ(sys.size(), 256);
  ASSERT_TRUE(sys.domain().any_periodic());
  const double n = static_cast<double>(sys.size());
  const double e0 = sys.kinetic_energy() + sys.potential_energy();
  const double t0 = 2 * sys.kinetic_energy() / (3 * n - 3);
  double worst = 0.0, momentum = 0.0;
  test::RunAll(scene, [&](std::int64_t) {
    worst = std::max(worst, std::abs(sys.kinetic_energy() + sys.potential_energy() - e0) / n);
    momentum = std::max(momentum, (sys.velocities() * sys.masses()).norm());
  });
  const double t1 = 2 * sys.kinetic_energy() / (3 * n - 3);
  std::cout << "lj_liquid: T " << t0 << " -> " << t1 << ", max |E - E0| per atom " << worst
            << " J, max |P| " << momentum << " kg m/s\n";
  EXPECT_NEAR(t0, 1.44, 1e-12);
  EXPECT_GT(t1, 0.5);  // melted: about half the kinetic energy went into the potential
  EXPECT_LT(t1, 0.9);
  EXPECT_LT(worst, 2e-3);  // measured 1.2e-3 in the 256-atom test at this dt (lennard_jones_test)
  EXPECT_LT(momentum, 1e-11);
  const Vec3 length = sys.domain().length();
  for (Index i = 0; i < sys.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      ASSERT_GE(sys.positions()(k, i), 0.0);
      ASSERT_LT(sys.positions()(k, i), length[k]);
    }
  }
}

}  // namespace
}  // namespace pdyn
