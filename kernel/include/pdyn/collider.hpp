// pdyn/collider.hpp — the Collider interface.
//
// Witkin treats collisions as an add-on to the particle simulator ("Bouncing
// off the Walls"): detection and an impulsive velocity change after a step,
// and a contact force during derivative evaluation for particles resting on
// the obstacle. A collider implements both hooks.
#pragma once

#include "pdyn/export.hpp"
#include "pdyn/particles.hpp"
#include "pdyn/plugin_object.hpp"

namespace pdyn {

class PDYN_API Collider : public PluginObject {
 public:
  /// Contact forces, during every derivative evaluation after all force
  /// objects have run: for particles in resting contact, removes the part of
  /// `f` (N) that pushes into the obstacle (Witkin's F' = F_T).
  virtual void apply_contact_forces(const ParticleView& p, Eigen::Ref<Matrix3X> f) = 0;

  /// Collision response, once after each accepted step of length `h` (s):
  /// reflects the normal velocity of colliding particles and puts penetrating
  /// ones back on the surface. No particle may end inside the obstacle.
  virtual void respond(MutableParticleView& p, double h) = 0;
};

}  // namespace pdyn
