// implicit_euler's direct linear solve (linear_solver: direct, and auto when
// every force has Jacobians): it must give the same steps as conjugate
// gradients driven to a tight tolerance, auto must pick it exactly when it
// can, and what it cannot do must be a clear error.
#include <gtest/gtest.h>

#include <iostream>

#include "implicit_euler_solver.hpp"
#include "pdyn/error.hpp"
#include "pdyn/host/assembly.hpp"
#include "pdyn/host/runner.hpp"
#include "plugins/solvers/solver_support.hpp"

namespace pdyn {
namespace {

Scene StiffCloth(const std::string& solver, int steps) {
  return load_scene(test::shared_scene("stiff_cloth.yaml"), test::shipped_plugins(),
                    {Override{"simulation.solver", solver}, Override{"simulation.dt", "0.01"},
                     Override{"simulation.duration", test::Num(0.01 * steps)}});
}

// Both solve the same linear system each step, so they may differ only by
// CG's residual, and implicit Euler's damping keeps that from growing. At
// cg_tolerance 1e-10 positions agree to 4.7e-9 and velocities to 4.0e-8
// after 30 steps (CG's error in dv is ~sqrt(cond A) times its residual); at
// 1e-12, asserted here, to ~1e-10.
TEST(ImplicitEuler, DirectAndTightConjugateGradientsAgreeOnTheStiffCloth) {
  Scene direct = StiffCloth("{ type: implicit_euler, linear_solver: direct }", 30);
  Scene cg = StiffCloth(
      "{ type: implicit_euler, linear_solver: cg, cg_tolerance: 1.0e-12, cg_max_iterations: "
      "10000 }",
      30);
  const Matrix3X x0 = direct.system->positions();
  const RunResult rd = run_scene(direct);
  const RunResult rc = run_scene(cg);
  ASSERT_EQ(rd.exit_code, 0) << rd.message;
  ASSERT_EQ(rc.exit_code, 0) << rc.message;
  const double moved = (direct.system->positions() - x0).cwiseAbs().maxCoeff();
  const double dx =
      (direct.system->positions() - cg.system->positions()).cwiseAbs().maxCoeff() / moved;
  const double dv = (direct.system->velocities() - cg.system->velocities()).cwiseAbs().maxCoeff() /
                    direct.system->velocities().cwiseAbs().maxCoeff();
  std::cout << "stiff cloth after 30 steps of 0.01 s (largest displacement " << moved
            << " m): direct vs CG at 1e-12, positions " << dx << ", velocities " << dv
            << " apart (relative)\n";
  EXPECT_GT(moved, 0.1);  // the cloth did move
  EXPECT_LT(dx, 1e-8);
  EXPECT_LT(dv, 1e-8);
}

// auto takes the direct path when every force has Jacobians: its steps are
// the direct solve's, bit for bit.
TEST(ImplicitEuler, AutoSolvesDirectlyWhenEveryForceHasJacobians) {
  Scene automatic = StiffCloth("{ type: implicit_euler }", 10);
  Scene direct = StiffCloth("{ type: implicit_euler, linear_solver: direct }", 10);
  ASSERT_EQ(run_scene(automatic).exit_code, 0);
  ASSERT_EQ(run_scene(direct).exit_code, 0);
  EXPECT_EQ(automatic.system->state(), direct.system->state());
}

const char* kSmallCloth =
    "simulation: { dt: 0.01, steps: 20, solver: { type: implicit_euler, linear_solver: %s, "
    "cg_tolerance: 1.0e-12 } }\n"
    "particles:\n"
    "  - grid: { origin: [0, 0, 0], u: [0.1, 0, 0], v: [0, 0.1, 0], nx: 5, ny: 5, mass: 0.01,\n"
    "            pin: [[0, 0], [-1, 0]], springs: { structural: { ks: 100, kd: 0.1 } } }\n"
    "forces:\n"
    "  - { type: gravity }\n";

std::string SmallCloth(const std::string& linear_solver) {
  std::string s = kSmallCloth;
  s.replace(s.find("%s"), 2, linear_solver);
  return s;
}

// A force without Jacobians: auto solves by CG (matrix-free), and gets the
// analytic drag's answer; direct cannot, and says so before stepping.
TEST(ImplicitEuler, DirectRefusesForcesWithoutJacobiansAndAutoFallsBackToCg) {
  Scene analytic = test::load_text(SmallCloth("direct") + "  - { type: drag, k: 0.02 }\n");
  ASSERT_EQ(run_scene(analytic).exit_code, 0);

  Scene automatic = test::load_text(SmallCloth("auto"));
  SystemAssembly(*automatic.system).add_force(std::make_shared<test::OpaqueDrag>(), "opaque drag");
  const RunResult ra = run_scene(automatic);
  ASSERT_EQ(ra.exit_code, 0) << ra.message;
  const double diff =
      (analytic.system->state() - automatic.system->state()).lpNorm<Eigen::Infinity>();
  std::cout << "5 x 5 cloth, direct with analytic drag vs auto (CG) with matrix-free drag: " << diff
            << " apart after 20 steps\n";
  EXPECT_LT(diff, 1e-8);

  Scene direct = test::load_text(SmallCloth("direct"));
  SystemAssembly(*direct.system).add_force(std::make_shared<test::OpaqueDrag>(), "opaque drag");
  const RunResult rd = run_scene(direct);
  EXPECT_EQ(rd.exit_code, 3);
  EXPECT_NE(rd.message.find("implicit_euler: linear_solver: direct needs every force's Jacobian, "
                            "but force 'opaque drag' has none (use linear_solver: auto or cg, "
                            "which solve matrix-free)"),
            std::string::npos)
      << rd.message;
  EXPECT_EQ(rd.steps_done, 0);
  EXPECT_EQ(direct.system->time(), 0.0);
}

// A force whose df/dx is positive definite (a repulsion from the origin
// growing with distance, f = +k x) makes M - h^2 df/dx indefinite once
// h^2 k > m: the direct solve finds a pivot that is not positive definite
// and stops, as CG does when p.Ap <= 0.
class AntiSpring final : public Force {
 public:
  explicit AntiSpring(double k) : k_(k) {}
  void add_forces(const ParticleView& p, Eigen::Ref<Matrix3X> f) override { f += k_ * p.x; }
  bool add_jacobians(const ParticleView& p, JacobianSink& sink) override {
    for (Index i = 0; i < p.x.cols(); ++i) sink.add_dfdx(i, i, k_ * Eigen::Matrix3d::Identity());
    return true;
  }

 private:
  double k_;
};

TEST(ImplicitEuler, DirectSolveReportsAMatrixThatIsNotPositiveDefinite) {
  for (const std::string linear_solver : {"direct", "cg"}) {
    Scene s = test::load_text(SmallCloth(linear_solver));
    SystemAssembly(*s.system).add_force(std::make_shared<AntiSpring>(1000.0),
                                        "anti-spring");  // h^2 k / m = 10
    const RunResult r = run_scene(s);
    std::cout << linear_solver << ": " << r.message << "\n";
    EXPECT_EQ(r.exit_code, 3) << linear_solver;
    EXPECT_NE(r.message.find("implicit_euler: the linear system is not positive definite at t = "
                             "0.01 s"),
              std::string::npos)
        << r.message;
  }
}

TEST(ImplicitEuler, UnknownLinearSolverIsRefusedAtItsKey) {
  EXPECT_EQ(test::load_problems("simulation: { dt: 0.01, steps: 1, solver: { type: "
                                "implicit_euler, linear_solver: lu } }\n"
                                "particles:\n  - { position: [0, 0, 0], mass: 1 }\n"),
            "test.yaml:1:82: simulation.solver.linear_solver: 'lu' is not a linear solver "
            "(expected one of: auto, direct, cg)");
}

}  // namespace
}  // namespace pdyn

namespace pdyn {
namespace {

// A solver's first step records the forces' blocks and builds the pattern;
// later steps enter each block straight into its slot. Both ways must give
// the same bits, or a resumed run (a fresh solver) would part from the
// original: here a solver taking over after 5 steps against one that took
// all 10, by both linear solvers.
TEST(ImplicitEuler, AFreshSolverStepsAsOneThatHasRunAllAlong) {
  for (const auto linear : {solvers::LinearSolver::Direct, solvers::LinearSolver::Cg}) {
    solvers::ImplicitEulerOptions options;
    options.linear_solver = linear;
    Scene all = StiffCloth("{ type: implicit_euler }", 10);
    Scene taken_over = StiffCloth("{ type: implicit_euler }", 10);
    solvers::ImplicitEuler one(options), first(options), second(options);
    for (int k = 0; k < 10; ++k) {
      one.step(*all.system, 0.01);
      (k < 5 ? first : second).step(*taken_over.system, 0.01);
    }
    EXPECT_EQ(one.steps(), 10);
    EXPECT_GT((all.system->positions() - taken_over.system->positions()).size(), 0);
    EXPECT_EQ(all.system->state(), taken_over.system->state());
  }
}

// The direct solve's statistics are 0 until its analysis, also for a solver
// that only ever runs CG (the stiff-cloth bench asks one for them; factor_bytes
// once read past an empty vector there).
TEST(ImplicitEuler, DirectStatisticsAreZeroForASolverThatOnlyRanCg) {
  solvers::ImplicitEulerOptions options;
  options.linear_solver = solvers::LinearSolver::Cg;
  solvers::ImplicitEuler cg(options);
  EXPECT_EQ(cg.factor_bytes(), 0.0);
  Scene scene = StiffCloth("{ type: implicit_euler }", 2);
  cg.step(*scene.system, 0.01);
  cg.step(*scene.system, 0.01);
  EXPECT_FALSE(cg.last_step_direct());
  EXPECT_GT(cg.total_cg_iterations(), 0);
  EXPECT_EQ(cg.factor_blocks(), 0u);
  EXPECT_EQ(cg.factor_bytes(), 0.0);
  EXPECT_EQ(cg.factor_flops(), 0.0);
}

}  // namespace
}  // namespace pdyn
