// pdyn/bonded_reference.hpp — the checking hook of a bonded force (since
// 0.10.0): its terms one at a time, for the conformance kit.
//
// BondedForce<Law> (pdyn/bonded_force.hpp) implements BondedReference, which
// the conformance kit (`pdyn check`, the bonded.* checks) uses to look at
// one term at a time: its forces (N) against minus the gradient of its
// energy (J), the third law and zero torque for an `internal` force, its
// Jacobians against finite differences, and the loop's sum against the
// terms'. A plugin never calls it; the kit finds it by dynamic_cast on the
// Force.
#pragma once

#include <Eigen/Core>
#include <array>

#include "pdyn/export.hpp"
#include "pdyn/particles.hpp"
#include "pdyn/types.hpp"

namespace pdyn {

/// The optional checking hook of a bonded force: one term at a time, for the
/// conformance kit (`pdyn check`, the bonded.* checks). BondedForce<Law>
/// implements it; found by dynamic_cast on the Force, so a force without it
/// keeps its vtable (no ABI bump).
class PDYN_API BondedReference {
 public:
  virtual ~BondedReference();
  /// Particles per term: 2, 3 or 4.
  virtual int bonded_arity() const = 0;
  /// How many terms the force holds.
  virtual Index bonded_terms() const = 0;
  /// Term s's particles (the first bonded_arity() entries).
  virtual std::array<Index, 4> bonded_term(Index s) const = 0;
  /// Term s's energy (J, returned) and forces on its particles (N) at `p`.
  virtual double bonded_term_forces(const ParticleView& p, Index s,
                                    std::array<Vec3, 4>& force) const = 0;
  /// Term s's Jacobians (3n x 3n for n = bonded_arity()): with exact = false
  /// what add_jacobians() adds, with exact = true the exact derivatives of
  /// bonded_term_forces(). False when the law gives no such Jacobian.
  virtual bool bonded_term_jacobian(const ParticleView& p, Index s, bool exact,
                                    Eigen::MatrixXd& dfdx, Eigen::MatrixXd& dfdv) const = 0;
};

}  // namespace pdyn
