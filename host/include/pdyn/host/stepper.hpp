// pdyn/host/stepper.hpp — one step of a simulation, the only place that takes one.
//
// Witkin's simulation loop is "take a step, handle collisions" (SIGGRAPH '97
// notes, "Bouncing off the Walls"). A host (the runner, the viewer, a
// benchmark, the conformance kit, a Python script) takes that step through a
// Stepper, which:
//   - owns time: a fixed step ends exactly at the time it was asked for
//     (computed by the caller, never accumulated), whatever the solver left;
//   - calls the solver (step, or advance for an adaptive one), then every
//     collider's response;
//   - checks the resulting state for NaN and infinity;
//   - on any failure restores the state and time the step started from (the
//     last good state) and describes the fault, naming the plugin object at
//     fault: when the solver throws or the state turns non-finite, the step is
//     replayed with per-force finite checks to find the force that produced
//     the first non-finite value.
//
// A plugin never needs it; a solver plugin implements Solver::step only.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <string>

#include "pdyn/host/export.hpp"
#include "pdyn/kernel/neighbor_schedule.hpp"
#include "pdyn/types.hpp"

namespace pdyn {

class Solver;
class System;

/// Why a step failed. The system is back at the step's start when this is set.
struct PDYN_HOST_API StepFault {
  enum class Kind {
    PluginThrew,     ///< a plugin object threw: `label` and `what` say which and what
    SolverThrew,     ///< the solver threw on its own account (replays found no other culprit)
    NonFiniteForce,  ///< the solver threw after a force object produced a NaN or infinity
    NonFiniteState,  ///< the step ended with a non-finite position or velocity
  };
  Kind kind = Kind::SolverThrew;
  /// The plugin object at fault, as the System (or the solver's label) names
  /// it; empty when a non-finite state could not be traced to a force.
  std::string label;
  /// What it said: PluginRuntimeError::what() (which starts with the label),
  /// or the solver's exception text for SolverThrew.
  std::string what;
  /// The solver's own exception text when a replay found another culprit
  /// (found_by_replay), or for NonFiniteForce.
  std::string solver_message;
  bool found_by_replay = false;  ///< PluginThrew: found by replaying a step the solver gave up on
  bool non_standard = false;     ///< SolverThrew: the exception was not a std::exception
  double start_time = 0.0;       ///< s: the step's start, the last good time
  /// NonFiniteState: the first particle with a non-finite position or
  /// velocity, its position (m) and the time (s) at the end of the bad step.
  Index particle = -1;
  Vec3 position = Vec3::Zero();
  double end_time = 0.0;

  /// The process exit status a command-line run reports: 4 for a numerical
  /// blow-up (NonFiniteForce, NonFiniteState), 3 for a plugin fault.
  int exit_code() const noexcept {
    return kind == Kind::NonFiniteForce || kind == Kind::NonFiniteState ? 4 : 3;
  }
};

/// Takes steps of one system with one solver. Holds the last good state and
/// the next one (2 x 6N doubles, allocated when the stepper is made; steps do
/// not allocate unless the system's size changed).
class PDYN_HOST_API Stepper {
 public:
  /// `solver_label` names the solver in faults and crash reports ("rk4
  /// (scene.yaml:3:11)"); it is referenced, not copied, and must outlive the
  /// stepper.
  /// `neighbors`: when the system's shared neighbor lists are rebuilt
  /// (pdyn/neighbors.hpp; a scene's simulation.neighbor), counted in the
  /// fixed steps step_to() takes.
  Stepper(System& sys, Solver& solver, const std::string& solver_label,
          const RebuildSchedule& neighbors = {});

  /// One fixed step from time() to `t_end` (h = t_end - time()); on success
  /// the time is exactly `t_end`. Returns h, or nothing after a fault.
  std::optional<double> step_to(double t_end);

  /// One accepted step of an adaptive solver (Solver::advance) ending no
  /// later than `t_stop`, with `h_hint` (s) as a first guess. Returns the
  /// length taken, or nothing after a fault.
  std::optional<double> advance(double t_stop, double h_hint);

  /// One step of `dt` as the solver wants it: advance(time() + dt, dt) for an
  /// adaptive solver (at most dt), step_to(time() + dt) otherwise.
  std::optional<double> step(double dt);

  /// The last fault; meaningful after a step returned nothing.
  const StepFault& fault() const noexcept { return fault_; }

  System& system() noexcept { return sys_; }
  Solver& solver() noexcept { return solver_; }
  const std::string& solver_label() const noexcept { return *label_; }

 private:
  template <class Take>
  std::optional<double> guarded(const Take& take);
  template <class Take>
  bool replay(const Take& take, bool finite_checks);
  std::nullopt_t fail();

  System& sys_;
  Solver& solver_;
  const std::string* label_;
  RebuildSchedule neighbors_;
  Eigen::VectorXd previous_;  // the last good state: where the current step started
  Eigen::VectorXd next_;      // a small state's end, copied there while it is checked
  std::uint64_t version_ = ~std::uint64_t{0};  // System::state_version() when previous_ was kept
  double t_previous_ = 0.0;
  StepFault fault_;
  StepFault replayed_;  // what a replay found
};

}  // namespace pdyn
