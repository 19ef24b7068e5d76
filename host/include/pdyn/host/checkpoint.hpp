// Checkpoints: the complete state of a run, to resume it bit-identically.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "pdyn/domain.hpp"
#include "pdyn/error.hpp"
#include "pdyn/host/export.hpp"
#include "pdyn/types.hpp"

namespace pdyn {

/// A checkpoint cannot be used: exit status 2. Nothing of it was applied.
class PDYN_HOST_API CheckpointError : public Error {
 public:
  using Error::Error;
};

/// How far one writer's output had gone at the checkpoint (Writer::mark()),
/// so a resumed run can check the output is the same and continue it.
struct PDYN_HOST_API WriterMark {
  std::string path;                ///< the writer's path as the scene names it
  std::vector<std::uint8_t> mark;  ///< the writer's own bytes (csv: pdyn::FileMark)
  /// Whether the output holds the checkpoint's state as a frame: 1 yes, 0
  /// no (a resumed run writes it first if it is on the writer's schedule),
  /// -1 unknown (versions 2 and 3: the writer's schedule says).
  std::int8_t wrote_state = -1;
  /// Version 5: frames the writer did not write because it had failed (a
  /// full disk), in order, each as the runner encoded it; a resumed run
  /// writes them first, so the output ends up as an uninterrupted run's.
  std::vector<std::vector<std::uint8_t>> pending;
};

struct PDYN_HOST_API Checkpoint {
  /// Version 6 adds the accelerations a velocity-Verlet solver keeps for
  /// its next step (pdyn/force_reuse.hpp): the resumed run's first step
  /// reuses them as the uninterrupted run would, and gives the same bits.
  /// Version 5 adds each writer's pending frames. Version 4 holds one mark
  /// per writer (output list); versions 3 (image
  /// counts, frames and energy marks) and 2 (no image counts: read as 0)
  /// are still read, their two marks as the csv and energy writers' marks.
  /// Version 7 adds the box, which a barostat changes.
  static constexpr std::uint32_t kFormatVersion = 7;
  static constexpr std::uint32_t kOldestReadableVersion = 2;

  std::string scene_file;           ///< where the scene came from (for messages)
  std::string scene_text;           ///< canonical scene after overrides, without steps/duration
  std::int64_t step = 0;            ///< steps done
  double time = 0.0;                ///< simulated time, s
  std::int64_t next_frame = 0;      ///< adaptive runs: index of the next frame due
  bool has_dense = false;           ///< adaptive runs: the solver has shown dense output
  Eigen::VectorXd state;            ///< [x | v], 6N
  Eigen::VectorXd mass;             ///< N
  std::vector<std::uint8_t> fixed;  ///< N
  /// N: box lengths each particle was wrapped by along x, y, z
  /// (System::images(); the unwrapped position is x + images L).
  std::vector<std::array<std::int32_t, 3>> images;
  /// save_state() of the solver, then each force, then each collider, in
  /// scene order, each with a label naming the plugin.
  std::vector<std::pair<std::string, std::vector<std::uint8_t>>> plugin_states;
  /// One per writer of the scene's output, in scene order.
  std::vector<WriterMark> outputs;
  /// Version 6: the end-of-step accelerations (m/s^2, 3 x N) the solver
  /// would reuse as its next step's a0 (ForceReuseHolder), or empty.
  Matrix3X reused;
  /// Version 7: the box at the checkpoint (System::domain()); earlier
  /// versions: none, and the scene's box is kept.
  std::optional<Domain> box;

  /// The mark of the writer whose path is `path`, or nullptr.
  const WriterMark* output(const std::string& path) const;
};

/// Writes `c` to `path` atomically: a temporary file in the same folder,
/// fsync, rename. The previous checkpoint stays intact until the new one is
/// complete. Throws Error if it cannot be written.
PDYN_HOST_API void write_checkpoint(const std::filesystem::path& path, const Checkpoint& c);

/// Reads and verifies a checkpoint (magic, format version, length, CRC-32).
/// Throws CheckpointError naming the file and what is wrong.
PDYN_HOST_API Checkpoint read_checkpoint(const std::filesystem::path& path);

/// FNV-1a 64-bit hash, for naming a scene text compactly.
PDYN_HOST_API std::uint64_t fnv1a(const std::string& text);

}  // namespace pdyn
