// configs/vortex.yaml: particles at rest in a rotating flow u = W (-y, x, 0)
// with drag c towards it. Their angular momentum about z starts at 0, only
// grows, and reaches most of sum m W r^2 (with r the current radii: the
// flow's own angular momentum) within a few time constants m / c = 0.2 s;
// every particle then moves anticlockwise about z.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <iostream>

#include "gallery/gallery_support.hpp"

namespace pdyn {
namespace {

TEST(GalleryVortex, ParticlesAreSpunUpAndCirculate) {
  Scene scene = test::LoadConfig("vortex.yaml");
  ASSERT_EQ(scene.steps, 600);
  System& sys = *scene.system;
  auto lz = [&] {
    double l = 0.0;
    for (Index i = 0; i < sys.size(); ++i) {
      l += sys.masses()(i) *
           Vec3(sys.positions().col(i)).cross(Vec3(sys.velocities().col(i))).z();
    }
    return l;
  };
  EXPECT_EQ(lz(), 0.0);
  double previous = 0.0;
  bool monotonic = true;
  test::RunAll(scene, [&](std::int64_t) {
    const double l = lz();
    monotonic = monotonic && l >= previous;
    previous = l;
  });
  const double W = 2.0;
  double rigid = 0.0;  // sum m W r^2: the flow's own angular momentum
  int anticlockwise = 0, off_centre = 0;
  for (Index i = 0; i < sys.size(); ++i) {
    const Vec3 x = sys.positions().col(i), v = sys.velocities().col(i);
    rigid += sys.masses()(i) * W * (x.x() * x.x() + x.y() * x.y());
    if (x.head<2>().norm() > 1e-9) {
      ++off_centre;
      if (x.cross(v).z() > 0.0) ++anticlockwise;
    }
  }
  std::cout << "vortex: L_z(3 s) = " << lz() << " kg m^2/s, sum m W r^2 = " << rigid
            << ", ratio " << lz() / rigid << "; " << anticlockwise << " of " << off_centre
            << " off-axis particles circulate anticlockwise\n";
  EXPECT_TRUE(monotonic) << "the flow only ever adds angular momentum";
  // The particles lag the flow (drag must also supply the centripetal
  // force, so they drift outwards and slip behind); measured: 0.83 at 3 s.
  EXPECT_GT(lz() / rigid, 0.75);
  EXPECT_LE(lz() / rigid, 1.0);
  EXPECT_EQ(anticlockwise, off_centre);
  EXPECT_TRUE(sys.state().allFinite());
}

}  // namespace
}  // namespace pdyn
