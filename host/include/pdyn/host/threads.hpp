// pdyn/host/threads.hpp — how many threads a host runs the kernel's and the
// plugins' parallel loops on (pdyn/parallel.hpp). A host sets the count once
// per process; plugins read it (pdyn::max_threads) and never set it.
#pragma once

#include <pdyn/types.hpp>

#include "pdyn/host/export.hpp"

namespace pdyn {

/// Sets the number of threads (>= 1) every later parallel loop in
/// the process uses, kernel and plugins alike (omp_set_num_threads). Without
/// OpenMP it does nothing. The runner calls it; plugins never need to.
PDYN_HOST_API void set_threads(int n);

/// The number of cores this process may use (omp_get_num_procs).
PDYN_HOST_API int available_threads() noexcept;

/// The thread count for `particles` particles on a machine with
/// `free_cores` cores not busy with other work: one thread per
/// kParallelMinElements particles, at least 1 and at most max(1,
/// free_cores). Below that a second thread has too little to do: on the
/// 2-core machine the cloth with rk4 ran 1.06x slower on 2 threads than on
/// 1 at 2,500 particles, even at 4,900 and 1.22x faster at 10,000. And a
/// thread on a core another process keeps busy stalls the others at every
/// barrier: with a CPU-bound process on each core, 2 threads took 1.8x the
/// time of 1 (docs/performance.md, "Threads and determinism").
PDYN_HOST_API int threads_for(Index particles, int free_cores) noexcept;

/// The thread count a host uses when the scene and the user name none:
/// threads_for(particles, the cores left idle by other processes, sampled
/// from /proc/stat over 20 ms when more than one thread would be worth it;
/// every core where that cannot be read). Results are bit-identical for
/// every count, so this changes only the speed.
PDYN_HOST_API int default_threads(Index particles) noexcept;

}  // namespace pdyn
