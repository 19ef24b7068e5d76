// The simulation runner: steps a loaded scene and writes its output.
#pragma once

#include <cstdint>
#include <functional>
#include <iosfwd>
#include <string>

#include "scene.hpp"

namespace pdyn {

struct RunOptions {
  bool progress = false;            ///< draw a progress bar on `log`
  std::ostream* log = nullptr;      ///< where the progress bar and messages go
};

struct RunResult {
  int exit_code = 0;                ///< 0 done, 4 the state became non-finite
  std::int64_t steps_done = 0;
  double time = 0.0;
  std::string message;              ///< one line for the user when exit_code != 0
  StepCounts counts;                ///< adaptive solvers: accepted and rejected steps
};

/// Runs `scene` to its end: steps the solver, applies collider responses
/// after each step, writes frames and energy rows. Output files are written
/// under a temporary name and renamed when complete. If the state becomes
/// NaN or infinite the run stops at that step, the last good state is
/// restored and written as the final frame, and exit_code is 4.
RunResult run_scene(Scene& scene, const RunOptions& options = {});

/// Writes a file under a temporary name in the same folder and renames it to
/// its final name on commit(), so an interrupted run never leaves a file that
/// looks finished. Abandoned (not committed) files are removed.
class AtomicFile {
 public:
  explicit AtomicFile(std::filesystem::path path);
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;
  std::FILE* stream() const noexcept { return file_; }
  /// Flushes, closes and renames to the final name. Throws Error on failure.
  void commit();

 private:
  std::filesystem::path path_, temp_;
  std::FILE* file_ = nullptr;
};

}  // namespace pdyn
