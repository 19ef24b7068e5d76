// pdyn/solver.hpp — the Solver interface.
//
// A solver sees the particle system only through Witkin's solver interface
// (pdyn::System: dimension, get/set state, derivative evaluation), plus split
// position/velocity views for methods that treat them differently.
#pragma once

#include <Eigen/Core>
#include <cstdint>

#include "pdyn/export.hpp"
#include "pdyn/plugin_object.hpp"

namespace pdyn {

class System;

/// Step counts of an adaptive solver.
struct StepCounts {
  std::int64_t accepted = 0;
  std::int64_t rejected = 0;
};

class PDYN_API Solver : public PluginObject {
 public:
  /// Advances `sys` by one step of `h` seconds: on return its state is the
  /// solution at time() + h and its time has been advanced by h. Hosts step
  /// through pdyn::Stepper (pdyn/host/stepper.hpp), which owns time: it then sets
  /// the time to the step's exact end, applies the collider responses and
  /// checks the state, so a solver does none of that. Scratch
  /// vectors should be members sized on the first call, so that later steps
  /// do not allocate.
  virtual void step(System& sys, double h) = 0;

  // ---- optional: adaptive step-size control ----

  /// True if the runner should drive this solver with advance() instead of
  /// fixed steps of the scene's dt.
  virtual bool adaptive() const noexcept { return false; }

  /// Adaptive solvers: takes one accepted step from sys.time(), choosing its
  /// length (rejecting and retrying internally as needed) but ending no later
  /// than `t_stop`; returns the length taken, s. `h_hint` is the scene's dt,
  /// a first guess. The default takes one fixed step of min(h_hint, t_stop - t).
  virtual double advance(System& sys, double t_stop, double h_hint);

  /// Dense output: writes into `y` (6N) the state at time `t` within the last
  /// accepted step, so output frames land exactly on their times. Returns
  /// false if the solver has no dense output.
  virtual bool interpolate(double t, Eigen::Ref<Eigen::VectorXd> y) const {
    (void)t;
    (void)y;
    return false;
  }

  /// Accepted and rejected steps so far (adaptive solvers), for the report
  /// at the end of a run.
  virtual StepCounts counts() const noexcept { return {}; }
};

}  // namespace pdyn
