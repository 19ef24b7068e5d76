#include "mpi_launch.hpp"

#include <fmt/format.h>

#include <cstdlib>

namespace pdyn::cli {

std::string several_mpi_ranks() {
  // The world size each launcher gives its processes (their own
  // documentation: Open MPI's mpirun(1) "Environment variables", MPICH's
  // PMI, MVAPICH2's user guide).
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "MV2_COMM_WORLD_SIZE"}) {
    const char* value = std::getenv(name);
    if (!value) continue;
    char* end = nullptr;
    const long size = std::strtol(value, &end, 10);
    if (end == value || size <= 1) continue;
    return fmt::format(
        "started as one of {} MPI ranks ({}={}): this pdyn runs a scene in one process, so "
        "each rank would run the whole scene and write the same files (expected pdyn without "
        "mpirun, or mpirun -np 1; several scenes at once: pdyn.sweep in Python)",
        size, name, value);
  }
  return "";
}

}  // namespace pdyn::cli
