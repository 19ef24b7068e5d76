// configs/xpbd_cloth.yaml: an inextensible cloth under XPBD (plugins/
// solvers/xpbd) at 10 ms steps. No structural edge stretches or shrinks by
// more than 1 % at any step, the pinned corners stay put, and the run is the
// same bits twice.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

#include "gallery/gallery_support.hpp"

namespace pdyn {
namespace xpbd_cloth_test {

constexpr Index kN = 30;           // particles per side
constexpr double kSpacing = 0.02;  // m

// The largest | |x_a - x_b| / spacing - 1 | over the grid's structural edges.
double LargestEdgeStrain(const System& sys) {
  double worst = 0.0;
  auto strain = [&](Index a, Index b) {
    return std::abs((sys.positions().col(a) - sys.positions().col(b)).norm() / kSpacing - 1.0);
  };
  for (Index j = 0; j < kN; ++j) {
    for (Index i = 0; i < kN; ++i) {
      if (i + 1 < kN) worst = std::max(worst, strain(j * kN + i, j * kN + i + 1));
      if (j + 1 < kN) worst = std::max(worst, strain(j * kN + i, (j + 1) * kN + i));
    }
  }
  return worst;
}

TEST(GalleryXpbdCloth, NoEdgeStretchesByMoreThanOnePercentAtTenMillisecondSteps) {
  Scene scene = test::LoadConfig("xpbd_cloth.yaml");
  ASSERT_EQ(scene.solver_name, "xpbd");
  ASSERT_EQ(scene.dt, 0.01);
  System& sys = *scene.system;
  ASSERT_EQ(sys.size(), kN * kN);
  ASSERT_EQ(sys.constraint_rows(), 5102);
  const Vec3 corner = sys.positions().col(kN * kN - 1);
  double worst = 0.0, swing = 0.0;
  test::StepThrough(scene, scene.steps, [&](std::int64_t) {
    worst = std::max(worst, LargestEdgeStrain(sys));
    swing = std::max(swing, sys.positions().row(1).maxCoeff());
  });
  std::cout << "xpbd cloth: " << scene.steps << " steps of " << scene.dt
            << " s, largest edge strain " << worst << ", largest swing " << swing << " m\n";
  EXPECT_LE(worst, 0.01);
  EXPECT_GT(swing, 0.05);  // the gust moved it
  EXPECT_EQ(sys.positions().col(kN * kN - 1), corner);
  EXPECT_FALSE(sys.constraint_force_enabled());
}

TEST(GalleryXpbdCloth, TwoRunsGiveTheSameBits) {
  auto run = [] {
    Scene scene = test::LoadConfig("xpbd_cloth.yaml");
    test::StepThrough(scene, 20, [](std::int64_t) {});
    return Eigen::VectorXd(scene.system->state());
  };
  const Eigen::VectorXd a = run(), b = run();
  EXPECT_EQ(a, b);
}

}  // namespace xpbd_cloth_test
}  // namespace pdyn
