// The thread count parallel loops use (see pdyn/parallel.hpp), answered by
// the kernel so that code built without OpenMP gets it right.
#include "pdyn/parallel.hpp"

namespace pdyn {

int max_threads() noexcept {
#ifdef _OPENMP
  return omp_get_max_threads();
#else
  return 1;
#endif
}

}  // namespace pdyn
