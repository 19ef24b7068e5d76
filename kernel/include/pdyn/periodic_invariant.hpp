// pdyn/periodic_invariant.hpp — an optional interface for forces that the
// kernel's wrap into a periodic box cannot change: forces that measure every
// separation to the nearest image (every PairForce), or read no positions
// at all (gravity, drag). After each step the host moves particles that
// left the box by whole box lengths (System::wrap_positions); when every
// force of the System says it is periodic-invariant, that wrap does not
// count as a change of the state (System::state_version()), and velocity
// Verlet reuses the step's end forces as the next step's start forces: one
// force evaluation per step, as LAMMPS's velocity Verlet, instead of a
// second one after every step that wraps a particle (issue 30).
//
// The end forces were evaluated at the positions before the wrap, so the
// reused forces equal a fresh evaluation to rounding (x + L - x_j rounds
// differently from x - x_j), not bit for bit. `pdyn check` tests the claim
// (force.periodic_invariant: whole-box shifts of half the particles change
// no force beyond rounding).
//
// A force implements it beside pdyn::Force, found with dynamic_cast when
// the System wraps (not a virtual of Force: forces built against an earlier
// SDK keep their vtable, and count as not invariant):
//
//   class Gravity final : public pdyn::Force, public pdyn::PeriodicInvariant { ... };
//
// Bonded terms (BondedForce, pdyn/bonded_force.hpp) measure each term at
// its particles' nearest images since 0.10.0 and implement it too; a bonded
// force written by hand that measures x_i - x_j as given is not invariant
// and must not.
#pragma once

#include "pdyn/export.hpp"
#include "pdyn/force.hpp"

namespace pdyn {

class PDYN_API PeriodicInvariant {
 public:
  virtual ~PeriodicInvariant();  // defined in the kernel: one type_info for every library

  /// True when this object's forces do not change, beyond rounding, when
  /// any particles are moved by whole box lengths along periodic axes. A
  /// force may answer for its parameters (false for a field that is not
  /// periodic); the default is true.
  virtual bool periodic_invariant() const { return true; }
};

/// True when `force` implements PeriodicInvariant and answers true.
inline bool periodic_invariant(const Force& force) {
  const auto* p = dynamic_cast<const PeriodicInvariant*>(&force);
  return p != nullptr && p->periodic_invariant();
}

}  // namespace pdyn
