// pdyn::Stepper, the one step: exact end times, rollback to the last good
// state, and naming the plugin object at fault (pdyn/host/stepper.hpp).
#include "pdyn/host/stepper.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>
#include <vector>

#include "pdyn/error.hpp"
#include "pdyn/host/assembly.hpp"
#include "pdyn/solver.hpp"
#include "pdyn/system.hpp"

namespace pdyn {
namespace {

// f = -k x on every particle: the harmonic oscillator, x(t) = cos(w t).
class Spring : public Force {
 public:
  explicit Spring(double k) : k_(k) {}
  void add_forces(const ParticleView& p, Eigen::Ref<Matrix3X> f) override { f -= k_ * p.x; }

 private:
  double k_;
};

// Adds NaN once the time passes `t_bad`.
class NanAfter : public Force {
 public:
  explicit NanAfter(double t_bad) : t_bad_(t_bad) {}
  void add_forces(const ParticleView& p, Eigen::Ref<Matrix3X> f) override {
    if (p.t > t_bad_) f(0, 1) += std::numeric_limits<double>::quiet_NaN();
  }

 private:
  double t_bad_;
};

class Throws : public Force {
 public:
  void add_forces(const ParticleView&, Eigen::Ref<Matrix3X>) override {
    throw std::runtime_error("no force today");
  }
};

// Symplectic Euler that leaves the time a little off, as a careless solver
// might: the stepper, which owns time, must end the step exactly.
class SloppyEuler : public Solver {
 public:
  void step(System& sys, double h) override {
    sys.velocities() += h * sys.compute_accelerations();
    sys.positions() += h * sys.velocities();
    sys.set_time(sys.time() + h * (1 + 1e-9));
  }
};

// A solver that gives up on its own, after evaluating the forces.
class GivesUp : public Solver {
 public:
  void step(System& sys, double) override {
    (void)sys.compute_accelerations();
    throw std::runtime_error("matrix is singular");
  }
};

std::unique_ptr<System> two_particles() {
  auto sys = std::make_unique<System>();
  Matrix3X x = Matrix3X::Zero(3, 2), v = Matrix3X::Zero(3, 2);
  x(0, 0) = 1;  // particle 0 at (1, 0, 0), particle 1 at (2, 0, 0)
  x(0, 1) = 2;
  SystemAssembly(*sys).set_particles(x, v, Eigen::VectorXd::Ones(2), {0, 0});
  return sys;
}

const std::string kSolverLabel = "euler (test)";

TEST(Stepper, AFixedStepEndsExactlyAtTheTimeAskedForAndFollowsTheOscillator) {
  auto sys = two_particles();
  SystemAssembly(*sys).add_force(std::make_shared<Spring>(1.0), "spring");
  SloppyEuler solver;
  Stepper stepper(*sys, solver, kSolverLabel);
  const double dt = 1e-3;
  for (int k = 1; k <= 1000; ++k) {
    const auto h = stepper.step_to(k * dt);
    ASSERT_TRUE(h);
    EXPECT_EQ(sys->time(), k * dt);  // bit-exact: computed, not accumulated
  }
  // Symplectic Euler is first order: x(1) = cos(1) to O(dt).
  EXPECT_NEAR(sys->positions()(0, 0), std::cos(1.0), 1e-3);
  EXPECT_NEAR(sys->positions()(0, 1), 2 * std::cos(1.0), 2e-3);
}

TEST(Stepper, AThrowingForceIsNamedAndTheLastGoodStateIsRestored) {
  auto sys = two_particles();
  SystemAssembly(*sys).add_force(std::make_shared<Throws>(), "throws (scene.yaml:4:5)");
  SloppyEuler solver;
  Stepper stepper(*sys, solver, kSolverLabel);
  const Eigen::VectorXd before = sys->state();
  EXPECT_FALSE(stepper.step_to(0.01));
  const StepFault& f = stepper.fault();
  EXPECT_EQ(f.kind, StepFault::Kind::PluginThrew);
  EXPECT_EQ(f.label, "throws (scene.yaml:4:5)");
  EXPECT_EQ(f.what, "throws (scene.yaml:4:5): add_forces threw: no force today");
  EXPECT_EQ(f.exit_code(), 3);
  EXPECT_EQ(sys->state(), before);
  EXPECT_EQ(sys->time(), 0.0);
}

// Steps `sys`, with a spring and a force that turns NaN after t = 0.025, to
// t = 0.03, then takes the step that fails: the fault names that force and
// particle 1, and the state is the last good one, at t = 0.03.
void ExpectTheNanStepTracedAndRolledBack(System& sys) {
  SystemAssembly(sys).add_force(std::make_shared<Spring>(1.0), "spring");
  SystemAssembly(sys).add_force(std::make_shared<NanAfter>(0.025), "nan (scene.yaml:9:5)");
  SloppyEuler solver;
  Stepper stepper(sys, solver, kSolverLabel);
  ASSERT_TRUE(stepper.step_to(0.01));
  ASSERT_TRUE(stepper.step_to(0.02));
  const Eigen::VectorXd good = sys.state();
  ASSERT_TRUE(stepper.step_to(0.03));  // evaluated at t = 0.02: still finite
  const Eigen::VectorXd good3 = sys.state();
  EXPECT_FALSE(stepper.step_to(0.04));  // evaluated at t = 0.03 > 0.025
  const StepFault& f = stepper.fault();
  EXPECT_EQ(f.kind, StepFault::Kind::NonFiniteState);
  EXPECT_EQ(f.particle, 1);
  EXPECT_EQ(f.start_time, 0.03);
  EXPECT_EQ(f.label, "nan (scene.yaml:9:5)");
  EXPECT_NE(f.what.find("non-finite force on particle 1"), std::string::npos) << f.what;
  EXPECT_EQ(f.exit_code(), 4);
  EXPECT_EQ(sys.state(), good3);
  EXPECT_EQ(sys.time(), 0.03);
  EXPECT_NE(good, good3);
}

TEST(Stepper, ANonFiniteStateIsTracedToTheForceThatProducedIt) {
  auto sys = two_particles();
  ExpectTheNanStepTracedAndRolledBack(*sys);
}

// The same for a state above the size that gets a second buffer (8 MB,
// 174,762 particles: stepper.cpp), where the end state is checked first and
// only then copied over the last good one; and a good step there keeps its
// end state as the next last good one.
TEST(Stepper, ALargeNonFiniteStateIsRolledBackToTheLastGoodOne) {
  const Index n = 200000;
  const std::vector<std::uint8_t> none_fixed(static_cast<std::size_t>(n), 0);
  System sys;
  Matrix3X x = Matrix3X::Zero(3, n);
  x.row(0).setLinSpaced(n, 1.0, 2.0);
  SystemAssembly(sys).set_particles(x, Matrix3X::Zero(3, n), Eigen::VectorXd::Ones(n), none_fixed);
  ExpectTheNanStepTracedAndRolledBack(sys);

  System fresh;
  SystemAssembly(fresh).set_particles(sys.positions(), sys.velocities(), Eigen::VectorXd::Ones(n),
                                      none_fixed);
  SystemAssembly(fresh).add_force(std::make_shared<Spring>(1.0), "spring");
  fresh.set_time(0.03);
  SloppyEuler solver;
  Stepper stepper(fresh, solver, kSolverLabel);
  ASSERT_TRUE(stepper.step_to(0.04));
  const Eigen::VectorXd good4 = fresh.state();
  SystemAssembly(fresh).add_force(std::make_shared<Throws>(), "throws (scene.yaml:4:5)");
  EXPECT_FALSE(stepper.step_to(0.05));
  EXPECT_EQ(fresh.state(), good4);
}

TEST(Stepper, ASolverThatGivesUpIsNamedWhenNoForceIsAtFault) {
  auto sys = two_particles();
  SystemAssembly(*sys).add_force(std::make_shared<Spring>(1.0), "spring");
  GivesUp solver;
  Stepper stepper(*sys, solver, kSolverLabel);
  EXPECT_FALSE(stepper.step(0.01));
  const StepFault& f = stepper.fault();
  EXPECT_EQ(f.kind, StepFault::Kind::SolverThrew);
  EXPECT_EQ(f.label, kSolverLabel);
  EXPECT_EQ(f.what, "matrix is singular");
  EXPECT_FALSE(f.found_by_replay);
}

TEST(Stepper, ASolverThatGivesUpOnANaNIsTracedToTheForceThatMadeIt) {
  auto sys = two_particles();
  SystemAssembly(*sys).add_force(std::make_shared<Spring>(1.0), "spring");
  SystemAssembly(*sys).add_force(std::make_shared<NanAfter>(-1.0), "nan (scene.yaml:9:5)");
  // An implicit solver's linear solve fails on a NaN; it throws its own
  // error. The replay with per-force finite checks finds the force.
  class GivesUpOnNan : public Solver {
   public:
    void step(System& sys, double) override {
      if (!sys.compute_accelerations().allFinite()) throw std::runtime_error("NaN in the matrix");
    }
  } solver;
  Stepper stepper(*sys, solver, kSolverLabel);
  EXPECT_FALSE(stepper.step(0.01));
  const StepFault& f = stepper.fault();
  EXPECT_EQ(f.kind, StepFault::Kind::NonFiniteForce);
  EXPECT_EQ(f.label, "nan (scene.yaml:9:5)");
  EXPECT_EQ(f.solver_message, "NaN in the matrix");
  EXPECT_EQ(f.exit_code(), 4);
  EXPECT_EQ(sys->time(), 0.0);
}

}  // namespace
}  // namespace pdyn
