// The step loop: Witkin's simulation loop plus output, checkpoints, signals
// and fault handling.
#include "pdyn/host/runner.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstring>
#include <exception>
#include <numeric>
#include <ostream>
#include <pdyn/parallel.hpp>
#include <tuple>
#include <utility>

#include "output.hpp"
#include "pdyn/force_reuse.hpp"
#include "pdyn/host/assembly.hpp"
#include "pdyn/host/crash_report.hpp"
#include "pdyn/host/stepper.hpp"
#include "pdyn/host/threads.hpp"
#include "pdyn/step_aware.hpp"
#include "pdyn/text.hpp"

namespace pdyn {

namespace fs = std::filesystem;

namespace {

std::string blow_up_message(const StepFault& f, std::int64_t step, const std::string& culprit,
                            std::string_view kept) {
  return fmt::format(
      "the state became non-finite at step {} (t = {:.17g} s): particle {} has position "
      "[{}, {}, {}]{}; the last good state (step {}) {}. Try a smaller dt or a more stable "
      "solver.",
      step, f.end_time, f.particle, f.position(0), f.position(1), f.position(2),
      culprit.empty() ? "" : "; " + culprit, step - 1, kept);
}

// " (library PATH)": which file a faulty plugin object came from.
std::string library_of(const Scene& scene, const std::string& label) {
  const auto it = scene.libraries.find(label);
  return it == scene.libraries.end() ? "" : fmt::format(" (library {})", it->second.string());
}

}  // namespace

std::string step_fault_message(const StepFault& f, const Scene& scene, std::int64_t k,
                               std::string_view kept) {
  const std::string solver = fmt::format("{} reported: {}", scene.solver_label, f.solver_message);
  using Kind = StepFault::Kind;
  switch (f.kind) {
    case Kind::PluginThrew:
      if (f.found_by_replay) {
        return fmt::format("plugin {}{} at step {} (found by replaying the step; {})", f.what,
                           library_of(scene, f.label), k, solver);
      }
      return fmt::format("plugin {} at step {}{}", f.what, k, library_of(scene, f.label));
    case Kind::NonFiniteForce:
      return fmt::format(
          "a force produced a non-finite value at step {} (t = {:.17g} s): {}{}; "
          "then {}; the last good state (step {}) {}",
          k, f.start_time, f.what, library_of(scene, f.label), solver, k - 1, kept);
    case Kind::SolverThrew:
      if (f.non_standard) {
        return fmt::format("plugin {}: step threw a non-standard exception at step {}{}", f.label,
                           k, library_of(scene, f.label));
      }
      return fmt::format("plugin {}: step threw at step {}: {}{}", f.label, k, f.what,
                         library_of(scene, f.label));
    case Kind::NonFiniteState:
      break;
  }
  return blow_up_message(f, k,
                         f.label.empty() ? ""
                                         : fmt::format("the first non-finite force came from {}{}",
                                                       f.what, library_of(scene, f.label)),
                         kept);
}

fs::path checkpoint_path(const Scene& scene) {
  if (!scene.output.checkpoint.empty()) return scene.output.checkpoint;
  if (!scene.output.checkpoint_beside.empty()) {
    return fs::path(scene.output.checkpoint_beside).replace_extension(".ckpt");
  }
  return fs::path(scene.file).stem().string() + ".ckpt";
}

// ---------------------------------------------------------------------------
// Signals

namespace {

std::atomic<int> g_signals{0};

extern "C" void on_signal(int) {
  // The first signal asks the loop to stop after the current step; a second
  // one means "now": leave at once, temporary files keep temporary names.
  if (g_signals.fetch_add(1) >= 1) ::_exit(130);
}

class SignalGuard {
 public:
  explicit SignalGuard(bool active) : active_(active) {
    if (!active_) return;
    g_signals = 0;
    struct sigaction sa {};
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, &old_int_);
    sigaction(SIGTERM, &sa, &old_term_);
  }
  ~SignalGuard() {
    if (!active_) return;
    sigaction(SIGINT, &old_int_, nullptr);
    sigaction(SIGTERM, &old_term_, nullptr);
  }
  bool raised() const { return active_ && g_signals.load() > 0; }

 private:
  bool active_;
  struct sigaction old_int_ {
  }, old_term_{};
};

// ---------------------------------------------------------------------------
// Output

class Progress {
 public:
  Progress(std::ostream* out, std::int64_t total, double end_time)
      : out_(out), total_(total), end_time_(end_time), start_(Clock::now()), last_(start_) {}
  void update(std::int64_t step, double t, bool force = false) {
    if (!out_) return;
    const auto now = Clock::now();
    if (!force && now - last_ < std::chrono::milliseconds(100)) return;
    last_ = now;
    const double elapsed = std::chrono::duration<double>(now - start_).count();
    const double frac = end_time_ > 0 ? std::min(1.0, t / end_time_) : 1.0;
    const double rate = elapsed > 0 ? static_cast<double>(step - first_) / elapsed : 0.0;
    const double eta = frac > 0 ? elapsed * (1 - frac) / frac : 0.0;
    constexpr int kWidth = 30;
    const int filled = static_cast<int>(frac * kWidth);
    *out_ << fmt::format(
                 "\r[{:<{}}] {:>3.0f}%  step {}/{}  t = {:.4g}/{:.4g} s  {:.0f} steps/s  "
                 "ETA {:.1f} s ",
                 std::string(static_cast<std::size_t>(filled), '#'), kWidth, 100 * frac, step,
                 total_, t, end_time_, rate, eta)
          << std::flush;
  }
  void start_at(std::int64_t step) { first_ = step; }
  void finish() {
    if (out_) *out_ << "\n" << std::flush;
  }

 private:
  using Clock = std::chrono::steady_clock;
  std::ostream* out_;
  std::int64_t total_, first_ = 0;
  double end_time_;
  Clock::time_point start_, last_;
};

// ---------------------------------------------------------------------------
// The loops

// The energy check: a run that diverges without ever becoming NaN (explicit
// Euler on a stiff chain reaches 1e293 J) must not pass for a success.
//
// It applies when every force object either reports a potential energy
// that does not depend on time (declared, Force::dependence, or checked
// once, at the start, by evaluating it at the start, middle and end times of
// the run with the state held) or
// declares the `dissipative` trait: then no force drives the system and its
// total energy E = K + U can only be kept or lost, up to the solver's error.
// Colliders only take energy away. The rule: E - E0 > 1e6 S, where
// S = max(|E0|, K0 + sum |U_i|) at the start (if that is 0, as for a
// particle at rest at the potential's zero, the first nonzero K + sum |U_i|
// seen at a check). Checked every kEvery steps and after the last step:
// about one force evaluation per 64 steps, and no allocation.
class EnergyWatch {
 public:
  static constexpr std::int64_t kEvery = 64;
  static constexpr double kFactor = 1e6;

  EnergyWatch(const Scene& scene) : sys_(*scene.system) {
    System& sys = *scene.system;
    const double t0 = sys.time();
    for (const auto& f : sys.force_objects()) {
      const auto traits = scene.force_traits.find(f.label);
      const bool dissipative = traits != scene.force_traits.end() && traits->second.dissipative;
      const auto u0 = f.force->potential_energy(sys.view());
      if (!u0) {
        if (dissipative) continue;
        return;  // a force whose work is not accounted for: no check
      }
      // A potential that changes with time at a fixed state (a moving
      // trap) pumps energy in: a driving force. A force that declares it
      // does not depend on time (Force::dependence) is not asked.
      if (!f.force->dependence().time) continue;
      for (const double t : {0.5 * (t0 + scene.end_time), scene.end_time}) {
        sys.set_time(t);
        const auto u = f.force->potential_energy(sys.view());
        sys.set_time(t0);
        if (!u || std::abs(*u - *u0) > 1e-12 * std::max(1.0, std::abs(*u0))) return;
      }
    }
    const std::array<double, 2> e0 = energy_and_magnitude(sys_, sys_.kinetic_energy());
    e0_ = e0[0];
    scale_ = std::max(std::abs(e0_), e0[1]);
    active_ = std::isfinite(e0_);
  }

  bool active() const { return active_; }
  // Under MPI ranks: the start's energy and magnitude summed over the ranks
  // (RankDriver::end_step), as every later check is, in place of this
  // rank's share that the constructor measured.
  void start_from(const std::array<double, 2>& summed) {
    e0_ = summed[0];
    scale_ = std::max(std::abs(e0_), summed[1]);
    active_ = active_ && std::isfinite(e0_);
  }
  bool due(std::int64_t k, bool last) const {
    return active_ && !tripped_ && (last || k % kEvery == 0);
  }

  // True once when the energy has grown past the bound; `message` then says
  // so. `summed`: the energy and magnitude summed over MPI ranks
  // (RankDriver::end_step), else the system's own.
  bool grew(std::int64_t k, const Scene& scene, std::string& message,
            const std::array<double, 2>* summed = nullptr) {
    const std::array<double, 2> now =
        summed != nullptr ? *summed : energy_and_magnitude(sys_, sys_.kinetic_energy());
    const double e = now[0], magnitude = now[1];
    if (!(scale_ > 0.0)) {  // no scale yet: the first nonzero magnitude is it
      scale_ = magnitude;
      return false;
    }
    if (!(e - e0_ > kFactor * scale_)) return false;
    tripped_ = true;
    message = fmt::format(
        "the total energy grew from {:.6g} J to {:.6g} J by step {} (t = {:.6g} s), more than "
        "{:.0e} times its initial scale of {:.6g} J, with no force driving it: the solver '{}' is "
        "probably unstable at dt = {} s. Try a smaller dt or a stable solver (implicit_euler, "
        "verlet)",
        e0_, e, k, sys_.time(), kFactor, scale_, scene.solver_name, scene.dt);
    if (summed != nullptr) {
      message +=
          " (under MPI ranks the energy at the step is summed over the ranks' subdomains, a pair "
          "across two of them counted on both)";
    }
    return true;
  }

 private:
  const System& sys_;
  bool active_ = false, tripped_ = false;
  double e0_ = 0.0, scale_ = 0.0;
};

// Shared state of one run's loop.
struct Loop {
  Scene& scene;
  Output& out;
  Progress& progress;
  SignalGuard& signals;
  RunResult& result;
  Stepper& stepper;
  std::int64_t next_frame = 1;  // adaptive runs: index m of the next frame, due at m every dt
  // Adaptive runs: a step has shown that the solver interpolates (dense
  // output). Until then each step stops on the next frame time. Carried by
  // checkpoints, since it changes the steps taken.
  bool has_dense = false;
  EnergyWatch* energy = nullptr;
  bool strict = false;
  // Under MPI ranks (RunOptions::ranks): the steps are the ranks', `scene`
  // is rank 0's copy of the whole, current after each gather.
  RankDriver* ranks = nullptr;
  std::array<double, 2> ranks_energy{};  // the ranks' energy and magnitude at the last check
  bool interrupt_seen = false;           // the interrupt as the ranks agreed on it at the last step
  // Whether the run was interrupted: under MPI ranks, as of the last
  // gather, so that a signal that arrives later does not make a stale
  // state the final frame (it stops the next step).
  bool interrupted() const { return ranks != nullptr ? interrupt_seen : signals.raised(); }

  // After step k (`last`: the run's final step): the energy check. Returns
  // false if the run must stop (--strict), like a blow-up, with exit code 4.
  bool energy_ok(std::int64_t k, bool last) {
    if (!energy || !energy->due(k, last)) return true;
    std::string message;
    if (!energy->grew(k, scene, message, ranks != nullptr ? &ranks_energy : nullptr)) return true;
    if (!strict) {
      result.energy_warning = std::move(message);
      return true;
    }
    // The state is finite and is the step's end: written as the final frame.
    result.exit_code = 4;
    result.message = message +
                     " (--strict: stopped here; this state was written as the final "
                     "frame)";
    out.emit_extra(result.steps_done);
    return false;
  }

  // After a frame: false if a writer failed (a full disk). The run stops
  // with exit code 3; the other writers get the current state, a checkpoint
  // records every writer's last complete frame.
  bool writes_ok() {
    std::string failure = out.take_failure();
    if (failure.empty()) return true;
    result.exit_code = 3;
    result.message = std::move(failure);
    out.emit_extra(result.steps_done);
    return false;
  }

  // One step or accepted adaptive step through the Stepper (`take` calls
  // it): returns its length, or nothing if the run must stop (result says
  // why; the Stepper has restored the last good state).
  template <class Take>
  std::optional<double> guarded_step(const Take& take, std::int64_t k) {
    crash::set_step(k);
    if (const auto h = take()) return h;
    const StepFault& f = stepper.fault();
    return stop(f, step_fault_message(f, scene, k, "was written as the final frame"));
  }

  // The Stepper has restored the last good state: written as the final
  // frame unless it already was.
  std::nullopt_t stop(const StepFault& f, std::string message) {
    result.exit_code = f.exit_code();
    result.message = std::move(message);
    // Under MPI ranks the whole scene holds the last gathered state, not
    // the last good one: no final frame (docs/parallel.md).
    if (ranks == nullptr) out.emit_extra(result.steps_done);
    return std::nullopt;
  }

  // Under MPI ranks, after step k (`ok`: it succeeded here): every rank
  // learns whether another failed, and the particles are gathered into the
  // whole scene when a frame, an energy check or a checkpoint needs them,
  // at the end and on an interrupt. False when the run must stop.
  bool ranks_agree(std::int64_t k, bool ok, bool due) {
    if (ranks == nullptr) return ok;
    const bool last = k == scene.steps;
    interrupt_seen = signals.raised();
    const bool need = ok && (due || last || interrupt_seen);
    // The energy check sums the ranks' energies instead of gathering: a
    // whole-scene evaluation on rank 0 alone would hold the others up.
    const bool check = ok && energy != nullptr && energy->due(k, last);
    const int failed = ranks->end_step(scene, need, !ok, check ? &ranks_energy : nullptr);
    if (ok && failed >= 0) {
      result.exit_code = 4;
      result.message = fmt::format(
          "step {} failed on MPI rank {} (that rank's standard error names the plugin object); "
          "under MPI no final frame is written yet",
          k, failed);
      return false;
    }
    return ok;
  }
};

// Fixed steps of dt: step k ends at t0 + k dt, computed rather than
// accumulated so that time carries no round-off drift (and a resumed run
// computes the same times); the last step of a `duration` run is shortened
// to end exactly on it.
void run_fixed(Loop& loop, std::int64_t k0) {
  const Scene& scene = loop.scene;
  const std::int64_t n_steps = scene.steps, every = loop.out.period();
  const std::int64_t ckpt_every = scene.output.checkpoint_every;
  for (std::int64_t k = k0 + 1; k <= n_steps; ++k) {
    const double t_end = k == n_steps ? scene.end_time : static_cast<double>(k) * scene.dt;
    if (loop.ranks != nullptr && !loop.ranks->begin_step()) return;
    const bool ok = loop.guarded_step([&] { return loop.stepper.step_to(t_end); }, k).has_value();
    // A scene without writers has a frame schedule (it shapes adaptive
    // steps) but nothing to write: no gather for it under MPI ranks.
    const bool frame = !scene.output.writers.empty() && every > 0 && k % every == 0;
    const bool due = frame || (ckpt_every > 0 && k % ckpt_every == 0);
    if (!loop.ranks_agree(k, ok, due)) return;
    loop.result.steps_done = k;
    // The final frame is extra unless it falls on the schedule: a longer
    // run resumed from this one's checkpoint does not write it.
    loop.out.new_state();
    if (every > 0 && k % every == 0) loop.out.emit(k);
    if (!loop.writes_ok()) return;
    if (!loop.energy_ok(k, k == n_steps)) return;
    if (ckpt_every > 0 && k % ckpt_every == 0 && k != n_steps) {
      loop.result.checkpoint = loop.out.write_checkpoint_now(k, 0, false);
      if (!loop.writes_ok()) return;
    }
    loop.progress.update(k, t_end);
    if (k == n_steps || loop.interrupted()) {
      if (k != n_steps) loop.result.exit_code = 130;
      loop.out.emit_extra(k);
      loop.writes_ok();
      return;
    }
  }
}

// Writes frame loop.next_frame from the dense output `dense` at time `tf`
// inside the step that ended at `t_new`, then puts the step's end state
// back. In a periodic box (`images_before` given: the image counts at the
// step's start, which the dense output continues) the frame is wrapped from
// those. `current` is scratch of the state's size.
void emit_interpolated(Loop& loop, const Eigen::VectorXd& dense, double tf, double t_new,
                       const std::vector<std::array<std::int32_t, 3>>* images_before,
                       Eigen::VectorXd& current) {
  System& sys = *loop.scene.system;
  current = sys.state();
  sys.state() = dense;
  sys.set_time(tf);
  std::vector<std::array<std::int32_t, 3>> images_after;
  if (images_before) {
    images_after = sys.images();
    SystemAssembly(sys).set_images(*images_before);
    SystemAssembly(sys).wrap_positions();
  }
  loop.out.emit(loop.next_frame * loop.out.period(), /*current=*/false);
  sys.state() = current;
  sys.set_time(t_new);
  if (images_before) SystemAssembly(sys).set_images(std::move(images_after));
}

// Adaptive steps: the solver chooses each step's length; frames are due at
// m every dt (the times a fixed-step run would write them) and at the end.
// With dense output a frame is interpolated inside the step that crosses its
// time, so the step sequence does not depend on the output; a solver without
// it is stopped at each frame time instead.
void run_adaptive(Loop& loop, std::int64_t k0) {
  Scene& scene = loop.scene;
  System& sys = *scene.system;
  Solver& solver = *scene.solver;
  const double t_end = scene.end_time;
  const std::int64_t every = loop.out.period();
  const double frame_dt = static_cast<double>(every) * scene.dt;
  const std::int64_t ckpt_every = scene.output.checkpoint_every;
  std::int64_t& next_frame = loop.next_frame;
  auto frame_time = [&](std::int64_t m) {
    return frame_dt > 0 ? std::min(static_cast<double>(m) * frame_dt, t_end) : t_end;
  };
  // A frame due at m every dt, not the end of the run cut short before it.
  auto on_schedule = [&](std::int64_t m) {
    return frame_dt > 0 && static_cast<double>(m) * frame_dt <= t_end;
  };
  Eigen::VectorXd dense(sys.dimension()), current(sys.dimension());
  // In a periodic box the dense output continues the step's start state,
  // which the Stepper wrapped before the step with the image counts of
  // then: a frame inside the step is wrapped from those.
  const bool periodic = sys.domain().any_periodic();
  std::vector<std::array<std::int32_t, 3>> images_before;
  // Until a step has shown that the solver interpolates, stop on frame times.
  bool& has_dense = loop.has_dense;
  // The frames strictly inside the accepted step that ended at t_new, from
  // the dense output (the solver's own record of the step, which the
  // collision response at its end does not change).
  auto dense_frames = [&](double t_new) {
    auto interpolate = [&](double t) {
      const crash::CallScope call(scene.solver_label, "interpolate");
      return solver.interpolate(t, dense);
    };
    if (!has_dense) has_dense = interpolate(t_new);
    for (double tf; (tf = frame_time(next_frame)) < t_new;) {
      if (!interpolate(tf)) break;
      emit_interpolated(loop, dense, tf, t_new, periodic ? &images_before : nullptr, current);
      ++next_frame;
    }
  };
  auto take = [&] {
    return loop.stepper.advance(has_dense ? t_end : frame_time(next_frame), scene.dt);
  };
  for (std::int64_t k = k0 + 1; sys.time() < t_end; ++k) {
    if (periodic) images_before = sys.images();
    if (!loop.guarded_step(take, k)) break;
    const double t_new = sys.time();
    loop.out.new_state();
    dense_frames(t_new);
    loop.result.steps_done = k;
    if (on_schedule(next_frame) && frame_time(next_frame) <= t_new) {
      loop.out.emit(next_frame * every);
      ++next_frame;
    }
    if (!loop.writes_ok()) break;
    const bool done = t_new >= t_end;
    if (!loop.energy_ok(k, done)) break;
    if (ckpt_every > 0 && k % ckpt_every == 0 && !done) {
      loop.result.checkpoint = loop.out.write_checkpoint_now(k, next_frame, has_dense);
      if (!loop.writes_ok()) break;
    }
    loop.progress.update(k, t_new);
    if (done || loop.signals.raised()) {
      if (!done) loop.result.exit_code = 130;
      // The end of a run whose length is not a whole number of frame
      // intervals, or an interrupt: not a frame a longer run writes.
      loop.out.emit_extra(k);
      loop.writes_ok();
      break;
    }
  }
  loop.result.counts = solver.counts();
}

}  // namespace

// The set-up before the steps, as LAMMPS's `run` computes the forces before
// its loop: a solver that reuses its end-of-step forces (velocity Verlet,
// pdyn/force_reuse.hpp) gets the first step's a0 evaluated here, at the same
// state and time as its first step would (the same bits). Not when a force
// is told each step first (pdyn/step_aware.hpp), nor when the solver already
// holds forces (a resumed run's, from its checkpoint).
void set_up_forces(Scene& scene) {
  System& sys = *scene.system;
  auto* holder = dynamic_cast<ForceReuseHolder*>(scene.solver.get());
  if (holder == nullptr || holder->kept_accelerations(sys) != nullptr) return;
  for (const auto& f : sys.force_objects()) {
    if (dynamic_cast<const StepAware*>(f.force.get()) != nullptr) return;
  }
  if (ForceReuse::needs(sys).velocity) return;
  holder->restore_kept_accelerations(sys, sys.compute_accelerations());
}

// The steps after the set-up, timed as LAMMPS times its loop; returns s.
double run_steps(Loop& loop, std::int64_t k0, bool adaptive) {
  // Under MPI ranks the ranks first agree to start (the others wait there
  // when rank 0 stops before its first step, a first frame it could not
  // write), then set up their shares' forces together.
  if (loop.ranks != nullptr && !loop.ranks->begin_step()) return 0.0;
  if (!adaptive) set_up_forces(loop.ranks != nullptr ? loop.ranks->local() : loop.scene);
  if (loop.ranks != nullptr) {
    // The energy check's start, summed over the ranks as its checks are.
    std::array<double, 2> sum{};
    const bool check = loop.energy != nullptr && loop.energy->active();
    loop.ranks->end_step(loop.scene, false, false, check ? &sum : nullptr);
    if (check) loop.energy->start_from(sum);
  }
  const auto start = std::chrono::steady_clock::now();
  if (adaptive) {
    run_adaptive(loop, k0);
  } else {
    run_fixed(loop, k0);
  }
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

RankDriver::~RankDriver() = default;

std::array<double, 2> energy_and_magnitude(const System& sys, double kinetic) {
  double u = 0.0, abs_u = 0.0;
  for (const auto& f : sys.force_objects()) {
    if (const auto ui = f.force->potential_energy(sys.view())) {
      u += *ui;
      abs_u += std::abs(*ui);
    }
  }
  return {kinetic + u, kinetic + abs_u};
}

RunResult run_scene(Scene& scene, const RunOptions& options) {
  System& sys = *scene.system;
  // The scene stepped: this one, or under MPI ranks this rank's share (a
  // fixed-step solver: DecomposedSystem refuses the others).
  Scene& stepped = options.ranks != nullptr ? options.ranks->local() : scene;
  set_threads(options.threads > 0 ? options.threads
              : scene.threads > 0 ? scene.threads
                                  : default_threads(stepped.system->size()));
  RunResult result;
  SignalGuard signals(options.handle_signals);
  Output out(scene, options.resume);
  std::optional<crash::FatalSignalReport> crash_report;
  if (crash::reporting_enabled()) {
    crash_report.emplace(scene, out.temp_files());
    out.set_crash_report(&*crash_report);
  }
  Progress progress(options.progress ? options.log : nullptr, scene.steps, scene.end_time);
  const std::int64_t k0 = options.resume ? options.resume->step : 0;
  progress.start_at(k0);
  if (!options.resume) {
    out.emit_first(0);
    if (const std::string failure = out.take_failure(); !failure.empty()) {
      result.exit_code = 3;
      result.message = failure;
    }
  }
  Stepper stepper(*stepped.system, *stepped.solver, stepped.solver_label,
                  stepped.neighbor_schedule);
  Loop loop{scene, out, progress, signals, result, stepper};
  // On this rank's share under MPI ranks: rank 0's whole scene would build
  // whole neighbor lists (the plain run's memory) for nothing else.
  EnergyWatch energy(stepped);
  loop.energy = &energy;
  loop.strict = options.strict;
  loop.ranks = options.ranks;
  const bool adaptive = scene.solver->adaptive();
  if (options.resume) {
    loop.next_frame = options.resume->next_frame;
    loop.has_dense = options.resume->has_dense;
    // Which writers wrote the checkpoint's state: those whose schedule has
    // it (an extra final frame is left out of the output it recorded).
    const std::int64_t every = out.period();
    const double frame_dt = static_cast<double>(every) * scene.dt;
    const std::int64_t m = loop.next_frame - 1;
    const bool on_base = frame_dt > 0 && static_cast<double>(m) * frame_dt == sys.time();
    out.resume_at(*options.resume, adaptive ? (on_base ? m * every : -1) : k0, [&](std::int64_t e) {
      return adaptive ? on_base && e > 0 && (m * every) % e == 0 : e > 0 && k0 % e == 0;
    });
    if (const std::string failure = out.take_failure(); !failure.empty()) {
      result.exit_code = 3;
      result.message = failure;
    }
  }
  result.steps_done = k0;
  if (result.exit_code == 0) result.loop_seconds = run_steps(loop, k0, adaptive);
  if (options.ranks != nullptr) options.ranks->finish();
  // A run resumed at its very end takes no step; its final frame is due.
  if (result.exit_code == 0) {
    out.emit_extra(result.steps_done);
    loop.writes_ok();
  }
  // The last frames are written in the background: a failure among them
  // stops the run as any other (exit 3, a checkpoint) unless it stopped
  // already.
  out.finish_frames();
  if (result.exit_code == 0) loop.writes_ok();
  progress.update(result.steps_done, sys.time(), true);
  progress.finish();
  result.time = sys.time();
  // A checkpoint at the end of every run that keeps them, and at any early
  // stop, so that the run can be continued or inspected.
  if (!scene.output.checkpoint.empty() || result.exit_code == 3 || result.exit_code == 130) {
    result.checkpoint = out.write_checkpoint_now(result.steps_done, adaptive ? loop.next_frame : 0,
                                                 adaptive && loop.has_dense);
  }
  out.commit();
  result.output_writing = out.writing_seconds();
  result.output_stalled = out.stalled_seconds();
  return result;
}

}  // namespace pdyn
