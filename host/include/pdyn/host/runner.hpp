// The simulation runner: steps a loaded scene and writes its output.
#pragma once

#include <array>
#include <cstdint>
#include <cstdio>
#include <iosfwd>
#include <optional>
#include <string>
#include <string_view>

#include "pdyn/host/checkpoint.hpp"
#include "pdyn/host/export.hpp"
#include "pdyn/host/scene.hpp"
#include "pdyn/host/stepper.hpp"

namespace pdyn {

/// Since 0.10.0 (issue 43; docs/parallel.md): rank 0's side of a scene run
/// by several MPI ranks (pdyn/host/decomposed.hpp implements it). The scene
/// run_scene is given is then rank 0's copy of the whole scene, which is
/// never stepped: the steps are taken on local(), which holds this rank's
/// particles, and the writers, the energy check and the checkpoints read
/// the whole scene once the particles have been gathered into it. Every
/// other rank calls the same collectives in the same order.
class PDYN_HOST_API RankDriver {
 public:
  virtual ~RankDriver();
  /// The scene whose System holds this rank's owned particles and ghosts:
  /// the one the Stepper steps.
  virtual Scene& local() = 0;
  /// Before each step (collective): false when the run stops here (only
  /// finish() asks for that). Exchanges the particles when due.
  virtual bool begin_step() = 0;
  /// After each step (collective): `gather` rank 0's wish to read the
  /// state, `failed` whether this rank's step failed. When gathering, every
  /// particle's state, the time and a solver's kept accelerations are put
  /// into `whole`. `energy`: non-null on rank 0 when the energy check is
  /// due; it then receives the total energy and its magnitude (J: K + sum
  /// U_i and K + sum |U_i|, EnergyWatch in runner.cpp) summed over the
  /// ranks, each rank's kinetic energy of its owned particles and potential
  /// energies of its particles, so that a pair across two subdomains counts
  /// on both (a safeguard's figure, never an output). Returns the lowest
  /// rank whose step failed, or -1.
  virtual int end_step(Scene& whole, bool gather, bool failed, std::array<double, 2>* energy) = 0;
  /// Ends the run on every rank (collective): called once, when run_scene
  /// stops stepping for whatever reason.
  virtual void finish() = 0;
};

/// What the energy check compares (EnergyWatch in runner.cpp), J: the total
/// energy `kinetic` + sum U_i and its magnitude `kinetic` + sum |U_i|, over
/// the potential energies the force objects of `sys` report.
PDYN_HOST_API std::array<double, 2> energy_and_magnitude(const System& sys, double kinetic);

struct PDYN_HOST_API RunOptions {
  bool progress = false;        ///< draw a progress bar on `log`
  std::ostream* log = nullptr;  ///< where the progress bar goes
  /// Catch SIGINT and SIGTERM: finish the current step, write the final
  /// frame, energy row and a checkpoint, and stop with exit code 130. A
  /// second signal exits at once (temporary files keep their temporary names).
  bool handle_signals = false;
  /// Continue from this checkpoint (already checked against the scene and
  /// applied by restore_checkpoint); its output files are continued.
  const Checkpoint* resume = nullptr;
  /// Threads for forces and solvers (pdyn run --threads); 0: the scene's
  /// simulation.threads, else one per 4096 particles, up to every core
  /// (pdyn::default_threads). The
  /// results are bit-identical for every count.
  int threads = 0;
  /// pdyn run --strict: a run whose energy grows without a driving force
  /// (see EnergyWatch in runner.cpp) stops with exit code 4 instead of
  /// finishing with a warning.
  bool strict = false;
  /// Since 0.10.0: the scene's particles live on MPI ranks (RankDriver):
  /// steps are taken on ranks->local(), and `scene` is rank 0's copy of the
  /// whole scene that the output reads. Fixed-step solvers only.
  RankDriver* ranks = nullptr;
};

struct PDYN_HOST_API RunResult {
  /// 0 done; 3 a plugin threw or a writer failed (a full disk); 4 the state
  /// became non-finite; 130 interrupted.
  int exit_code = 0;
  std::int64_t steps_done = 0;
  double time = 0.0;
  std::string message;               ///< one line for the user when exit_code != 0
  StepCounts counts;                 ///< adaptive solvers: accepted and rejected steps
  std::filesystem::path checkpoint;  ///< the last checkpoint written, if any
  /// Set when the total energy grew more than a millionfold with no force
  /// driving it: one line naming the step, the energies and the solver.
  std::string energy_warning;
  /// Output, s: the writers' time in write() on the output thread, which
  /// overlaps the steps, and in commit() at the end (what a writer's
  /// throughput is measured against); and the run's own time spent copying
  /// frames for the output thread, waiting for it and committing (what
  /// output adds to the run when a core is free for the output thread).
  double output_writing = 0.0, output_stalled = 0.0;
  /// The steps' loop, s: from after the set-up (the first force evaluation,
  /// the first frames) to the last step, as LAMMPS's "Loop time" counts.
  double loop_seconds = 0.0;
};

/// Runs `scene` to its end: steps the solver, applies collider responses
/// after each step, writes frames, energy rows and checkpoints. Output files
/// are written under a temporary name and renamed when complete. If the
/// state becomes NaN or infinite, or a plugin throws, the run stops at that
/// step, the last good state is restored, written as the final frame and
/// checkpointed. Throws CheckpointError if resumed output files do not match.
PDYN_HOST_API RunResult run_scene(Scene& scene, const RunOptions& options = {});

/// The set-up run_scene makes before its steps, as LAMMPS's `run` computes
/// the forces before its loop: a solver that reuses its end-of-step forces
/// gets the first step's evaluated. Since 0.10.0 public, for the other MPI
/// ranks, which step their share without run_scene (pdyn/host/decomposed.hpp).
PDYN_HOST_API void set_up_forces(Scene& scene);

/// One line for the user on a failed step `k` (Stepper::fault()): which
/// plugin object is at fault and its library, or where the state became
/// non-finite. `kept` completes "the last good state (step k-1) ...": what
/// the host did with it ("was written as the final frame").
PDYN_HOST_API std::string step_fault_message(const StepFault& fault, const Scene& scene,
                                             std::int64_t k, std::string_view kept);

/// The scene's complete state as a checkpoint at step `step`: particles,
/// time, and every plugin object's save_state(), solver first. Output marks
/// and the adaptive schedule (next_frame, has_dense) are left for the caller.
PDYN_HOST_API Checkpoint capture_checkpoint(const Scene& scene, std::int64_t step);

/// Applies checkpoint `c` to a freshly loaded `scene`: state, masses, fixed
/// flags, time and every plugin's internal state. Throws CheckpointError if
/// the checkpoint was written for another scene (unless `force`), or does not
/// fit it. With `force`, `differences` receives one line per differing key.
/// `anyway` names, in the caller's terms, how to restore regardless; it ends
/// the message of a scene mismatch.
PDYN_HOST_API void restore_checkpoint(Scene& scene, const Checkpoint& c, bool force,
                                      std::vector<std::string>* differences = nullptr,
                                      std::string_view anyway = "--force resumes anyway");

/// Where a run's checkpoint goes: output.checkpoint.path (or checkpoint.path),
/// else beside output.path or the first writer's file (.ckpt), else
/// `<scene name>.ckpt` in the working directory.
PDYN_HOST_API std::filesystem::path checkpoint_path(const Scene& scene);

}  // namespace pdyn
