// Refusing to run as several MPI ranks: this pdyn runs a scene in one
// process, so `mpirun -np N pdyn run scene.yaml` would start N whole copies
// of the run, each writing the same output files over the others'.
#pragma once

#include <string>

namespace pdyn::cli {

/// What is wrong when the process was started by an MPI launcher as one of
/// several ranks (Open MPI's OMPI_COMM_WORLD_SIZE, MPICH's and Intel MPI's
/// PMI_SIZE, MVAPICH's MV2_COMM_WORLD_SIZE above 1), or "" (no launcher,
/// or a single rank).
std::string several_mpi_ranks();

}  // namespace pdyn::cli
