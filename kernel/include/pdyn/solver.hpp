// pdyn/solver.hpp — the Solver interface.
//
// A solver sees the particle system only through Witkin's solver interface
// (pdyn::System: dimension, get/set state, derivative evaluation), plus split
// position/velocity views for methods that treat them differently.
#pragma once

namespace pdyn {

class System;

class Solver {
 public:
  virtual ~Solver() = default;

  /// Advances `sys` by one step of `h` seconds: on return its state is the
  /// solution at time() + h and its time has been advanced by exactly h.
  /// Collider responses are applied by the kernel after this returns. Scratch
  /// vectors should be members sized on the first call, so that later steps
  /// do not allocate.
  virtual void step(System& sys, double h) = 0;
};

}  // namespace pdyn
