// The check of every kind "threads.two_systems": two systems, each with its
// own plugin object, stepped in two threads at once, must end bit-identical
// to the same runs in one thread. Every step is taken by a pdyn::Stepper, as
// in a run; force and collider plugins are stepped by the kit's symplectic
// Euler, a solver plugin by itself, a constraint plugin by the kit's rk4: a
// free fall from rest under Witkin's constraint force (with feedback, so that
// every value the constraint writes, C, c_t, b and J, steers the motion).
//
// Scenes are independent, so a host may run two of them at once (a parameter
// sweep, a GUI next to a batch run). A plugin that keeps mutable state outside
// its objects (a static scratch buffer, a global cache) breaks that silently.
// Each run builds its own System and plugin object from its own seed; the two
// seeds differ so that shared state shows up as a difference.
#include <fmt/format.h>

#include <algorithm>
#include <exception>
#include <latch>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <thread>

#include "checks.hpp"
#include "pdyn/host/assembly.hpp"
#include "pdyn/host/stepper.hpp"
#include "pdyn/system.hpp"
#include "sample.hpp"

namespace pdyn::conformance::detail {

namespace {

constexpr int kThreadSteps = 100;
constexpr double kThreadStep = 0.005;  // s
constexpr int kThreadRounds = 3;

// The kit's own solver for force and collider plugins: symplectic Euler,
// v += h a, then x += h v with the new velocity.
class SymplecticEuler final : public Solver {
 public:
  void step(System& sys, double h) override {
    const Matrix3X& a = sys.compute_accelerations();
    sys.velocities() += h * a;
    sys.positions() += h * sys.velocities();
    sys.set_time(sys.time() + h);
  }
};

// The kit's solver for constraint plugins: the classic fourth-order
// Runge-Kutta method through derivative(), each evaluation of which adds the
// constraint force.
class KitRk4 final : public Solver {
 public:
  void step(System& sys, double h) override {
    const double t0 = sys.time();
    y0_ = sys.state();
    k_.resize(y0_.size());
    sys.derivative(k_);
    sum_ = k_;
    sys.state() = y0_ + (0.5 * h) * k_;
    sys.set_time(t0 + 0.5 * h);
    sys.derivative(k_);
    sum_ += 2.0 * k_;
    sys.state() = y0_ + (0.5 * h) * k_;
    sys.derivative(k_);
    sum_ += 2.0 * k_;
    sys.state() = y0_ + h * k_;
    sys.set_time(t0 + h);
    sys.derivative(k_);
    sum_ += k_;
    sys.state() = y0_ + (h / 6.0) * sum_;
  }

 private:
  Eigen::VectorXd y0_, k_, sum_;
};

// A constraint plugin's system: gravity, the object made from the system's
// initial state, and feedback (ks = 100 1/s^2, kd = 20 1/s: critically
// damped at 10 rad/s, well inside rk4's stability at 5 ms).
std::unique_ptr<Solver> add_constraint_under_test(System& sys, const PluginDescriptor& d,
                                                  const Params& params, const std::string& label) {
  const SceneContext ctx{sys.view(), nullptr};
  SystemAssembly(sys).add_force(std::make_shared<Constant>(Vec3(0.5, -0.3, -9.81)),
                                "conformance gravity");
  SystemAssembly(sys).add_constraint(std::shared_ptr<Constraint>(d.create_constraint(params, ctx)),
                                     label);
  SystemAssembly(sys).set_constraint_feedback({.ks = 100.0, .kd = 20.0});
  SystemAssembly(sys).enable_constraint_force(true);
  return std::make_unique<KitRk4>();
}

// What a failed step says: the fault's `what` (which names the plugin object
// at fault, except for a solver's own exception), or what happened.
std::string fault_text(const StepFault& f) {
  if (f.kind == StepFault::Kind::SolverThrew) {
    return f.non_standard ? fmt::format("{}: step threw a non-standard exception", f.label)
                          : fmt::format("{}: step threw: {}", f.label, f.what);
  }
  if (!f.what.empty()) return f.what;
  return fmt::format("the state became non-finite: particle {} at t = {} s", f.particle,
                     f.end_time);
}

// A run's final state, or why a step failed (then `fault` is not empty).
struct Run {
  Eigen::VectorXd state;
  std::string fault;
};

Run separate_run(const PluginDescriptor& d, const Params& params, std::uint64_t seed) {
  static const std::string kKitSolver = "conformance symplectic Euler";
  static const std::string kKitRk4 = "conformance rk4";
  static const std::string kUnderTest = "under test";
  std::mt19937_64 r(seed);
  State s = random_state(r);
  if (d.kind == PluginKind::Collider) s.x *= 0.5;  // near the origin, where default obstacles are
  if (d.kind == PluginKind::Constraint) s.v.setZero();  // from rest: no rod collapses at once
  auto sys = std::make_unique<System>();
  SystemAssembly(*sys).set_particles(s.x, s.v, s.mass, s.fixed);
  SystemAssembly(*sys).set_radii(s.radius);
  const SceneContext ctx{sys->view(), nullptr};
  std::unique_ptr<Solver> solver;
  switch (d.kind) {
    case PluginKind::Force:
      SystemAssembly(*sys).add_force(std::shared_ptr<Force>(d.create_force(params, ctx)),
                                     kUnderTest);
      solver = std::make_unique<SymplecticEuler>();
      break;
    case PluginKind::Solver:
      SystemAssembly(*sys).add_force(std::make_shared<Anchor>(), "conformance anchor");
      SystemAssembly(*sys).add_force(std::make_shared<Constant>(Vec3(0, 0, -9.81)),
                                     "conformance gravity");
      solver = d.create_solver(params, ctx);
      break;
    case PluginKind::Collider:
      SystemAssembly(*sys).add_force(std::make_shared<Constant>(Vec3(0.5, -0.3, -9.81)),
                                     "conformance gravity");
      SystemAssembly(*sys).add_collider(std::shared_ptr<Collider>(d.create_collider(params, ctx)),
                                        kUnderTest);
      solver = std::make_unique<SymplecticEuler>();
      break;
    case PluginKind::Constraint:
      solver = add_constraint_under_test(*sys, d, params, kUnderTest);
      break;
    case PluginKind::Writer:  // writers are not stepped (report.cpp never asks)
      solver = std::make_unique<SymplecticEuler>();
      break;
  }
  Stepper stepper(*sys, *solver,
                  d.kind == PluginKind::Solver       ? kUnderTest
                  : d.kind == PluginKind::Constraint ? kKitRk4
                                                     : kKitSolver);
  const double t0 = sys->time();
  for (int k = 1; k <= kThreadSteps; ++k) {
    if (!stepper.step_to(t0 + k * kThreadStep)) {
      return {sys->state(), fmt::format("step {} of {} failed: {}", k, kThreadSteps,
                                        fault_text(stepper.fault()))};
    }
  }
  return {sys->state(), {}};
}

}  // namespace

CheckResult check_threads(const PluginDescriptor& d, const Options& o) {
  const std::string name = "threads.two_systems";
  const Params params = sample_params(d, kParticles);
  const std::uint64_t seeds[2] = {o.seed * 7919 + 101, o.seed * 7919 + 202};
  const Run expected[2] = {separate_run(d, params, seeds[0]), separate_run(d, params, seeds[1])};
  for (const Run& run : expected) {
    if (!run.fault.empty()) return result(name, false, 0, 0, run.fault);
  }
  int differing = 0;
  double worst = 0;
  for (int round = 0; round < kThreadRounds; ++round) {
    Run got[2];
    std::exception_ptr error[2];
    std::latch start(2);  // both runs begin together, so that they overlap
    {
      std::jthread threads[2];
      for (int k = 0; k < 2; ++k) {
        threads[k] = std::jthread([&, k] {
          start.arrive_and_wait();
          try {
            got[k] = separate_run(d, params, seeds[k]);
          } catch (...) {
            error[k] = std::current_exception();
          }
        });
      }
    }
    for (const auto& e : error) {
      if (e) std::rethrow_exception(e);
    }
    for (const Run& run : got) {
      if (!run.fault.empty()) {
        return result(name, false, 0, 0,
                      fmt::format("in two threads at once, though not alone: {}", run.fault));
      }
    }
    for (int k = 0; k < 2; ++k) {
      if (bit_equal(got[k].state, expected[k].state)) continue;
      ++differing;
      // NOLINTBEGIN(bugprone-narrowing-conversions): to Eigen's Scalar, a double too
      worst = std::max(worst, got[k].state.size() == expected[k].state.size()
                                  ? (got[k].state - expected[k].state).cwiseAbs().maxCoeff()
                                  : std::numeric_limits<double>::infinity());
      // NOLINTEND(bugprone-narrowing-conversions)
    }
  }
  return result(name, differing == 0, worst, 0,
                differing == 0
                    ? fmt::format("{} rounds of two threads, each with its own system and object, "
                                  "{} steps of {} s: states bit-identical to one thread's",
                                  kThreadRounds, kThreadSteps, kThreadStep)
                    : fmt::format("{} of {} concurrent runs differ from the same run alone "
                                  "(max |difference| of the state): shared mutable state?",
                                  differing, 2 * kThreadRounds));
}

}  // namespace pdyn::conformance::detail
