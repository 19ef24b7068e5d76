// The process-wide thread count (see pdyn/parallel.hpp).
#include "pdyn/parallel.hpp"

#include <algorithm>

namespace pdyn {

void set_threads(int n) {
#ifdef _OPENMP
  // nthreads-var is inherited by every later parallel region started from
  // this (the main) thread, including those inside plugin libraries, which
  // share the one libgomp runtime of the process.
  omp_set_num_threads(std::max(n, 1));
#else
  (void)n;
#endif
}

int max_threads() noexcept {
#ifdef _OPENMP
  return omp_get_max_threads();
#else
  return 1;
#endif
}

int available_threads() noexcept {
#ifdef _OPENMP
  return omp_get_num_procs();
#else
  return 1;
#endif
}

int default_threads(Index particles) noexcept {
  const Index per_thread = particles / kParallelMinElements;
  return static_cast<int>(std::clamp<Index>(per_thread, 1, available_threads()));
}

}  // namespace pdyn
