// RATTLE in verlet (plugins/solvers/verlet/rattle.hpp; Andersen 1983):
// configs/hanging_chain.yaml's 50 rods keep their lengths to 1e-10 m and
// their rigid motions (Cdot = 0) at every step, with the energy in a band;
// and on configs/double_pendulum.yaml the method converges to the exact
// motion at second order.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <iostream>

#include "gallery/gallery_support.hpp"

namespace pdyn {
namespace hanging_chain_test {

// The largest |(v_i - v_j) . n| over the chain's rods: Cdot of each.
double LargestRodRate(const System& sys) {
  double worst = 0.0;
  for (Index i = 0; i + 1 < sys.size(); ++i) {
    const Vec3 d = sys.positions().col(i + 1) - sys.positions().col(i);
    const Vec3 w = sys.velocities().col(i + 1) - sys.velocities().col(i);
    worst = std::max(worst, std::abs(w.dot(d.normalized())));
  }
  return worst;
}

TEST(GalleryHangingChain, RattleKeepsEveryRodToTenToTheMinusTenMetresAndTheEnergyInABand) {
  Scene scene = test::LoadConfig("hanging_chain.yaml");
  ASSERT_EQ(scene.solver_name, "verlet");
  System& sys = *scene.system;
  ASSERT_EQ(sys.size(), 51);
  ASSERT_EQ(sys.constraint_rows(), 50);
  const double e0 = sys.kinetic_energy() + sys.potential_energy();
  // The energy's scale: the chain's potential energy range, M g L / 2.
  const double scale = sys.masses().sum() * 9.81 * 5.0 / 2;
  double worst_c = 0.0, worst_rate = 0.0, worst_e = 0.0;
  double lowest_tip = 0.0, late_sum = 0.0;
  std::int64_t late = 0;
  test::StepThrough(scene, scene.steps, [&](std::int64_t k) {
    worst_c = std::max(worst_c, sys.constraint_error());
    worst_rate = std::max(worst_rate, LargestRodRate(sys));
    worst_e = std::max(worst_e, std::abs(sys.kinetic_energy() + sys.potential_energy() - e0));
    lowest_tip = std::min(lowest_tip, sys.positions()(2, 50));
    if (k > scene.steps - 4000) {  // the last second
      late_sum += sys.kinetic_energy() + sys.potential_energy() - e0;
      ++late;
    }
  });
  const double drift = late_sum / static_cast<double>(late);
  std::cout << "hanging chain (RATTLE, " << scene.steps << " steps): max |C| = " << worst_c
            << " m, max |Cdot| = " << worst_rate << " m/s, max |E - E0| = " << worst_e
            << " J = " << worst_e / scale
            << " of M g L / 2, mean E - E0 over the last second = " << drift
            << " J, lowest tip z = " << lowest_tip << " m\n";
  EXPECT_LE(worst_c, 1e-10);
  EXPECT_LE(worst_rate, 1e-10);
  // A band (the whip's jumps, O(h^2)) and no drift: symplectic.
  EXPECT_LE(worst_e, 1.5e-3 * scale);
  EXPECT_LE(std::abs(drift), 2e-4 * scale);
  EXPECT_LT(lowest_tip, -4.9);  // it fell: the tip passed within 0.1 m of straight down
  // No Witkin force under RATTLE: the solver enforces the rods itself.
  EXPECT_FALSE(sys.constraint_force_enabled());
}

// The double pendulum of configs/double_pendulum.yaml under verlet (RATTLE)
// at h, h/2 and h/4 against rk4 at a hundredth of the smallest step: the
// position errors after 0.5 s fall as h^2.
TEST(GalleryHangingChain, RattleConvergesAtSecondOrderOnTheDoublePendulum) {
  auto run = [](double h, std::int64_t steps) {
    Scene scene = load_scene(test::source_path("configs/double_pendulum.yaml"),
                             test::shipped_plugins(), {{"simulation.solver.type", "verlet"}});
    scene.dt = h;
    Matrix3X x;
    test::StepThrough(scene, steps, [&](std::int64_t) {});
    x = scene.system->positions();
    return x;
  };
  const Matrix3X ref = [] {
    Scene scene = test::LoadConfig("double_pendulum.yaml");
    scene.dt = 1e-5;
    test::StepThrough(scene, 50000, [&](std::int64_t) {});
    return Matrix3X(scene.system->positions());
  }();
  std::array<double, 3> err{};
  for (int k = 0; k < 3; ++k) {
    const double h = 2e-3 / (1 << k);
    err[k] = (run(h, 250 << k) - ref).cwiseAbs().maxCoeff();
  }
  const double p1 = std::log2(err[0] / err[1]), p2 = std::log2(err[1] / err[2]);
  std::cout << "double pendulum, RATTLE: errors " << err[0] << ", " << err[1] << ", " << err[2]
            << " m at h = 2, 1, 0.5 ms: orders " << p1 << ", " << p2 << "\n";
  EXPECT_NEAR(p1, 2.0, 0.2);
  EXPECT_NEAR(p2, 2.0, 0.2);
}

}  // namespace hanging_chain_test
}  // namespace pdyn
