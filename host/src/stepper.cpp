// One step: solver, collision response, non-finite check, rollback (see
// pdyn/host/stepper.hpp).
#include "pdyn/host/stepper.hpp"

#ifdef __SSE2__
#include <emmintrin.h>
#endif

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <cstring>
#include <utility>

#include "pdyn/constraint_solver.hpp"
#include "pdyn/error.hpp"
#include "pdyn/host/assembly.hpp"
#include "pdyn/kernel/plugin_call.hpp"
#include "pdyn/parallel.hpp"
#include "pdyn/solver.hpp"
#include "pdyn/step_aware.hpp"
#include "pdyn/system.hpp"

namespace pdyn {

namespace {

// Whether m doubles are all finite: x * 0 is 0 for a finite x and NaN for an
// infinity or a NaN, so the products' sum is 0 or NaN. Eigen's allFinite()
// took longer than a copy (its early exit keeps the loop scalar).
bool all_finite(const double* from, Index m) {
#ifdef __SSE2__
  const __m128d zero = _mm_setzero_pd();
  __m128d sum0 = zero, sum1 = zero;
  Index k = 0;
  for (; k + 3 < m; k += 4) {
    sum0 = _mm_add_pd(sum0, _mm_mul_pd(_mm_loadu_pd(from + k), zero));
    sum1 = _mm_add_pd(sum1, _mm_mul_pd(_mm_loadu_pd(from + k + 2), zero));
  }
  double scalar = 0.0;
  for (; k < m; ++k) scalar += from[k] * 0.0;
  const __m128d sum = _mm_add_pd(sum0, sum1);
  return _mm_movemask_pd(_mm_cmpunord_pd(sum, sum)) == 0 && scalar == 0.0;
#else
  double sum = 0.0;
  for (Index k = 0; k < m; ++k) sum += from[k] * 0.0;
  return sum == 0.0;
#endif
}

// Copies m doubles and tells whether all are finite, in one loop: the copy
// is the last good state, read only if a later step fails, so it is written
// with streaming stores where the CPU has them (it should not displace the
// working set from the caches, nor be read from memory first, as a plain
// store reads each cache line before writing it), and x * 0 is 0 for a
// finite x and NaN for an infinity or a NaN, so the products' sum is 0 or
// NaN. Eigen's allFinite() took longer than the copy (8% of a velocity
// Verlet step of the 1000 x 1000 cloth against 6%: its early exit keeps the
// loop scalar).
bool copy_finite(const double* from, double* to, Index m) {
#ifdef __SSE2__
  Index k = 0;
  double scalar = 0.0;
  if (m > 0 && (reinterpret_cast<std::uintptr_t>(to) & 15) != 0) {
    to[0] = from[0];
    scalar += from[0] * 0.0;
    k = 1;
  }
  const __m128d zero = _mm_setzero_pd();
  __m128d sum = zero;
  for (; k + 1 < m; k += 2) {
    const __m128d x = _mm_loadu_pd(from + k);
    sum = _mm_add_pd(sum, _mm_mul_pd(x, zero));
    _mm_stream_pd(to + k, x);
  }
  for (; k < m; ++k) {
    to[k] = from[k];
    scalar += from[k] * 0.0;
  }
  return _mm_movemask_pd(_mm_cmpunord_pd(sum, sum)) == 0 && scalar == 0.0;
#else
  std::memcpy(to, from, static_cast<std::size_t>(m) * sizeof(double));
  return all_finite(from, m);
#endif
}

// Copies `from` into `to` and tells whether every value is finite, in one
// pass over memory, split over the threads. This is the only pass the
// Stepper makes over a good step's state; a separate check and copy cost
// two (issue 17, item 1).
bool copy_if_finite(const Eigen::Ref<const Eigen::VectorXd>& from, Eigen::VectorXd& to) {
  to.resize(from.size());  // allocates on the first step only
  std::atomic<bool> finite{true};
  parallel_state_chunks(from.size(), from.size(), [&](Index b, Index e) {
    const bool ok = copy_finite(from.data() + b, to.data() + b, e - b);
#ifdef __SSE2__
    _mm_sfence();  // the streaming stores are weakly ordered: done before the barrier
#endif
    if (!ok) finite.store(false, std::memory_order_relaxed);
  });
  return finite.load(std::memory_order_relaxed);
}

// Copies m doubles into the last good state, which is read only if a later
// step fails: with streaming stores where the CPU has them, so that it
// neither displaces the working set from the caches nor is read from memory
// first (a plain store reads each cache line before writing it).
void stream_copy(const double* from, double* to, Index m) {
#ifdef __SSE2__
  Index k = 0;
  if (m > 0 && (reinterpret_cast<std::uintptr_t>(to) & 15) != 0) {
    to[0] = from[0];
    k = 1;
  }
  for (; k + 1 < m; k += 2) _mm_stream_pd(to + k, _mm_loadu_pd(from + k));
  for (; k < m; ++k) to[k] = from[k];
  _mm_sfence();  // the streaming stores are weakly ordered: done before the barrier
#else
  std::memcpy(to, from, static_cast<std::size_t>(m) * sizeof(double));
#endif
}

// Keeps a step's end state as the last good one if every value is finite,
// in two passes split over the threads: a check, then the copy over the
// previous last good state. A single buffer cannot be written before the
// check has passed, since a failed step must find the state it started
// from; copy_if_finite's one pass needs a second buffer. The Stepper takes
// this path for states above kSecondBufferBytes, where the second buffer
// would be 48 bytes per particle of the peak (issue 32, item 4) and the
// extra read about 1% of a step.
bool keep_if_finite(const Eigen::Ref<const Eigen::VectorXd>& from, Eigen::VectorXd& to) {
  std::atomic<bool> finite{true};
  parallel_state_chunks(from.size(), from.size(), [&](Index b, Index e) {
    if (!all_finite(from.data() + b, e - b)) finite.store(false, std::memory_order_relaxed);
  });
  if (!finite.load(std::memory_order_relaxed)) return false;
  to.resize(from.size());  // allocates on the first step only
  parallel_state_chunks(from.size(), from.size(), [&](Index b, Index e) {
    stream_copy(from.data() + b, to.data() + b, e - b);
  });
  return true;
}

// The largest state that gets a second buffer, so that a step's end state
// is checked and kept in one pass (copy_if_finite, then a swap): 8 MB, a
// state of 174,762 particles. A small step is short, and a second pass over
// its state measured several per cent of it (32 x 32 cloth).
constexpr std::size_t kSecondBufferBytes = std::size_t{8} << 20;

bool second_buffer(Index dimension) {
  return static_cast<std::size_t>(dimension) * sizeof(double) <= kSecondBufferBytes;
}

// Index of the first particle whose position or velocity is not finite, or -1.
Index first_non_finite(const System& sys) {
  if (sys.state().allFinite()) return -1;
  const auto x = sys.positions();
  const auto v = sys.velocities();
  for (Index i = 0; i < sys.size(); ++i) {
    if (!x.col(i).allFinite() || !v.col(i).allFinite()) return i;
  }
  return -1;
}

// Tells the forces that hold a value over a step (pdyn/step_aware.hpp)
// which step comes: its start time and length. Again for a replayed step, so
// that the replay draws what the step drew.
void begin_step(System& sys, double h) {
  for (const auto& entry : sys.force_objects()) {
    if (auto* aware = dynamic_cast<StepAware*>(entry.force.get())) {
      const crash::CallScope call(entry.label, "begin_step");
      aware->begin_step(sys.time(), h);
    }
  }
}

}  // namespace

// The state buffers are allocated and their pages touched here, before the
// first step: at 10^6 particles that is 48 MB of page faults a timed loop
// would otherwise pay in its first step.
Stepper::Stepper(System& sys, Solver& solver, const std::string& solver_label,
                 const RebuildSchedule& neighbors)
    : sys_(sys), solver_(solver), label_(&solver_label), neighbors_(neighbors) {
  // A solver that projects onto the constraints itself (RATTLE, XPBD) must
  // not see Witkin's constraint force in its force evaluations as well.
  const auto* projecting = dynamic_cast<const ConstraintSolver*>(&solver);
  SystemAssembly(sys).enable_constraint_force(projecting == nullptr ||
                                              !projecting->enforces_constraints());
  previous_.setZero(sys.dimension());
  if (second_buffer(sys.dimension())) next_.setZero(sys.dimension());
}

// The solver's time after step() is overwritten with `t_end` itself: a run's
// step k ends at k dt exactly, with no round-off carried from step to step,
// and a resumed run computes the same times.
std::optional<double> Stepper::step_to(double t_end) {
  return guarded([&] {
    const double h = t_end - sys_.time();
    begin_step(sys_, h);
    if (neighbors_ != RebuildSchedule{}) {
      begin_neighbor_step(std::as_const(sys_).positions().data(), sys_.time(), neighbors_);
    }
    const crash::CallScope call(*label_, "step");
    solver_.step(sys_, h);
    sys_.set_time(t_end);
    return h;
  });
}

std::optional<double> Stepper::advance(double t_stop, double h_hint) {
  return guarded([&] {
    const crash::CallScope call(*label_, "advance");
    return solver_.advance(sys_, t_stop, h_hint);
  });
}

std::optional<double> Stepper::step(double dt) {
  const double t = sys_.time();
  return solver_.adaptive() ? advance(t + dt, dt) : step_to(t + dt);
}

// `take` is a template parameter, not a std::function: converting the step
// lambda to one would allocate on every step.
template <class Take>
std::optional<double> Stepper::guarded(const Take& take) {
  // The last good state is normally the one the previous step left, which
  // keep_if_finite kept; it is copied here only if someone wrote the state
  // since (state_version), or on the first step.
  if (sys_.state_version() != version_ || previous_.size() != sys_.dimension()) {
    previous_ = std::as_const(sys_).state();  // allocates on the first step only
  }
  t_previous_ = sys_.time();
  fault_ = StepFault{};
  fault_.start_time = t_previous_;
  double h = 0.0;
  try {
    h = take();
    SystemAssembly(sys_).respond_to_collisions(h);
  } catch (const PluginRuntimeError& e) {
    fault_.kind = StepFault::Kind::PluginThrew;
    fault_.label = e.label();
    fault_.what = e.what();
    return fail();
  } catch (const std::exception& e) {
    // The solver failed on its own account, or so it seems: it may have
    // called a force directly (finite-difference Jacobians) that threw, or
    // given up on a NaN a force fed it. Replay the step to find out.
    fault_.solver_message = e.what();
    if (replay(take, false)) {
      fault_.kind = StepFault::Kind::PluginThrew;
      fault_.found_by_replay = true;
    } else if (replay(take, true)) {
      fault_.kind = StepFault::Kind::NonFiniteForce;
    } else {
      fault_.kind = StepFault::Kind::SolverThrew;
      fault_.label = *label_;
      fault_.what = e.what();
      fault_.solver_message.clear();
      return fail();
    }
    fault_.label = replayed_.label;
    fault_.what = replayed_.what;
    return fail();
  } catch (...) {
    fault_.kind = StepFault::Kind::SolverThrew;
    fault_.label = *label_;
    fault_.non_standard = true;
    return fail();
  }
  const bool one_pass = second_buffer(sys_.dimension());
  if (!(one_pass ? copy_if_finite(std::as_const(sys_).state(), next_)
                 : keep_if_finite(std::as_const(sys_).state(), previous_))) {
    const Index bad = first_non_finite(sys_);
    fault_.kind = StepFault::Kind::NonFiniteState;
    fault_.particle = bad;
    fault_.position = sys_.positions().col(bad);
    fault_.end_time = sys_.time();
    if (replay(take, true)) {
      fault_.label = replayed_.label;
      fault_.what = replayed_.what;
    }
    return fail();
  }
  if (one_pass) previous_.swap(next_);  // the next step's last good state
  // Only after a good step: a failed one leaves the images alone. previous_
  // equals the state here, and the wrap moves its positions with the
  // state's (the image counts are the System's): the next step need not
  // copy the state again, though some particle crosses a face in most steps
  // of a periodic liquid (a 32,000-bead melt: 1.5 MB a step saved).
  SystemAssembly(sys_).wrap_positions(previous_.data());
  version_ = sys_.state_version();
  return h;
}

// Replays the failed step from the last good state, with finite checks on or
// off; true if a plugin object threw (PluginRuntimeError, which names it),
// recorded in replayed_. With finite checks on, that names the force object
// that first produced a NaN or infinity. The state is left as the replay
// leaves it: fail() restores the last good one.
template <class Take>
bool Stepper::replay(const Take& take, bool finite_checks) {
  sys_.state() = previous_;
  sys_.set_time(t_previous_);
  SystemAssembly(sys_).set_finite_checks(finite_checks);
  bool found = false;
  try {
    take();
  } catch (const PluginRuntimeError& e) {
    replayed_.label = e.label();
    replayed_.what = e.what();
    found = true;
  } catch (...) {
  }
  SystemAssembly(sys_).set_finite_checks(false);
  return found;
}

std::nullopt_t Stepper::fail() {
  sys_.state() = previous_;
  sys_.set_time(t_previous_);
  return std::nullopt;
}

}  // namespace pdyn
