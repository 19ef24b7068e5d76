// The virial of RATTLE's constraint forces at a state, for the pressure
// (pdyn/thermo.hpp: ConstraintVirialSource), in LAMMPS's convention for
// fix shake and fix rattle: the constraint forces of the position stage of
// the step that starts at the state. LAMMPS computes them at the end of
// each step (FixShake::post_force, called from FixRattle::final_integrate)
// as the forces G along the bonds at x_n that bring the unconstrained
// drift onto the constraints,
//
//   x_{n+1} = x_n + h v_n + h^2/2 W (f_n + G),   C(x_{n+1}) = 0,   G = J(x_n)^T Lambda,
//
// and tallies their virial with that step's thermo output. That is
// RATTLE's position stage (rattle.hpp) written as a force: its
// multipliers mu, with x_{n+1} = x_n + h v_half - W J0^T mu, are
// Lambda = -2 mu / h^2.
#pragma once

#include <pdyn/system.hpp>

namespace pdyn_verlet {

/// W = sum_r Lambda_r sum_e (x_k(e) - x_k(first)) . J0_e (J) at the state of
/// `sys`, with Lambda from the position stage of a step of `h` starting
/// there: x_pred = x + h v + h^2/2 W f with the forces of the last
/// evaluation (sys.forces(), at this state), then Newton's iteration
/// (J(x) W J0^T) dmu = C(x), x = x_pred - W J0^T mu, until |C| stops
/// falling (the rounding floor, far below rattle_tolerance: LAMMPS solves a
/// bond's quadratic exactly). Changes nothing in `sys`. Throws pdyn::Error
/// if |C| is still above `tolerance` when the iteration stops.
double rattle_virial(const pdyn::System& sys, double h, double tolerance);

}  // namespace pdyn_verlet
