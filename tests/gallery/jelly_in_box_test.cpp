// configs/jelly_in_box.yaml: a soft lattice cube bouncing inside a box. The
// box collider (inside: true) must keep every particle inside at the end of
// every step, and the shear and body springs must keep the cube's shape:
// the 28 distances between its 8 corners stay within 15% of their rest
// values throughout.
#include <gtest/gtest.h>

#include <iostream>

#include "support/physics_support.hpp"
#include "support/test_support.hpp"

namespace pdyn {
namespace {

TEST(JellyInBox, StaysInsideTheBoxAndKeepsItsShape) {
  Scene scene = load_scene(test::source_path("configs/jelly_in_box.yaml"), test::shipped_plugins());
  System& sys = *scene.system;
  ASSERT_EQ(sys.size(), 64);
  const Vec3 lo(-0.5, -0.5, 0.0), hi(0.5, 0.5, 1.0);  // the scene's box
  std::vector<Index> corners;
  for (int k : {0, 3})
    for (int j : {0, 3})
      for (int i : {0, 3}) corners.push_back((k * 4 + j) * 4 + i);
  auto corner_distances = [&] {
    std::vector<double> d;
    for (std::size_t a = 0; a < corners.size(); ++a)
      for (std::size_t b = a + 1; b < corners.size(); ++b)
        d.push_back((sys.positions().col(corners[a]) - sys.positions().col(corners[b])).norm());
    return d;
  };
  const std::vector<double> rest = corner_distances();
  double outside = -1.0, distortion = 0.0, travelled = 0.0;
  const Vec3 start = sys.positions().rowwise().mean();
  int wall_hits = 0;
  for (std::int64_t k = 1; k <= scene.steps; ++k) {
    test::TakeStep(scene, k, scene.dt);
    const Matrix3X& x = sys.positions();
    for (Index i = 0; i < sys.size(); ++i) {
      const double d = std::min((x.col(i) - lo).minCoeff(), (hi - x.col(i)).minCoeff());
      outside = std::max(outside, -d);
      wall_hits += d < 1e-3;
    }
    const std::vector<double> now = corner_distances();
    for (std::size_t p = 0; p < now.size(); ++p) {
      distortion = std::max(distortion, std::abs(now[p] / rest[p] - 1.0));
    }
    travelled = std::max(travelled, (Vec3(x.rowwise().mean()) - start).norm());
  }
  std::cout << "jelly in box: worst penetration " << outside << " m, " << wall_hits
            << " particle-steps at a wall, worst corner-distance change " << 100 * distortion
            << "%, centre moved up to " << travelled << " m\n";
  EXPECT_LE(outside, 1e-12);
  EXPECT_GT(wall_hits, 100);  // it did hit the walls
  EXPECT_LT(distortion, 0.15);
  EXPECT_GT(travelled, 0.2);
}

}  // namespace
}  // namespace pdyn
