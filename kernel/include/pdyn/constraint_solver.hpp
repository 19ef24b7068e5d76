// pdyn/constraint_solver.hpp — an optional interface for solvers that keep
// the system on its constraints themselves (since 0.9.0).
//
// By default the kernel enforces constraints with Witkin's constraint force,
// added in every derivative evaluation (pdyn/constraint.hpp), which works
// with every solver. A solver that projects positions and velocities back
// onto the constraints instead (RATTLE: Andersen 1983; XPBD: Macklin, Muller
// & Chentanez 2016) does not want that force as well: it implements this
// interface beside pdyn::Solver, and the host turns the force off while the
// solver steps the system (pdyn::Stepper). The solver reads the constraints
// through System::evaluate_constraint_rows().
//
//   class Xpbd final : public pdyn::Solver, public pdyn::ConstraintSolver { ... };
#pragma once

#include "pdyn/export.hpp"

namespace pdyn {

class PDYN_API ConstraintSolver {
 public:
  virtual ~ConstraintSolver();  // defined in the kernel: one type_info for every library

  /// True if step() keeps C = 0 (and Cdot = 0) itself, so that the kernel
  /// must not add Witkin's constraint force. May depend on the solver's
  /// parameters (verlet: `constraints: rattle` or `force`).
  virtual bool enforces_constraints() const noexcept = 0;

  /// True if the solver honours a constraint's compliance (the scene's
  /// `compliance` key, ConstraintRows::compliance): a scene with a compliant
  /// constraint and a solver that treats every constraint as rigid is
  /// refused at load time.
  virtual bool honours_compliance() const noexcept { return false; }
};

}  // namespace pdyn
