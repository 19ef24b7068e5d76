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

#include "pdyn/export.hpp"
#include "pdyn/force.hpp"
#include "pdyn/types.hpp"

namespace pdyn {

class PDYN_API LocalForce {
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

/// A local force linear in the mass and the velocity: on every particle i,
///
///   f_i <- f_i + acceleration * m_i   (if has_acceleration; N, gravity)
///   f_i <- f_i - damping * v_i        (then, if has_damping; N, drag)
///
/// each product and sum in double precision as written, component by
/// component, with no fused multiply-add.
struct PDYN_API LinearLocalLaw {
  bool has_acceleration = false;
  Vec3 acceleration = Vec3::Zero();  ///< m/s^2
  bool has_damping = false;
  double damping = 0.0;  ///< kg/s
};

/// Applies `law` to one particle's force f = (f0, f1, f2), N, of mass m
/// (kg) and velocity v (m/s): the operations the kernel performs.
inline void apply_linear_law(const LinearLocalLaw& law, double m, const double* v, double& f0,
                             double& f1, double& f2) {
  if (law.has_acceleration) {
    f0 += law.acceleration[0] * m;
    f1 += law.acceleration[1] * m;
    f2 += law.acceleration[2] * m;
  }
  if (law.has_damping) {
    f0 -= law.damping * v[0];
    f1 -= law.damping * v[1];
    f2 -= law.damping * v[2];
  }
}

/// Optional, beside LocalForce (since pdyn 0.10, within ABI 7): a local
/// force whose add_forces_range is a LinearLocalLaw says so, and the kernel
/// then evaluates the law itself inside its gather loop, one pass for every
/// such force and f/m together, instead of calling add_forces_range (the
/// plugin boundary cost the 1000 x 1000 cloth about 10% of its step;
/// docs/log/performance.md). The law must give add_forces' bits: `pdyn check`
/// compares them (force.linear_law).
class PDYN_API LinearLocalForce {
 public:
  virtual ~LinearLocalForce();  // defined in the kernel: one type_info for every library

  /// Fills `law` and returns true when add_forces_range is that law now;
  /// false to be called through add_forces_range. Asked once per force
  /// evaluation, only while acts_locally() is true. Must not throw.
  virtual bool linear_law(LinearLocalLaw& law) const = 0;
};

/// The force's LinearLocalForce interface, or nullptr if it has none.
inline LinearLocalForce* linear_local_force(Force& force) {
  return dynamic_cast<LinearLocalForce*>(&force);
}

}  // namespace pdyn
