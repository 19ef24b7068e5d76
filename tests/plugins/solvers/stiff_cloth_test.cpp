// The stiff cloth of tests/scenes/shared/stiff_cloth.yaml (30 x 30 particles, structural
// and shear springs of ks = 1e5 N/m, gravity, pinned at two opposite
// corners, released flat): explicit solvers need dt ~ 1e-4 s here, while
// implicit_euler takes dt = 0.01 s.
//
// Bound: every particle of the sheet stays within its rest distance of
// both pins (springs barely stretch at ks = 1e5), so it moves inside the
// lens between two spheres around the pins; the widest such lens, that of
// the free corners, is sqrt(2) m across -- the cloth's diagonal. A stable
// run keeps every particle within that distance of its start.
#include <gtest/gtest.h>

#include <chrono>
#include <iostream>

#include "pdyn/error.hpp"
#include "pdyn/host/assembly.hpp"
#include "pdyn/host/runner.hpp"
#include "plugins/solvers/solver_support.hpp"

namespace pdyn {
namespace {

const double kDiagonal = std::sqrt(2.0);  // m, the 1 m x 1 m cloth's diagonal

Scene StiffCloth(const std::string& solver, double dt, double duration) {
  return load_scene(
      test::shared_scene("stiff_cloth.yaml"), test::shipped_plugins(),
      {Override{"simulation.solver", solver}, Override{"simulation.dt", test::Num(dt)},
       Override{"simulation.duration", test::Num(duration)}});
}

TEST(StiffCloth, ImplicitEulerAtLargeStepsStaysFiniteAndBounded) {
  Scene scene = StiffCloth("{ type: implicit_euler }", 0.01, 2.0);
  const Matrix3X x0 = scene.system->positions();
  const auto start = std::chrono::steady_clock::now();
  const RunResult r = run_scene(scene);
  const double wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ASSERT_EQ(r.exit_code, 0) << r.message;
  EXPECT_EQ(r.steps_done, 200);
  EXPECT_TRUE(scene.system->state().allFinite());
  const double travel = (scene.system->positions() - x0).colwise().norm().maxCoeff();
  const double lowest = scene.system->positions().row(2).minCoeff();
  std::cout << "stiff cloth, implicit_euler, dt = 0.01 s, 2 s: largest distance from start "
            << travel << " m (bound " << kDiagonal << " m), lowest point z = " << lowest
            << " m, wall time " << wall << " s\n";
  EXPECT_LE(travel, kDiagonal);
  // It did fall: the free corners hang below the pinned diagonal.
  EXPECT_LT(lowest, -0.3);
}

TEST(StiffCloth, Rk4AtTheSameStepBlowsUp) {
  Scene scene = StiffCloth("{ type: rk4 }", 0.01, 2.0);
  const RunResult r = run_scene(scene);
  std::cout << "stiff cloth, rk4, dt = 0.01 s: exit " << r.exit_code << " after " << r.steps_done
            << " steps: " << r.message << "\n";
  EXPECT_EQ(r.exit_code, 4);
  EXPECT_LT(r.steps_done, 200);
}

TEST(StiffCloth, ConjugateGradientsThatDoNotConvergeAreAClearError) {
  Scene scene =
      StiffCloth("{ type: implicit_euler, linear_solver: cg, cg_max_iterations: 3 }", 0.01, 0.1);
  // The solver throws pdyn::Error; the runner stops with exit code 3 and
  // restores the last good state.
  const RunResult r = run_scene(scene);
  std::cout << "implicit_euler, cg_max_iterations 3: exit " << r.exit_code << ": " << r.message
            << "\n";
  EXPECT_EQ(r.exit_code, 3);
  EXPECT_NE(r.message.find("implicit_euler: conjugate gradients did not converge in 3 "
                           "iterations at t = "),
            std::string::npos)
      << r.message;
  EXPECT_NE(r.message.find("cg_tolerance"), std::string::npos) << r.message;
  EXPECT_GT(r.steps_done, 0);  // the first step, from rest, is easy
  EXPECT_EQ(scene.system->time(), static_cast<double>(r.steps_done) * 0.01);
}

// A force without analytic Jacobians: the same linear spring-and-drag law as
// spring (rest 0) + drag, but through add_forces() only, so implicit_euler
// must differentiate it numerically (matrix-free).
class OpaqueSpringAndDrag final : public Force {
 public:
  OpaqueSpringAndDrag(Index i, double ks, double k) : i_(i), ks_(ks), k_(k) {}
  void add_forces(const ParticleView& p, Eigen::Ref<Matrix3X> f) override {
    f.col(i_) += -ks_ * (p.x.col(i_) - p.x.col(0)) - k_ * p.v.col(i_);
  }

 private:
  Index i_;
  double ks_, k_;
};

TEST(ImplicitEuler, ForcesWithoutJacobiansAgreeWithAnalyticOnes) {
  test::Oscillator osc;
  osc.k = 0.3;
  const std::string solver = "{ type: implicit_euler, cg_tolerance: 1.0e-12 }";
  const std::string timing = "dt: 0.01, steps: 300";
  Scene analytic = test::load_text(osc.scene(solver, timing));
  ASSERT_EQ(run_scene(analytic).exit_code, 0);

  // The same particles with no force objects, then the opaque force.
  test::Oscillator bare = osc;
  bare.ks = 0.0;
  bare.k = 0.0;
  Scene opaque = test::load_text(bare.scene(solver, timing));
  SystemAssembly(*opaque.system)
      .add_force(std::make_shared<OpaqueSpringAndDrag>(1, osc.ks, osc.k), "opaque");
  ASSERT_EQ(run_scene(opaque).exit_code, 0);

  const double diff = (analytic.system->state() - opaque.system->state()).lpNorm<Eigen::Infinity>();
  std::cout << "implicit_euler, analytic vs finite-difference Jacobians after 300 steps: " << diff
            << " m or m/s apart; error against the closed form " << osc.error(*analytic.system)
            << "\n";
  EXPECT_LT(diff, 1e-8);
}

// Mixed: a small cloth whose springs have Jacobians and whose drag does not.
TEST(ImplicitEuler, MixesAnalyticAndMatrixFreeForces) {
  const std::string cloth =
      "simulation: { dt: 0.01, steps: 50, solver: { type: implicit_euler, cg_tolerance: "
      "1.0e-12 } }\n"
      "particles:\n"
      "  - grid: { origin: [0, 0, 0], u: [0.1, 0, 0], v: [0, 0.1, 0], nx: 5, ny: 5, mass: 0.01,\n"
      "            pin: [[0, 0], [-1, 0]], springs: { structural: { ks: 100, kd: 0.1 } } }\n"
      "forces:\n"
      "  - { type: gravity }\n";
  Scene analytic = test::load_text(cloth + "  - { type: drag, k: 0.02 }\n");
  ASSERT_EQ(run_scene(analytic).exit_code, 0);

  Scene mixed = test::load_text(cloth);
  SystemAssembly(*mixed.system).add_force(std::make_shared<test::OpaqueDrag>(), "opaque drag");
  ASSERT_EQ(run_scene(mixed).exit_code, 0);
  const double diff = (analytic.system->state() - mixed.system->state()).lpNorm<Eigen::Infinity>();
  std::cout << "implicit_euler on a 5 x 5 cloth, drag analytic vs matrix-free: " << diff
            << " apart after 50 steps\n";
  EXPECT_LT(diff, 1e-8);
}

}  // namespace
}  // namespace pdyn
