// A loaded scene stepped under a program's control: what the Python module
// (python/) and any embedding program drive, step by step, taking exactly
// the steps `pdyn run` takes.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "pdyn/host/export.hpp"
#include "pdyn/host/runner.hpp"
#include "pdyn/host/scene.hpp"
#include "pdyn/host/stepper.hpp"

namespace pdyn {

/// A step failed (Stepper::fault()): what() is the line `pdyn run` prints,
/// naming the plugin object at fault and its library. The simulation is back
/// at the last good state, the start of the failed step.
class PDYN_HOST_API StepError : public Error {
 public:
  StepError(const std::string& message, StepFault fault)
      : Error(message), fault_(std::move(fault)) {}
  const StepFault& fault() const noexcept { return fault_; }

 private:
  StepFault fault_;
};

class PDYN_HOST_API Simulation {
 public:
  /// Takes over a loaded scene (load_scene). Sets the thread count: `threads`
  /// if > 0, else the scene's simulation.threads, else
  /// pdyn::default_threads(particles) (pdyn/host/threads.hpp).
  explicit Simulation(Scene scene, int threads = 0);
  Simulation(const Simulation&) = delete;
  Simulation& operator=(const Simulation&) = delete;

  Scene& scene() noexcept { return scene_; }
  const Scene& scene() const noexcept { return scene_; }
  System& system() noexcept { return *scene_.system; }
  const System& system() const noexcept { return *scene_.system; }
  /// Steps taken (accepted steps for an adaptive solver), counting those of
  /// the checkpoint a simulation was restored from.
  std::int64_t steps() const noexcept { return steps_; }

  /// Takes `n` steps exactly as `pdyn run` takes them: fixed step k ends at
  /// k dt (computed, not accumulated; the last step of a `duration` scene
  /// ends on the duration), and an adaptive solver's steps stop on the
  /// scene's frame times until it shows dense output, so the same scene gives
  /// the same bits. `interrupted`, if given, is asked every 64 steps and
  /// stops the loop when it returns true. Throws StepError on a fault;
  /// returns the steps taken.
  std::int64_t step(std::int64_t n, const std::function<bool()>& interrupted = {});
  /// Steps until the time reaches `t_end` (s), at most `max_steps` steps:
  /// the same steps as step(), the last one shortened to end on t_end if
  /// the step times miss it by more than rounding (the step times then
  /// restart there, as for set_dt). Returns the steps taken.
  std::int64_t run_until(double t_end, std::int64_t max_steps,
                         const std::function<bool()>& interrupted = {});
  /// Steps to the scene's end (simulation.steps or duration).
  std::int64_t run_to_end(const std::function<bool()>& interrupted = {});

  /// The time step, s. Changing it restarts the computed step times at the
  /// current time: later fixed steps end at t + k dt'.
  double dt() const noexcept { return scene_.dt; }
  /// The thread count set at construction. OpenMP keeps it per calling
  /// thread: a program that steps from another thread calls
  /// pdyn::set_threads(threads()) there first (the Python module does).
  int threads() const noexcept { return threads_; }
  void set_dt(double dt);
  /// Replaces the solver with a new object (add_plugin with PluginKind::Solver
  /// makes one); the step times restart at the current time, as for set_dt.
  void solver_changed();

  /// Writes a checkpoint of the current state to `path` (atomically).
  void save_checkpoint(const std::filesystem::path& path) const;
  /// Restores a checkpoint written for this scene (same particles and plugin
  /// objects). Throws CheckpointError otherwise; nothing is applied then.
  /// With `force`, one written for a scene that differs only in its
  /// parameters is restored too, as `pdyn run --resume --force` does;
  /// `anyway` names that option in the caller's terms in the message.
  void restore_checkpoint(const std::filesystem::path& path, bool force = false,
                          std::string_view anyway = "--force resumes anyway");

  /// Replaces the system (same forces, colliders, box, radii, types, time
  /// and images) with one holding the particles of the current one plus the
  /// `x.cols()` new ones: the old System is handed back, untouched, so that
  /// memory a caller still refers to stays valid (Python's array views).
  std::unique_ptr<System> add_particles(const Matrix3X& x, const Matrix3X& v,
                                        const Eigen::VectorXd& mass,
                                        const std::vector<std::uint8_t>& fixed);

 private:
  void step_once(double limit);
  template <class Take>
  void take(const Take& take_step);
  void restart_clock();

  Scene scene_;
  int threads_ = 1;
  std::unique_ptr<Stepper> stepper_;
  std::int64_t steps_ = 0;
  // Fixed steps: step k ends at clock_time_ + (k - clock_step_) dt; (0, 0)
  // until dt or the solver changes, which is pdyn run's k dt bit for bit.
  std::int64_t clock_step_ = 0;
  double clock_time_ = 0.0;
  // Adaptive steps, as run_adaptive schedules them: the next frame's index
  // and whether the solver has shown dense output.
  std::int64_t next_frame_ = 1;
  bool has_dense_ = false;
  Eigen::VectorXd dense_;
};

}  // namespace pdyn
