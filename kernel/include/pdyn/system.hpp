// pdyn/system.hpp — the particle system: store, force loop and solver interface.
//
// This is Witkin's particle system seen by a solver (SIGGRAPH '97 notes,
// "Solver Interface"): a phase-space state of dimension 6N that can be read
// and written as one contiguous vector, a time, and a derivative evaluation
// that clears the force accumulators, invokes every force object, applies
// colliders' contact forces and gathers [v, f/m].
//
// State layout: [x_0 .. x_{N-1} | v_0 .. v_{N-1}], each a 3-vector. Positions
// and velocities are stored in that one vector, so state() is the store itself
// (no copy for get/set) while positions() and velocities() are 3 x N views of
// its two halves for symplectic and implicit solvers.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <type_traits>
#include <vector>

#include "pdyn/collider.hpp"
#include "pdyn/constraint.hpp"
#include "pdyn/export.hpp"
#include "pdyn/force.hpp"
#include "pdyn/particles.hpp"
#include "pdyn/types.hpp"

namespace pdyn {

class LocalForce;
class LinearLocalForce;
struct LinearLocalLaw;
class ConstraintForce;

/// The settings of Witkin's constraint force (since ABI 7; docs/constraints.md):
///   J W J^T lambda = -b - J W Q - ks C - kd Cdot,
/// solved by preconditioned conjugate gradients to a relative residual.
struct PDYN_API ConstraintFeedback {
  double ks = 0.0;           ///< 1/s^2: pulls a drifted C back to zero
  double kd = 0.0;           ///< 1/s: damps Cdot
  double tolerance = 1e-12;  ///< relative residual |r| / |rhs| at which CG stops
  Index max_iterations = 0;  ///< CG's limit; 0 = 10 x rows + 100
};

class PDYN_API System {
 public:
  System() = default;
  System(const System&) = delete;
  System& operator=(const System&) = delete;

  // ---- Witkin's solver interface ----

  /// Number of particles N.
  Index size() const noexcept { return static_cast<Index>(mass_.size()); }
  /// Dimension of the phase-space state: 6N.
  Index dimension() const noexcept { return 6 * size(); }
  /// The state itself, [x | v] (6N), writable in place: a solver may assign
  /// a stage state to it directly instead of calling set_state.
  Eigen::Map<Eigen::VectorXd> state() noexcept {
    ++version_;
    return {state_.data(), state_.size()};
  }
  Eigen::Map<const Eigen::VectorXd> state() const noexcept {
    return {state_.data(), state_.size()};
  }
  /// Copies the state into `y` (size 6N).
  void get_state(Eigen::Ref<Eigen::VectorXd> y) const;
  /// Copies `y` (size 6N) into the state.
  void set_state(const Eigen::Ref<const Eigen::VectorXd>& y);
  /// Simulated time, s.
  double time() const noexcept { return time_; }
  void set_time(double t) noexcept { time_ = t; }
  /// Derivative evaluation at the current state and time: writes
  /// dy/dt = [v | f/m] (6N) into `dydt`. Fixed particles get zero. Does not
  /// allocate once the system is assembled.
  void derivative(Eigen::Ref<Eigen::VectorXd> dydt);

  /// Since 0.10.0: what a solver does to a chunk of particles right after
  /// derivative(dydt, then) has written their entries of dydt, while those
  /// are in cache: `call(context, begin, end)` for particles [begin, end),
  /// whose entries are dydt's [3 begin, 3 end) and [3N + 3 begin,
  /// 3N + 3 end). It may read and write those entries and the same entries
  /// of the state, nothing else: chunks run on the host's threads, in any
  /// order. A fused solver step saves a pass over dydt (rk4: the stage's
  /// sum and next state made from each chunk's slope, plugins/solvers/rk4).
  struct DerivativeChunk {
    void (*call)(void* context, Index begin, Index end) = nullptr;
    void* context = nullptr;
  };
  /// Since 0.10.0: derivative(dydt), then `then` on each chunk of particles
  /// once its entries are written (DerivativeChunk). The values written are
  /// derivative(dydt)'s, bit for bit.
  void derivative(Eigen::Ref<Eigen::VectorXd> dydt, DerivativeChunk then);
  /// derivative(dydt, then) with a callable `f(begin, end)`.
  template <class F>
  void derivative_then(Eigen::Ref<Eigen::VectorXd> dydt, F&& f) {
    using Fn = std::remove_reference_t<F>;  // may be const: called as it was given
    auto call = [](void* c, Index b, Index e) { (*static_cast<Fn*>(c))(b, e); };
    void* context = const_cast<void*>(static_cast<const volatile void*>(std::addressof(f)));
    derivative(dydt, DerivativeChunk{call, context});
  }

  // ---- split views, for symplectic and implicit solvers ----

  /// Positions, m (3 x N view of the first half of state()).
  Eigen::Map<Matrix3X> positions() noexcept {
    ++version_;
    return {state_.data(), 3, size()};
  }
  Eigen::Map<const Matrix3X> positions() const noexcept { return {state_.data(), 3, size()}; }
  /// Velocities, m/s (3 x N view of the second half of state()).
  Eigen::Map<Matrix3X> velocities() noexcept {
    ++version_;
    return {state_.data() + 3 * size(), 3, size()};
  }
  Eigen::Map<const Matrix3X> velocities() const noexcept {
    return {state_.data() + 3 * size(), 3, size()};
  }
  /// Evaluates forces at the current state and returns the accelerations
  /// f/m (m/s^2, 3 x N; zero for fixed particles). The reference stays valid
  /// until the next call.
  const Matrix3X& compute_accelerations();
  /// Forces (N) of the last derivative or acceleration evaluation.
  const Matrix3X& forces() const noexcept { return force_; }
  /// Since ABI 6: a count of the calls that may have changed what the forces
  /// see, so that a solver can tell whether forces it evaluated are still
  /// valid. Every call of the non-const state(), positions() or velocities()
  /// (the writable views) and of set_state, set_particles, add_particle,
  /// set_fixed, add_force, remove_force, add_collider, remove_collider,
  /// set_domain, set_radii, set_types and touch increases it; so do a
  /// collider response and a wrap that moved a particle. set_time does not:
  /// a solver compares times itself. The pattern (plugins/solvers/verlet):
  /// read it at the end of step() after the solver's own last write, and
  /// reuse the forces in the next step() only if it has not changed when
  /// that step starts.
  std::uint64_t state_version() const noexcept { return version_; }
  /// Marks the state as changed: for a host that writes through a writable
  /// view it obtained earlier (a Map kept from state(), a NumPy array), or
  /// that changes a force's parameters between steps (pdyn/targets.hpp).
  void touch() noexcept { ++version_; }
  /// Force evaluations (derivative or compute_accelerations calls) since the
  /// system was assembled: the cost measure a run summary reports.
  std::uint64_t force_evaluations() const noexcept { return evaluations_; }

  // ---- particle properties and observables ----

  const Eigen::VectorXd& masses() const noexcept { return mass_; }
  const std::vector<std::uint8_t>& fixed() const noexcept { return fixed_; }
  /// 1/m per particle, 1/kg; 0 for a fixed particle, which no force or
  /// constraint impulse moves. Kept in step with masses() and fixed().
  const Eigen::VectorXd& inverse_masses() const noexcept { return inv_mass_; }
  const Domain& domain() const noexcept { return domain_; }
  /// Since 0.10.0, for a solver that controls the pressure (a barostat):
  /// moves the bounds of the periodic axes to `min` and `max` (m), keeping
  /// which axes are periodic and the open axes' bounds. The solver moves the
  /// positions itself, scaled with the box as its method says. Increases
  /// state_version(); pair forces' neighbor lists rebuild for the new box.
  /// Throws Error unless min < max, both finite, along every periodic axis.
  void resize_box(const Vec3& min, const Vec3& max);
  const std::vector<double>& radii() const noexcept { return radius_; }
  const std::vector<std::int32_t>& types() const noexcept { return type_; }
  /// Per particle, how many box lengths it has been wrapped by along each
  /// axis: the unwrapped position is x + images * L (0 along open axes).
  const std::vector<std::array<std::int32_t, 3>>& images() const noexcept { return images_; }
  /// Read-only view of the current state, as forces see it.
  ParticleView view() const noexcept;
  /// Kinetic energy sum(m v^2 / 2), J.
  double kinetic_energy() const;
  /// Sum of the potential energies (J) that force objects report.
  double potential_energy() const;

  struct ForceEntry {
    std::shared_ptr<Force> force;
    std::string label;
  };
  struct ColliderEntry {
    std::shared_ptr<Collider> collider;
    std::string label;
  };
  const std::vector<ForceEntry>& force_objects() const noexcept { return forces_; }
  const std::vector<ColliderEntry>& collider_objects() const noexcept { return colliders_; }

  // ---- constraints (since ABI 7, pdyn/constraint.hpp) ----

  struct ConstraintEntry {
    std::shared_ptr<Constraint> constraint;
    std::string label;
  };
  const std::vector<ConstraintEntry>& constraint_objects() const noexcept { return constraints_; }
  /// Total number of constraint rows (scalar constraints).
  Index constraint_rows() const noexcept;
  /// Whether derivative evaluations add Witkin's constraint force (on
  /// whenever the system holds a constraint, unless a solver that enforces
  /// constraints itself turned it off).
  bool constraint_force_enabled() const noexcept { return constraint_force_on_; }
  const ConstraintFeedback& constraint_feedback() const noexcept { return feedback_; }
  /// The largest |C_r| over every row at the current state (0 without
  /// constraints), in each row's own unit: what a run reports as drift.
  double constraint_error() const;
  /// Since 0.9.0: evaluates every constraint object at the current state and
  /// time and returns their rows gathered (pdyn/constraint.hpp), for a solver
  /// that enforces them itself (pdyn/constraint_solver.hpp). The reference
  /// stays valid, and its values unchanged, until the next evaluation.
  /// Throws PluginRuntimeError naming the object whose output is wrong.
  const ConstraintRows& evaluate_constraint_rows() const;
  /// Since 0.10.0: the virial (J) of Witkin's constraint force J^T lambda of
  /// the last derivative evaluation, with J and lambda of that evaluation
  /// and the current positions (pdyn/thermo.hpp, constraint_force_virial):
  /// the constraint part of the pressure when the kernel enforces the
  /// constraints. 0 without constraint rows; NaN before the first
  /// evaluation with the constraint force on.
  double constraint_force_virial() const;

 private:
  // ---- assembly and the step's bookkeeping: the host's, not a plugin's ----
  // Called through pdyn::SystemAssembly (pdyn/host/assembly.hpp, which
  // documents them). Private since 0.6.0 so that a solver, which gets a
  // System&, sees Witkin's solver interface and not the host's mutators; the
  // symbols are unchanged, so binaries built before keep loading.
  friend class SystemAssembly;

  /// Replaces all particles. `x`, `v` are 3 x N (m, m/s), `mass` N (kg, > 0),
  /// `fixed` N flags; a fixed particle's velocity is set to zero.
  void set_particles(const Matrix3X& x, const Matrix3X& v, const Eigen::VectorXd& mass,
                     const std::vector<std::uint8_t>& fixed);
  /// Appends one particle and returns its index. O(N): for interactive use.
  Index add_particle(const Vec3& x, const Vec3& v, double mass, bool fixed = false);
  /// Nails (or frees) particle i; nailing zeroes its velocity.
  void set_fixed(Index i, bool fixed);
  /// Adds a force object; `label` names it in messages (e.g. "spring (scene.yaml:12)").
  void add_force(std::shared_ptr<Force> force, std::string label);
  /// Removes a force object added with add_force (an interactive host's
  /// mouse spring, when the button is released); false if it is not held.
  bool remove_force(const Force* force);
  /// Adds a collider; `label` names it in messages.
  void add_collider(std::shared_ptr<Collider> collider, std::string label);
  /// Removes a collider added with add_collider; false if it is not held.
  bool remove_collider(const Collider* collider);
  /// Sets the simulation box (default: open space). Throws Error unless
  /// min < max, both finite, along every periodic axis.
  void set_domain(const Domain& domain);
  /// Sets every particle's radius, m (N values, each finite and >= 0), or
  /// none (empty). set_particles clears them; add_particle gives the new
  /// particle radius 0.
  void set_radii(std::vector<double> radius);
  /// Sets every particle's type (N values, each >= 0), or none (empty: all
  /// of type 0). set_particles clears them; add_particle gives type 0.
  void set_types(std::vector<std::int32_t> type);

  /// Restores the image counts (a checkpoint's), N entries.
  void set_images(std::vector<std::array<std::int32_t, 3>> images);
  /// Brings every particle back into the box along periodic axes (counting
  /// the box lengths in images()); nothing without a periodic axis. The
  /// Stepper calls it after each accepted step. Returns true if it moved a
  /// particle. A move changes state_version() unless every force object is
  /// periodic-invariant (pdyn/periodic_invariant.hpp): forces evaluated
  /// before the wrap then stay valid, to rounding.
  bool wrap_positions();
  /// As wrap_positions(), and each moved particle's position is written to
  /// `mirror` as well, a state vector (dimension()) that equals state()
  /// before the call: the Stepper's last good state follows the wrap
  /// without a copy of the whole state (since 0.10).
  bool wrap_positions(double* mirror);
  /// Runs every collider's collision response; the host's Stepper calls it
  /// (through pdyn::SystemAssembly) after each accepted step of length `h`.
  void respond_to_collisions(double h);
  /// Adds a constraint object; `label` names it in messages. Throws Error if
  /// its pattern names a particle outside 0 .. N-1 or is malformed.
  void add_constraint(std::shared_ptr<Constraint> constraint, std::string label);
  /// The same with the rows' compliance (>= 0, the row's unit per N), which
  /// a solver that honours it reads from ConstraintRows (since 0.9.0).
  void add_constraint(std::shared_ptr<Constraint> constraint, std::string label, double compliance);
  /// Witkin's feedback terms and CG settings (checked by the host).
  void set_constraint_feedback(const ConstraintFeedback& feedback);
  /// Turns the constraint force on or off (a solver that projects onto the
  /// constraints itself does not want it).
  void enable_constraint_force(bool on) noexcept { constraint_force_on_ = on; }

  /// When on, every force evaluation checks each force object's output and
  /// throws an error naming the first object that produced a NaN or infinite
  /// force. Off by default (it costs a pass over f per force object); the
  /// runner turns it on to replay a step that blew up.
  void set_finite_checks(bool on) noexcept { finite_checks_ = on; }

  // A force's optional interfaces (pdyn/local_force.hpp), found when it is
  // added.
  struct LocalEntry {
    LocalForce* local = nullptr;
    LinearLocalForce* linear = nullptr;
  };
  // At most this many local forces are evaluated by their laws in the gather.
  static constexpr int kMaxLinearLaws = 4;

  std::size_t evaluate_forces();
  void evaluate_constraints() const;
  void add_local_forces(std::size_t first, Index begin, Index end);
  int linear_laws(std::size_t first, LinearLocalLaw* laws) const;
  template <class Out, class Then>
  void gather(std::size_t first_local, Out out, Then then);
  void update_inverse_mass();

  Eigen::VectorXd state_;     // [x | v], 6N
  Eigen::VectorXd mass_;      // N
  Eigen::VectorXd inv_mass_;  // N, zero for fixed particles: gathers f/m with no branch
  std::vector<std::uint8_t> fixed_;
  std::vector<Index> fixed_ids_;  // indices of fixed particles
  Matrix3X force_;                // force accumulators, 3 x N
  Matrix3X accel_;                // f/m for compute_accelerations()
  double time_ = 0.0;
  bool finite_checks_ = false;
  std::vector<ForceEntry> forces_;
  std::vector<LocalEntry> local_;  // per force (the same size as a vector of pointers)
  std::vector<ColliderEntry> colliders_;
  std::uint64_t evaluations_ = 0;
  std::uint64_t version_ = 0;  // state_version()
  Domain domain_;
  std::vector<double> radius_;                       // N or empty
  std::vector<std::int32_t> type_;                   // N or empty
  std::vector<std::array<std::int32_t, 3>> images_;  // N
  // Since ABI 7, after every member a plugin compiled against ABI 6 may read
  // inline, so those keep their offsets.
  std::vector<ConstraintEntry> constraints_;
  std::shared_ptr<ConstraintForce> constraint_force_;  // assembled rows and CG work space
  ConstraintFeedback feedback_;
  bool constraint_force_on_ = true;
};

}  // namespace pdyn
