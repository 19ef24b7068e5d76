// pdyn/particles.hpp — the views of the particle store that plugins receive.
//
// Witkin's particle is (x, v, f, m) (SIGGRAPH '97 notes, "Particle
// Structures"). pdyn stores each field as a structure of arrays; these views
// point into the store and never copy it. They are rebuilt for every call, so
// a plugin must not keep them.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <span>

#include "pdyn/domain.hpp"
#include "pdyn/export.hpp"
#include "pdyn/types.hpp"

namespace pdyn {

/// Read-only view of the phase-space state, given to forces and to colliders'
/// contact-force hook. Forces read it; they only ever write the force matrix
/// they are handed.
struct PDYN_API ParticleView {
  double t;                                ///< simulated time, s
  Eigen::Map<const Matrix3X> x;            ///< positions, m (3 x N)
  Eigen::Map<const Matrix3X> v;            ///< velocities, m/s (3 x N)
  Eigen::Map<const Eigen::VectorXd> mass;  ///< masses, kg (N)
  std::span<const std::uint8_t> fixed;     ///< 1 where a particle is nailed in place
  // Since ABI 4: what pair forces and contact laws need.
  Domain domain{};                       ///< the simulation box (default: open space)
  std::span<const double> radius{};      ///< radii, m (N), or empty: the scene gave none
  std::span<const std::int32_t> type{};  ///< types >= 0 (N), or empty: all of type 0

  /// Number of particles N.
  Index size() const noexcept { return x.cols(); }
};

/// Writable view given to a collider's collision response after an accepted
/// step: it may change positions and velocities of free particles.
struct PDYN_API MutableParticleView {
  double t;                                ///< simulated time at the end of the step, s
  Eigen::Map<Matrix3X> x;                  ///< positions, m (3 x N)
  Eigen::Map<Matrix3X> v;                  ///< velocities, m/s (3 x N)
  Eigen::Map<const Matrix3X> f;            ///< forces of the step's last derivative evaluation, N
  Eigen::Map<const Eigen::VectorXd> mass;  ///< masses, kg (N)
  std::span<const std::uint8_t> fixed;     ///< 1 where a particle is nailed in place
  // Since ABI 4, as in ParticleView.
  Domain domain{};
  std::span<const double> radius{};
  std::span<const std::int32_t> type{};

  Index size() const noexcept { return x.cols(); }
};

}  // namespace pdyn
