// pdyn/force.hpp — the Force interface.
//
// Witkin's force objects are "black boxes that point to the particles they
// influence and add in their own forces" (SIGGRAPH '97 notes, "Force
// Structures"). pdyn calls each force object once per derivative evaluation,
// with the whole particle view, so the per-call cost is paid once per force
// object, never once per particle or per spring.
#pragma once

#include <optional>

#include "pdyn/particles.hpp"

namespace pdyn {

class Force {
 public:
  virtual ~Force() = default;

  /// Adds this object's forces (N) into `f` (3 x N), for every particle it
  /// influences. Called once per derivative evaluation, after the kernel has
  /// cleared `f`. Must only add: other forces' contributions are already there.
  virtual void add_forces(const ParticleView& p, Eigen::Ref<Matrix3X> f) = 0;

  /// Potential energy (J) of this force at the state `p`, if it has one: the
  /// kernel reports total energy from it, and the conformance kit checks that
  /// f = -grad U. Forces without a potential (drag) return nullopt.
  virtual std::optional<double> potential_energy(const ParticleView& p) const {
    (void)p;
    return std::nullopt;
  }
};

}  // namespace pdyn
