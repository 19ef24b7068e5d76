// pdyn/host/velocities.hpp — initial velocities drawn from the
// Maxwell-Boltzmann distribution at a temperature (a scene's `velocities:`
// section, Python's Simulation.create_velocities), as LAMMPS's `velocity
// create`.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "pdyn/host/export.hpp"
#include "pdyn/types.hpp"

namespace pdyn {

struct PDYN_HOST_API VelocitySpec {
  double kT = 0.0;             ///< k_B T, J (>= 0)
  std::uint64_t seed = 1;      ///< the generator's seed (pdyn/random.hpp)
  bool zero_momentum = true;   ///< remove the members' total momentum
  bool scale = true;           ///< scale to exactly kT (dof 3 n - 3, or 3 n)
  std::vector<Index> members;  ///< the particles drawn for; empty: all
};

/// Overwrites the velocities (m/s) of the free members with draws from the
/// Maxwell-Boltzmann distribution at spec.kT: each component of v_i normal
/// with variance k_B T / m_i, particle i's numbers from (seed, i) alone
/// (pdyn/random.hpp), so they do not depend on the other particles, the
/// order or the thread count. Then, if asked, the members' centre-of-mass
/// velocity is subtracted, and the velocities are scaled so that 2 K / N_f
/// = k_B T exactly, N_f = 3 n - 3 with the momentum removed (3 n without),
/// n the free members: the temperature `thermo()` (pdyn/thermo.hpp) and the
/// energy writer then report at step 0. Fixed particles keep zero velocity.
/// Throws pdyn::Error when scaling is asked for but impossible: no degrees
/// of freedom, or every velocity zero.
PDYN_HOST_API void maxwell_boltzmann(Eigen::Ref<Matrix3X> v, const Eigen::VectorXd& mass,
                                     std::span<const std::uint8_t> fixed, const VelocitySpec& spec);

}  // namespace pdyn
