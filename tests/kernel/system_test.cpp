// The particle system's solver interface: state layout, gather, fixed particles.
#include "pdyn/system.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <pdyn/parallel.hpp>
#include <utility>
#include <vector>

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

// derivative_then hands each chunk of particles to the solver right after
// writing its slope: every particle in exactly one chunk, the slope it sees
// derivative()'s bits (fixed particles' zero included), for 1 and 2 threads,
// and what the callback writes into the state is what a separate pass would
// write. An 80 x 80 cloth is many chunks, split over 2 threads.
TEST(System, DerivativeThenGivesEachChunkTheSlopeOfDerivative) {
  Scene s = test::load_text(R"(
simulation: { dt: 0.001, steps: 1 }
particles:
  - grid:
      origin: [0, 0, 1]
      u: [0.01, 0, 0]
      v: [0, 0, 0.01]
      nx: 80
      ny: 80
      mass: 0.001
      velocity: [0, 1, 0]
      pin: [[0, -1], [-1, -1]]
      springs:
        structural: { ks: 1000, kd: 0.02 }
        shear: { ks: 500, kd: 0.01 }
forces:
  - { type: gravity, g: [0, 0, -9.81] }
  - { type: drag, k: 0.0001 }
)");
  System& sys = *s.system;
  const Index n = sys.size();
  const Index dim = sys.dimension();
  ASSERT_GT(n, kParallelMinElements);
  // Move the cloth off its rest state so that the springs pull.
  Eigen::VectorXd y0 = std::as_const(sys).state();
  for (Index i = 0; i < n; ++i) y0(3 * i + 1) += 0.001 * std::sin(0.37 * static_cast<double>(i));
  sys.set_state(y0);
  Eigen::VectorXd expected(dim);
  sys.derivative(expected);
  const Eigen::VectorXd stepped = y0 + 0.001 * expected;
  EXPECT_EQ(expected.segment(3 * n + 3 * (n - 1), 3), Eigen::Vector3d::Zero());  // pinned
  const int saved = max_threads();
  for (const int threads : {1, 2}) {
    set_threads(threads);
    sys.set_state(y0);
    Eigen::VectorXd k = Eigen::VectorXd::Constant(dim, -1.0);
    std::vector<int> seen(static_cast<std::size_t>(n), 0);
    std::vector<unsigned char> same(static_cast<std::size_t>(n), 0);
    double* y = sys.state().data();
    // A const callable, as a solver may hold one.
    const auto check = [&](Index b, Index e) {
      for (Index i = b; i < e; ++i) {
        ++seen[static_cast<std::size_t>(i)];
        bool equal = true;
        for (const Index at : {3 * i, 3 * n + 3 * i}) {
          for (Index d = 0; d < 3; ++d) {
            equal = equal && k(at + d) == expected(at + d);
            y[at + d] += 0.001 * k(at + d);
          }
        }
        same[static_cast<std::size_t>(i)] = equal ? 1 : 0;
      }
    };
    sys.derivative_then(k, check);
    EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), n) << threads << " threads";
    EXPECT_EQ(std::count(same.begin(), same.end(), 1), n) << threads << " threads";
    EXPECT_EQ(k, expected) << threads << " threads";
    EXPECT_EQ(Eigen::VectorXd(std::as_const(sys).state()), stepped) << threads << " threads";
  }
  set_threads(saved);
}

}  // namespace
}  // namespace pdyn
