// pdyn/force.hpp — the Force interface.
//
// Witkin's force objects are "black boxes that point to the particles they
// influence and add in their own forces" (SIGGRAPH '97 notes, "Force
// Structures"). pdyn calls each force object once per derivative evaluation,
// with the whole particle view, so the per-call cost is paid once per force
// object, never once per particle or per spring.
#pragma once

#include <optional>

#include "pdyn/export.hpp"
#include "pdyn/particles.hpp"
#include "pdyn/plugin_object.hpp"

namespace pdyn {

/// Receives the 3 x 3 blocks of a force's Jacobians, for implicit solvers
/// (Baraff & Witkin 1998, "Large Steps in Cloth Simulation", section 4).
class PDYN_API JacobianSink {
 public:
  virtual ~JacobianSink() = default;
  /// Adds `block` to df_i/dx_j, N/m.
  virtual void add_dfdx(Index i, Index j, const Eigen::Matrix3d& block) = 0;
  /// Adds `block` to df_i/dv_j, N s/m.
  virtual void add_dfdv(Index i, Index j, const Eigen::Matrix3d& block) = 0;
};

/// What a force's value depends on besides the positions and the particles'
/// fixed properties (since ABI 6). Only a claim of independence is ever used:
/// a solver may then reuse forces it evaluated at the same positions (velocity
/// Verlet needs one force evaluation per step instead of two, see
/// plugins/solvers/verlet). The default claims both, which is always safe.
struct StateDependence {
  bool velocity = true;  ///< f changes with the velocities (drag, damping)
  bool time = true;      ///< f changes with the time (driven or time-varying forces)
};

class PDYN_API Force : public PluginObject {
 public:
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

  /// Optional: adds this force's analytic Jacobians df/dx and df/dv at the
  /// state `p` into `sink` and returns true. A force without them returns
  /// false; implicit solvers then differentiate add_forces numerically.
  virtual bool add_jacobians(const ParticleView& p, JacobianSink& sink) {
    (void)p;
    (void)sink;
    return false;
  }

  /// Since ABI 6. Whether this object's forces depend on the velocities and
  /// on the time, for the parameters it was created with (a spring with kd =
  /// 0 reads no velocity). Claim independence only when add_forces would give
  /// the same bits for any velocity or time: the conformance kit checks it,
  /// and a solver that reuses forces relies on it. A force whose value can
  /// change in another way between steps (a host moving its targets, see
  /// pdyn/targets.hpp) keeps the default.
  virtual StateDependence dependence() const { return {}; }
};

}  // namespace pdyn
