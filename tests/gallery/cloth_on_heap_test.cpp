// configs/cloth_on_heap.yaml: the demo's cloth dropped onto a pyramid of 30
// balls (base nailed), every particle under one soft_contact (Hertz). The
// cloth must come to rest draped over the heap, the total energy must never
// grow (the scene only dissipates), no contact may overlap deeply, the heap
// must stand and the cloth stay above the floor.
#include <gtest/gtest.h>

#include <iostream>

#include "gallery/gallery_support.hpp"

namespace pdyn {
namespace {

constexpr Index kCloth = 900;      // ids 0..899; the balls are 900..929
constexpr double kRc = 0.012;      // a cloth particle's radius, m
constexpr double kRb = 0.075;      // a ball's radius, m
constexpr double kTop = 0.393198;  // the top ball's centre, m

struct Overlaps {
  double cloth_ball = 0.0, ball_ball = 0.0;  // deepest, m
};

Overlaps deepest_overlaps(const System& sys) {
  Overlaps o;
  const auto& x = sys.positions();
  for (Index b = kCloth; b < sys.size(); ++b) {
    for (Index i = 0; i < b; ++i) {
      const double d = (x.col(i) - x.col(b)).norm();
      if (i < kCloth) {
        o.cloth_ball = std::max(o.cloth_ball, kRc + kRb - d);
      } else {
        o.ball_ball = std::max(o.ball_ball, 2 * kRb - d);
      }
    }
  }
  return o;
}

TEST(GalleryClothOnHeap, TheClothDrapesOverTheHeapAndComesToRest) {
  Scene scene = test::LoadConfig("cloth_on_heap.yaml");
  ASSERT_EQ(scene.steps, 12500);
  System& sys = *scene.system;
  ASSERT_EQ(sys.size(), 930);
  const Matrix3X heap0 = sys.positions().rightCols(30);
  const double e0 = sys.kinetic_energy() + sys.potential_energy();
  double lowest = e0, growth = 0.0;  // the largest rise of E above its lowest value so far
  Overlaps worst;
  double floor = 1.0;  // the lowest cloth particle, m
  test::RunAll(scene, [&](std::int64_t k) {
    const double e = sys.kinetic_energy() + sys.potential_energy();
    lowest = std::min(lowest, e);
    growth = std::max(growth, e - lowest);
    if (k % 10 != 0) return;
    const Overlaps o = deepest_overlaps(sys);
    worst.cloth_ball = std::max(worst.cloth_ball, o.cloth_ball);
    worst.ball_ball = std::max(worst.ball_ball, o.ball_ball);
    floor = std::min(floor, sys.positions().row(2).head(kCloth).minCoeff());
  });
  const double e1 = sys.kinetic_energy() + sys.potential_energy();
  double cloth_kinetic = 0.0;
  for (Index i = 0; i < kCloth; ++i) {
    cloth_kinetic += 0.5 * sys.masses()[i] * sys.velocities().col(i).squaredNorm();
  }
  const double heap_moved = (sys.positions().rightCols(30) - heap0).colwise().norm().maxCoeff();
  // The middle of the cloth (particles (14..15, 14..15)) on the top ball:
  // 2.47 cm off its axis, at sqrt((R_b + R_c)^2 - 0.0247^2) = 0.0834 m above
  // its centre less the overlap and the stretch; the corners on the floor.
  const auto& x = sys.positions();
  const double middle =
      0.25 * (x(2, 14 * 30 + 14) + x(2, 14 * 30 + 15) + x(2, 15 * 30 + 14) + x(2, 15 * 30 + 15));
  const double above_top = middle - x(2, 929);  // over the top ball's centre
  const Overlaps resting = deepest_overlaps(sys);
  const double corners = std::max({x(2, 0), x(2, 29), x(2, 870), x(2, 899)});
  std::cout << "cloth_on_heap: energy " << e0 << " -> " << e1 << " J, largest rise " << growth
            << " J; cloth kinetic " << cloth_kinetic << " J, heap kinetic "
            << sys.kinetic_energy() - cloth_kinetic << " J; deepest overlap cloth-ball "
            << worst.cloth_ball / kRc << " cloth radius, ball-ball " << worst.ball_ball / kRb
            << " ball radius; heap moved " << heap_moved << " m; lowest cloth surface "
            << floor - kRc << " m above the floor; middle at " << middle << " m, " << above_top
            << " m above the top ball, corners below " << corners
            << " m; at rest overlaps cloth-ball " << resting.cloth_ball / kRc << ", ball-ball "
            << resting.ball_ball / kRb << "\n";
  const double lost = e0 - e1;  // measured 3.307 J of 13.59 J (halving dt: 0.02% less)
  EXPECT_GT(lost, 3.0);
  EXPECT_LT(growth, 1e-4 * lost);           // measured 7.8e-6 J (2.3e-6), a step's wobble
  EXPECT_LT(cloth_kinetic, 3e-5 * lost);    // measured 1.2e-5 J (3.5e-6): rms 5 mm/s
  EXPECT_LT(worst.cloth_ball, 0.12 * kRc);  // measured 7.5% (the landing at 1.4 m/s)
  EXPECT_LT(worst.ball_ball, 0.04 * kRb);   // measured 2.2% (1.3% at rest)
  EXPECT_LT(heap_moved, 0.01);              // measured 4.0 mm: the heap stands
  EXPECT_GE(floor - kRc, -1e-9);            // no cloth surface below z = 0 (measured 0)
  EXPECT_NEAR(above_top, 0.0834, 0.005);    // on the top ball (measured 0.0813 m)
  EXPECT_LT(corners, kRc + 0.008);          // the corners on the floor (measured 0.0121 m)
}

}  // namespace
}  // namespace pdyn
