// Everything a run writes: each writer's frames on its own schedule, written
// on an output thread while the solver steps on, and checkpoints with every
// writer's mark. Internal to the runner (host/src/runner.cpp).
#pragma once

#include <condition_variable>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "frame_snapshot.hpp"
#include "pdyn/host/checkpoint.hpp"
#include "pdyn/host/crash_report.hpp"
#include "pdyn/host/scene.hpp"
#include "pdyn/writer.hpp"

namespace pdyn {

// Runs one job at a time on its own thread: start() hands it over, wait()
// blocks until it is done. The thread sleeps on a condition variable in
// between (no spinning: it must not take a core from the solver's threads).
class OutputThread {
 public:
  explicit OutputThread(std::function<void()> job);
  ~OutputThread();
  OutputThread(const OutputThread&) = delete;
  OutputThread& operator=(const OutputThread&) = delete;

  void start();  // the previous job must be done (wait())
  void wait();

 private:
  void loop();

  std::function<void()> job_;
  std::mutex mutex_;
  std::condition_variable cv_;
  bool busy_ = false, quit_ = false;
  std::thread thread_;  // last: started once the members above exist
};

// Schedules: writer w writes the frame of step n when n % every_w == 0. The
// loops step through frames of the base period, the greatest common divisor
// of the writers' `every` (one writer: its own), and call emit(n) there.
// Each writer knows whether it holds the current state (`current`): an
// extra frame (end of run, interrupt, fault) goes only to writers that do
// not, and a checkpoint after it records their marks from before it, so a
// resumed run continues every file as an uninterrupted run would have.
//
// Background writing: a frame is copied (FrameSnapshot: 6N doubles and the
// particle properties, about 1 ms per 10^5 particles) and handed to the
// output thread, which encodes and writes it while the solver takes the next
// steps. Anything that needs the writers' files as they are (the next
// frame, a mark, a checkpoint, commit) first waits for that write to end.
// So a failed write (a full disk) is seen at the next frame or checkpoint,
// after the run has moved on: the frames the failed writer could not write
// are kept (`pending`) and travel in the checkpoint, and the resumed run
// writes them first.
class Output {
 public:
  Output(const Scene& scene, const Checkpoint* resume);
  ~Output();

  /// The base period in steps (gcd of the writers' `every`); 0: no writer
  /// writes between the first and the final frame.
  std::int64_t period() const { return scene_.output.period(); }

  /// Every writer writes the first frame.
  void emit_first(std::int64_t step);
  /// The state has changed (a step was taken): no writer holds it yet.
  void new_state();
  /// The frame of step n on the schedule: written by the writers it is due
  /// for. `current`: the state is the run's current one (not a frame
  /// interpolated inside a step).
  void emit(std::int64_t n, bool current = true);
  /// A frame off the run's schedule: the end of a run that a longer run
  /// would pass through without a frame, the step an interrupt stopped at,
  /// the last good state before a fault. Written by every writer that does
  /// not hold the current state yet, but a checkpoint taken after it records
  /// the output without it.
  void emit_extra(std::int64_t step);
  /// After a resume: first the frames the checkpoint holds for writers that
  /// had failed; then, which writers wrote the checkpoint's state (it is in
  /// the output they continue): as the checkpoint says, else (older
  /// checkpoints) as `wrote` says from the writer's schedule. A writer that
  /// did not, although the state is on its schedule (`n`, -1: off the base
  /// schedule), writes it now.
  void resume_at(const Checkpoint& c, std::int64_t n,
                 const std::function<bool(std::int64_t every)>& wrote);
  /// Waits for the frame being written: afterwards take_failure() knows
  /// every failure so far.
  void finish_frames();
  /// The first writer failure seen since the last call, as a message, or
  /// empty. A frame still being written is not waited for (finish_frames).
  std::string take_failure() { return std::exchange(failure_, {}); }

  std::filesystem::path write_checkpoint_now(std::int64_t step, std::int64_t next_frame,
                                             bool has_dense);
  /// Completes every output (a writer that failed keeps its complete
  /// frames); throws the first failure after trying them all.
  void commit();
  std::vector<std::filesystem::path> temp_files() const;
  void set_crash_report(crash::FatalSignalReport* report) { crash_report_ = report; }
  /// RunResult::output_writing and output_stalled so far, s.
  double writing_seconds() const { return writing_seconds_; }
  double stalled_seconds() const { return stalled_seconds_; }

 private:
  struct Slot {
    const WriterSpec* spec = nullptr;
    std::shared_ptr<Writer> writer;
    bool force = false, energy = false;  // the frames need forces, energies
    // The frames need the constraint forces' virial: a writer with energies
    // that is not the shipped energy writer, or that one with a pressure or
    // virial column (a RATTLE solve per frame otherwise spent for nothing).
    bool constraint_virial = false;
    bool current = false;  // has written (or keeps pending) the current state
    bool failed = false;   // a write threw: no more frames, no commit
    std::optional<std::vector<std::uint8_t>> held;  // mark before an extra frame
    // Frames it did not write after it failed, encoded for the checkpoint.
    std::vector<std::vector<std::uint8_t>> pending;
    // Handed to the output thread with the snapshot (queued), whether that
    // frame is extra, and the output thread's message if the write threw.
    bool queued = false, queued_extra = false;
    std::string error;
  };

  static bool due(const Slot& s, std::int64_t n);
  // Captures the current state as frame `step` and hands it to the output
  // thread for every slot `pick` selects (a failed one keeps it pending,
  // unless `extra`).
  void dispatch(std::int64_t step, bool current, bool extra,
                const std::function<bool(const Slot&)>& pick);
  // The output thread's job: the snapshot to every queued slot.
  void write_queued();
  // Writes `frame` to `s` on the calling thread; returns the failure message.
  std::string write_one(Slot& s, const Frame& frame);
  std::vector<std::uint8_t> mark(Slot& s);
  std::string library_of(const WriterSpec& spec) const;

  const Scene& scene_;
  const System& sys_;
  std::filesystem::path checkpoint_;
  std::vector<Slot> slots_;
  std::string failure_;
  std::int64_t step_ = 0;  // of the checkpoint being written, for messages
  crash::FatalSignalReport* crash_report_ = nullptr;
  FrameSnapshot snapshot_;        // the frame the output thread writes
  bool writing_ = false;          // the output thread has a job
  double writing_seconds_ = 0.0;  // updated by the output thread, read after wait()
  double stalled_seconds_ = 0.0;
  std::unique_ptr<OutputThread> thread_;  // started with the first frame
};

}  // namespace pdyn
