#include "mpi_launch.hpp"

#include <fmt/format.h>

#include <cstdlib>
#include <utility>

namespace pdyn::cli {

bool built_with_mpi() noexcept {
#ifdef PDYN_MPI
  return true;
#else
  return false;
#endif
}

namespace {

// The world size a launcher gave this process and the variable that says
// so (their own documentation: Open MPI's mpirun(1) "Environment
// variables", MPICH's PMI, MVAPICH2's user guide); {1, ""} without one.
std::pair<long, const char*> launcher_size() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "MV2_COMM_WORLD_SIZE"}) {
    const char* value = std::getenv(name);
    if (!value) continue;
    char* end = nullptr;
    const long size = std::strtol(value, &end, 10);
    if (end != value && size > 1) return {size, name};
  }
  return {1, ""};
}

}  // namespace

int mpi_world_size() { return static_cast<int>(launcher_size().first); }

std::string several_mpi_ranks(const std::string& command) {
  const auto [size, name] = launcher_size();
  if (size <= 1 || (command == "run" && built_with_mpi())) return "";
  const char* value = std::getenv(name);
  if (command == "run") {
    return fmt::format(
        "started as one of {} MPI ranks ({}={}): this pdyn was built without MPI and runs a "
        "scene in one process, so each rank would run the whole scene and write the same "
        "files (expected pdyn without mpirun, or mpirun -np 1, or a pdyn built with MPI; "
        "several scenes at once: pdyn.sweep in Python)",
        size, name, value);
  }
  return fmt::format(
      "started as one of {} MPI ranks ({}={}): only `pdyn run` runs on several ranks (expected "
      "pdyn {} without mpirun, or mpirun -np 1)",
      size, name, value, command);
}

#ifndef PDYN_MPI
std::unique_ptr<MpiRun> start_mpi_run() { return nullptr; }
#endif

}  // namespace pdyn::cli
