// pdyn/force_reuse.hpp — one force evaluation per step for velocity-Verlet
// solvers: the end-of-step accelerations a1 kept as the next step's a0.
//
// A step of velocity Verlet (plugins/solvers/verlet) or of a method built on
// it (plugins/solvers/nose_hoover) evaluates the accelerations twice: a0 at
// its start, a1 at the end positions x1. The next step's a0 is evaluated at
// those same positions, so a1 can stand in for it, as LAMMPS's velocity
// Verlet does, but only when that gives the same bits as evaluating a0
// afresh:
//   - every force declares that it does not read velocities
//     (Force::dependence(); the default claims it does), and there is no
//     collider (contact forces read velocities): a1 was evaluated at other
//     velocities (v_half, or a predictor) than the next step starts with;
//   - nothing but the kernel's step wrote the state since the step ended
//     (System::state_version(): a collider's response, a checkpoint
//     restored, an interactive edit, a force added or removed all change
//     it, and so does a wrap into a periodic box that moved a particle
//     unless every force is periodic-invariant, pdyn/periodic_invariant.hpp:
//     then a1, evaluated before the wrap, equals a fresh a0 to rounding);
//   - no force evaluation has happened since, so the System still holds a1
//     (System::force_evaluations(); compute_accelerations() returns a
//     reference into the System that the next evaluation overwrites);
//   - the system is the same object, of the same size (a host may hand a
//     solver another System, or add particles);
//   - the time is the one a1 was evaluated at, exactly, if any force reads
//     the time.
// Otherwise the solver evaluates a0 at the start of the step.
//
// The pattern, in a solver's step():
//
//   const pdyn::ForceReuse::Needs needs = pdyn::ForceReuse::needs(sys);
//   const pdyn::Matrix3X* kept = reuse_.kept(sys, needs);  // before any writable view
//   auto x = sys.positions();
//   auto v = sys.velocities();
//   const pdyn::Matrix3X& a0 = kept != nullptr ? *kept : sys.compute_accelerations();
//   ... v += h/2 a0, x += h v, set_time(t0 + h) ...
//   const pdyn::Matrix3X& a1 = sys.compute_accelerations();
//   ... v += h/2 a1, the step's last write to the state ...
//   reuse_.keep(sys, a1, needs);
//
// kept() must be called before the step takes its writable views (each call
// of positions(), velocities() or state() counts as a write), keep() after
// its last write. Writes through views taken earlier in the same step do
// not count: they are the step's own.
//
// Checkpoints. A run resumed from a checkpoint must continue with the same
// bits as the uninterrupted run, which reuses a1 where the conditions hold.
// After a wrap into a periodic box a1 (evaluated before the wrap) and a
// fresh a0 differ in the last bits, so the kept a1 travels in the
// checkpoint: a solver that uses a ForceReuse implements ForceReuseHolder,
// and the host stores current() with the state and gives it back through
// restore() after the resumed run's state is set.
#pragma once

#include <cstdint>

#include "pdyn/export.hpp"
#include "pdyn/system.hpp"
#include "pdyn/types.hpp"

namespace pdyn {

class ForceReuse {
 public:
  /// What the accelerations of a System read besides the positions.
  struct Needs {
    bool velocity = false;  ///< some force or a collider reads velocities
    bool time = false;      ///< some force reads the time
  };

  /// The needs of `sys`'s force objects (Force::dependence()), colliders
  /// (every collider's contact force reads velocities) and constraint force
  /// (its bias Jdot v reads velocities; a moving constraint, the time).
  static Needs needs(const System& sys) {
    Needs n;
    n.velocity = !sys.collider_objects().empty();
    if (sys.constraint_force_enabled() && sys.constraint_rows() > 0) n.velocity = n.time = true;
    for (const auto& entry : sys.force_objects()) {
      const StateDependence d = entry.force->dependence();
      n.velocity = n.velocity || d.velocity;
      n.time = n.time || d.time;
    }
    return n;
  }

  /// At the start of a step, before any writable view of the state is
  /// taken: the a1 that keep() recorded if it may stand in for this step's
  /// a0 (the conditions at the top of this file), else nullptr.
  const Matrix3X* kept(const System& sys, const Needs& needs) const {
    if (a1_ == nullptr || &sys != system_ || a1_->cols() != sys.size()) return nullptr;
    if (sys.state_version() != version_ || sys.force_evaluations() != evaluations_) return nullptr;
    if (needs.time && sys.time() != t1_) return nullptr;
    return a1_;
  }

  /// For a host's checkpoint: the kept a1 if the next step on `sys` would
  /// reuse it now, else nullptr (what kept() says, whatever the time).
  const Matrix3X* current(const System& sys) const {
    if (a1_ == nullptr || &sys != system_ || a1_->cols() != sys.size()) return nullptr;
    if (sys.state_version() != version_ || sys.force_evaluations() != evaluations_) return nullptr;
    return a1_;
  }

  /// For a host resuming from a checkpoint, after the System's state, time
  /// and images are set: `a1` (what current() gave when the checkpoint was
  /// taken, copied) stands in for the next a0 on `sys` unless something
  /// writes or evaluates first. A host's set-up may give the accelerations
  /// it evaluated at the current state too. Ignored when some force or
  /// collider reads velocities.
  void restore(const System& sys, const Matrix3X& a1) { restore(sys, a1, needs(sys)); }

  /// As restore(sys, a1), with `needs` as the solver takes them for kept()
  /// and keep() (verlet's velocity_forces: half_step reuses a1 whatever the
  /// forces read, and says so with needs.velocity false).
  void restore(const System& sys, const Matrix3X& a1, const Needs& needs) {
    if (needs.velocity) {  // a1 was evaluated at other velocities
      a1_ = nullptr;
      return;
    }
    restored_ = a1;
    a1_ = &restored_;
    system_ = &sys;
    t1_ = sys.time();
    evaluations_ = sys.force_evaluations();
    version_ = sys.state_version();
  }

  /// At the end of a step, after its last write to the state: records `a1`
  /// (the reference compute_accelerations() returned) and what the System
  /// looks like now. With velocity-dependent needs nothing is kept.
  void keep(const System& sys, const Matrix3X& a1, const Needs& needs) {
    a1_ = needs.velocity ? nullptr : &a1;
    system_ = &sys;
    t1_ = sys.time();
    evaluations_ = sys.force_evaluations();
    version_ = sys.state_version();
  }

 private:
  const Matrix3X* a1_ = nullptr;  // the System's a1 (or restored_), or nullptr
  Matrix3X restored_;             // a checkpoint's a1, until the next keep()
  const System* system_ = nullptr;
  double t1_ = 0.0;  // the time a1 was evaluated at
  std::uint64_t evaluations_ = 0;
  std::uint64_t version_ = 0;
};

/// Optional interface of a solver that reuses its end-of-step forces
/// (verlet, nose_hoover): the host carries the kept accelerations through
/// checkpoints (see the top of this file). Found with dynamic_cast on the
/// Solver; a solver without it resumes with a fresh a0.
class PDYN_API ForceReuseHolder {
 public:
  virtual ~ForceReuseHolder();  // defined in the kernel: one type_info for every library
  /// The accelerations (m/s^2) the next step on `sys` would reuse, or nullptr
  /// (ForceReuse::current()).
  virtual const Matrix3X* kept_accelerations(const System& sys) const = 0;
  /// After a resume set `sys`'s state: `a1`, what kept_accelerations() gave
  /// for the checkpoint, stands in for the next a0 (ForceReuse::restore()).
  virtual void restore_kept_accelerations(const System& sys, const Matrix3X& a1) = 0;
};

}  // namespace pdyn
