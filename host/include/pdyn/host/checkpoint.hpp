// Checkpoints: the complete state of a run, to resume it bit-identically.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "pdyn/error.hpp"
#include "pdyn/types.hpp"

namespace pdyn {

/// A checkpoint cannot be used: exit status 2. Nothing of it was applied.
class CheckpointError : public Error {
 public:
  using Error::Error;
};

/// How much of an output file belonged to the run at the checkpoint, so a
/// resumed run can check the file is the same and continue it.
struct OutputMark {
  std::string path;         ///< as the scene names it; empty: no such output
  std::uint64_t bytes = 0;  ///< length written up to the checkpoint
  std::uint32_t crc = 0;    ///< CRC-32 of those bytes
};

struct Checkpoint {
  /// Version 3 added the image counts; version 2 files are still read (as
  /// images 0: they were written before the simulation box existed).
  static constexpr std::uint32_t kFormatVersion = 3;
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
  OutputMark frames, energy;
};

/// Writes `c` to `path` atomically: a temporary file in the same folder,
/// fsync, rename. The previous checkpoint stays intact until the new one is
/// complete. Throws Error if it cannot be written.
void write_checkpoint(const std::filesystem::path& path, const Checkpoint& c);

/// Reads and verifies a checkpoint (magic, format version, length, CRC-32).
/// Throws CheckpointError naming the file and what is wrong.
Checkpoint read_checkpoint(const std::filesystem::path& path);

/// FNV-1a 64-bit hash, for naming a scene text compactly.
std::uint64_t fnv1a(const std::string& text);

}  // namespace pdyn
