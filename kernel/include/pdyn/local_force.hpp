// pdyn/local_force.hpp — an optional interface for forces whose force on
// particle i depends on particle i alone (gravity, drag): the kernel then
// adds them chunk by chunk inside the pass that gathers f/m after the other
// forces, instead of in a pass over all particles of their own. At 10^6
// particles that pass moves 56 to 72 bytes per particle from memory; in the
// gather the chunk is already in cache (issue 17, item 3).
//
// A force implements it beside pdyn::Force:
//
//   class Gravity final : public pdyn::Force, public pdyn::LocalForce { ... };
//
// The kernel finds it with dynamic_cast when the force is added (like
// pdyn/targets.hpp, it is not a virtual of Force: forces without it are
// untouched). It uses it only for the forces at the end of the System's list
// (after the last force without it, so that every particle's forces are
// still added in the list's order), when there is no collider and no finite
// check is on; otherwise it calls add_forces as usual. `pdyn check` compares
// the two (force.local_range).
#pragma once

#include "pdyn/force.hpp"
#include "pdyn/types.hpp"

namespace pdyn {

class LocalForce {
 public:
  virtual ~LocalForce();  // defined in the kernel: one type_info for every library

  /// True when add_forces_range may stand for add_forces for this object
  /// (a force on every particle; one on a group may answer false).
  virtual bool acts_locally() const = 0;

  /// Adds the forces (N) on particles [begin, end) into those columns of
  /// `f`, with exactly the operations add_forces uses for them: the results
  /// must be the same bits. Called from several threads at once on disjoint
  /// ranges, after the forces before it in the list have been added. Must
  /// not throw.
  virtual void add_forces_range(const ParticleView& p, Eigen::Ref<Matrix3X> f, Index begin,
                                Index end) = 0;
};

/// The force's LocalForce interface, or nullptr if it has none.
inline LocalForce* local_force(Force& force) { return dynamic_cast<LocalForce*>(&force); }

}  // namespace pdyn
