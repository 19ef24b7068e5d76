// pdyn/targets.hpp — an optional interface for forces that pull particles
// towards points in space which a host may move while the simulation runs
// (the `anchor` force; an interactive viewer's mouse spring).
//
// A host finds it with dynamic_cast on a force it holds:
//
//   for (auto& fo : system.force_objects()) {
//     if (auto* t = pdyn::movable_targets(*fo.force)) t->set_target(0, mouse_point);
//   }
//
// Moved targets are part of the force's state: a force implementing this
// interface must carry them in save_state()/restore_state(), so that a
// checkpointed and resumed run stays bit-identical to an uninterrupted one.
#pragma once

#include <cstddef>

#include "pdyn/export.hpp"
#include "pdyn/force.hpp"
#include "pdyn/types.hpp"

namespace pdyn {

class PDYN_API MovableTargets {
 public:
  virtual ~MovableTargets();  // defined in the kernel: one type_info for every library

  /// Number of targets K; target k is numbered as the force documents it
  /// (for `anchor`: the target of ids[k]).
  virtual std::size_t target_count() const = 0;
  /// Position of target k, m. Throws pdyn::Error if k >= target_count().
  virtual Vec3 target(std::size_t k) const = 0;
  /// Moves target k to `point` (m), from the next derivative evaluation on.
  /// Call it between steps, not during one, and call System::touch() after
  /// it (forces evaluated before are no longer valid). Throws pdyn::Error if k >=
  /// target_count() or `point` is not finite.
  virtual void set_target(std::size_t k, const Vec3& point) = 0;
};

/// The force's MovableTargets interface, or nullptr if it has none.
inline MovableTargets* movable_targets(Force& force) {
  return dynamic_cast<MovableTargets*>(&force);
}

}  // namespace pdyn
