// pdyn/thermo.hpp — temperature and pressure of a particle system, and the
// two optional interfaces they need from plugins.
//
// The kinetic temperature is the equipartition estimate
//   k_B T = 2 K / N_f,   K = sum_i m_i |v_i|^2 / 2 over the free particles,
// with N_f = 3 N_free - extra degrees of freedom (3 by default: the total
// momentum, as LAMMPS's `compute temp` removes it). The pressure is the
// virial estimate (Allen & Tildesley, "Computer Simulation of Liquids",
// 2nd ed., eq. 2.61)
//   P = (2 K + W) / (3 V),   W = sum over interacting pairs of r_ij . f_ij,
// where r_ij = x_i - x_j is measured to the nearest periodic image and f_ij
// is the force on i from j. Forces report W through VirialSource; external
// forces (gravity, drag, a field, a thermostat) contribute none, as LAMMPS's
// fixes contribute none unless asked.
//
// With constraints (pdyn/constraint.hpp; docs/constraints.md, "Temperature
// and pressure"), since 0.10.0: each independent constraint row removes one
// degree of freedom, N_f = 3 N_free - extra - rank J (redundant rows counted
// once: constraint_dof()), as LAMMPS's fix shake/rattle removes one per bond
// (its compute temp's dof); and W includes the constraint forces' virial
// (total_virial(sys, solver, h)): the constraint force J^T lambda is a force
// between the particles like any other, so the virial theorem needs it (Allen
// & Tildesley, 2nd ed., sec. 2.4 and 3.4: the pressure of a molecular system
// from atomic forces includes the constraint forces).
//
// Units: SI. Scenes in reduced (Lennard-Jones) units read as SI give
// k_B T in "J" that is LAMMPS's T* (its k_B is 1), and P in "Pa" that is P*.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "pdyn/constraint.hpp"
#include "pdyn/export.hpp"
#include "pdyn/params.hpp"
#include "pdyn/particles.hpp"

namespace pdyn {

class System;

/// Boltzmann's constant, J/K (exact since the 2019 SI).
inline constexpr double kBoltzmann = 1.380649e-23;

/// The parameters that give a temperature, in one place for every plugin and
/// scene section that takes one (langevin, nose_hoover, `velocities:`):
/// `temperature` (K) or `kT` (J: k_B T, for scenes in reduced units, where
/// it is LAMMPS's T*), exactly one of them. `what` names it in the docs
/// ("the bath's temperature"); `positive`: 0 is refused too (a Nose-Hoover
/// chain's masses scale with it). `kT` has the sample 1 J for `pdyn check`.
PDYN_API std::vector<ParamSpec> temperature_params(const std::string& what, bool positive);

/// k_B T (J) from temperature_params()'s keys. Throws ParamError naming the
/// key when neither or both are given.
PDYN_API double temperature_kT(const Params& p);

/// Optional interface of a force: its virial. Found with dynamic_cast on the
/// Force (forces built against an earlier SDK keep their vtable). Every
/// PairForce and BondedForce implements it, and the shipped external forces
/// (which return 0); a force without it makes the pressure unknown rather than
/// silently wrong (total_virial()).
class PDYN_API VirialSource {
 public:
  virtual ~VirialSource();  // defined in the kernel: one type_info for every library
  /// W = sum over this force's interactions of r . f (J): for a pair, (x_i -
  /// x_j) . f_ij with the separation to the nearest image; for a term over
  /// several particles, sum_a (x_a - x_0) . f_a (translation-invariant, since
  /// the term's forces sum to zero). 0 for a force from outside the system.
  virtual double virial(const ParticleView& p) const = 0;
};

/// Optional interface of a force or a solver that exchanges energy with a
/// reservoir (a thermostat): the energy it has taken out of the particles so
/// far, J. K + U + reservoir_energy() is then the conserved quantity (for a
/// Nose-Hoover chain, its extended energy). Carried in save_state() by the
/// object, so that a resumed run continues it.
class PDYN_API EnergyReservoir {
 public:
  virtual ~EnergyReservoir();
  virtual double reservoir_energy() const = 0;
};

/// The sum of every force's virial in `sys`, J.
struct VirialSum {
  double value = 0.0;
  /// The label of the first force without VirialSource (the pressure is
  /// unknown then), or empty.
  std::string missing;
};
PDYN_API VirialSum total_virial(const System& sys);

class Solver;

/// Since 0.10.0: the degrees of freedom `sys`'s constraints remove at its
/// current state: the rank of J restricted to the free particles'
/// coordinates, so that redundant rows (a rod given twice, a triangle of rods
/// between pinned particles) count once and a row that acts on fixed
/// particles only counts none. Rows are grouped by the free particles they
/// share; a group of one row counts 1 (0 if its gradient vanishes), a larger
/// group the rank of its rows, each scaled to unit length, by column-pivoted
/// QR with the relative threshold 1e-10 (above 200 rows, a cloth, by Givens
/// rotations of the rows into R with the same threshold: counted once per
/// structure, the System, its constraint objects and fixed particles, and
/// kept per thread for later calls). 0
/// without constraints. Evaluates the constraints (System::
/// evaluate_constraint_rows). The rank is that of the state: at a singular
/// configuration (a straight line of rods with its "bend" rods) it is lower
/// than elsewhere.
PDYN_API double constraint_dof(const System& sys);

/// Since 0.10.0: the virial of constraint forces J^T Lambda at the state `p`:
/// sum over rows r of Lambda_r sum_e (x_k(e) - x_k(first)) . J_e, the row's
/// entries e measured from its first particle to the nearest image (the
/// convention of VirialSource for a term over several particles; a row over
/// one particle, a pin, contributes 0, as external forces do). `rows` gives
/// the pattern and J, `multipliers` Lambda (N per row unit), one per row.
PDYN_API double constraint_force_virial(const ParticleView& p, const ConstraintRows& rows,
                                        const Eigen::VectorXd& multipliers);

/// Since 0.10.0: optional interface of a solver that keeps constraints itself
/// (pdyn/constraint_solver.hpp): the virial (J) of its constraint forces at
/// the current state, for a step of `h` (s) starting there. Found with
/// dynamic_cast on the Solver. RATTLE (plugins/solvers/verlet) gives the
/// virial of the position stage's constraint forces of the step that starts
/// at this state, LAMMPS's convention for fix shake and fix rattle. A
/// solver that enforces constraints without it makes the pressure unknown.
class PDYN_API ConstraintVirialSource {
 public:
  virtual ~ConstraintVirialSource();  // defined in the kernel: one type_info for every library
  /// Called between steps, with the forces of an evaluation at the current
  /// state in sys.forces(). Throws pdyn::Error if it cannot be computed.
  virtual double constraint_virial(const System& sys, double h) const = 0;
};

/// Since 0.10.0: every force's virial (total_virial(sys)) plus, when `sys`
/// has constraint rows, the constraint forces': the solver's
/// (ConstraintVirialSource) if it enforces the constraints, else Witkin's
/// J^T lambda of the last evaluation (System::constraint_force_virial).
/// Expects sys.forces() to be an evaluation at the current state (the host
/// evaluates before a frame). `h` is the step the solver takes next (s).
/// NaN when a part is unknown, with `missing` the force's label, "solver"
/// for a solver that keeps the constraints without ConstraintVirialSource
/// (xpbd), or kSolverFailed followed by the solver's message when its
/// constraint_virial threw at this state.
PDYN_API VirialSum total_virial(const System& sys, const Solver* solver, double h);
/// VirialSum::missing's start when the solver could not compute the
/// constraint virial at the state (total_virial above).
inline constexpr const char* kSolverFailed = "solver failed: ";

/// The energy every EnergyReservoir among `sys`'s forces and `solver` (if
/// not null) has taken out of the particles, J.
PDYN_API double total_reservoir_energy(const System& sys, const Solver* solver);

/// Temperature and pressure of a state.
struct Thermo {
  double dof = 0.0;          ///< degrees of freedom N_f = 3 N_free - extra (>= 0); with
                             ///< constraints, extra includes constraint_dof()
  double kinetic = 0.0;      ///< K over the free particles, J
  double kT = 0.0;           ///< k_B T = 2 K / N_f, J (0 when N_f = 0)
  double temperature = 0.0;  ///< T = kT / k_B, K
  double volume = 0.0;       ///< the box's volume, m^3; NaN in open space
  double virial = 0.0;       ///< W, J (as given)
  double pressure = 0.0;     ///< (2 K + W) / (3 V), Pa; NaN in open space or W NaN
};

/// Temperature and pressure of the state `p` with the virial `virial` (J; NaN
/// when unknown), removing `extra_dof` degrees of freedom (3: the momentum).
/// Sums in particle order: the same bits for any thread count. With
/// constraints, pass extra_dof + constraint_dof(sys) and the virial of
/// total_virial(sys, solver, h).
PDYN_API Thermo thermo(const ParticleView& p, double virial, double extra_dof = 3.0);

}  // namespace pdyn
