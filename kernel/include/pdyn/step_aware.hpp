// pdyn/step_aware.hpp — an optional interface for forces that must know the
// step they are evaluated in: a force whose value is held over a step, such
// as the random force of a Langevin thermostat.
//
// A stochastic force is white noise; a solver with a fixed step h integrates
// it as a force held constant over each step, with variance scaled by 1/h
// so that the velocity it adds over the step has the variance the
// fluctuation-dissipation theorem asks for (Euler-Maruyama; Allen &
// Tildesley, "Computer Simulation of Liquids", 2nd ed., sec. 12.2). Every
// derivative evaluation of one step (rk4's four, verlet's two) then sees the
// same noise, and a step that is replayed (after a fault, or by a resumed
// run) draws the same numbers again.
//
// The host calls begin_step() before each fixed step, with the step's start
// time and length. An adaptive solver (rk45) chooses its step lengths
// itself: a scene combining it with a StepAware force is refused at load
// time, because the noise's amplitude depends on h.
//
// A force implements it beside pdyn::Force, found with dynamic_cast (no
// virtual of Force: forces built against an earlier SDK keep their vtable):
//
//   class Langevin final : public pdyn::Force, public pdyn::StepAware { ... };
#pragma once

#include "pdyn/export.hpp"

namespace pdyn {

class PDYN_API StepAware {
 public:
  virtual ~StepAware();  // defined in the kernel: one type_info for every library

  /// The step about to be taken starts at time `t` (s) and is `h` long (s,
  /// > 0). Called again with the same values when a step is replayed. Before
  /// the first call (the conformance kit, a host that evaluates forces
  /// without stepping) a force behaves as it documents, deterministically.
  virtual void begin_step(double t, double h) = 0;
};

}  // namespace pdyn
