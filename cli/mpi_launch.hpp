// `mpirun -np N pdyn run scene.yaml` (issue 43; docs/parallel.md). A pdyn
// built with MPI runs the scene decomposed over the ranks (cli/mpi_run.cpp);
// one built without refuses, since each rank would run the whole scene and
// write the same output files over the others'. Every other command refuses
// under several ranks.
#pragma once

#include <functional>
#include <iosfwd>
#include <memory>
#include <optional>
#include <string>

#include "pdyn/host/runner.hpp"

namespace pdyn::cli {

/// What is wrong when the process was started by an MPI launcher as one of
/// several ranks (Open MPI's OMPI_COMM_WORLD_SIZE, MPICH's and Intel MPI's
/// PMI_SIZE, MVAPICH's MV2_COMM_WORLD_SIZE above 1) and `command` cannot
/// run that way, or "" (no launcher, a single rank, or `pdyn run` in a
/// pdyn built with MPI).
std::string several_mpi_ranks(const std::string& command);

/// The launcher's world size (1 without a launcher).
int mpi_world_size();

/// True when this pdyn runs `pdyn run` decomposed under mpirun.
bool built_with_mpi() noexcept;

/// A run on several MPI ranks, between MPI_Init and MPI_Finalize.
class MpiRun {
 public:
  virtual ~MpiRun() = default;
  virtual int rank() const = 0;
  /// Runs the scene decomposed: `local` is loaded (and a checkpoint
  /// restored) on every rank; on rank 0 only (nullptr elsewhere),
  /// `load_whole` loads the same scene again into `whole`, once `local` has
  /// given up the particles that are not its own (so that the two whole
  /// copies are never held at once), and run_scene runs on it with
  /// `options` and writes the output. `grid`: pdyn run --grid, or "".
  /// Returns rank 0's result; on the other ranks exit_code is the rank's
  /// status. Throws DecompositionError (on every rank alike) when the scene
  /// cannot run decomposed.
  virtual RunResult run(Scene& local, const std::function<Scene()>* load_whole,
                        std::optional<Scene>& whole, RunOptions options, const std::string& grid,
                        std::ostream& err) = 0;
  /// Force evaluations on this rank's share so far.
  virtual std::uint64_t evaluations() const = 0;
  /// One line on the decomposition of the last run: ranks, grid,
  /// exchanges, rank 0's halo, for `pdyn run`'s summary.
  virtual std::string summary() const = 0;
  /// After an error on this rank once the run has started, the other ranks
  /// wait for it: ends the whole job with `status`.
  virtual void abort_if_running(int status) = 0;
};

/// MPI_Init for a `pdyn run` under several ranks, or nullptr in a pdyn
/// built without MPI.
std::unique_ptr<MpiRun> start_mpi_run();

}  // namespace pdyn::cli
