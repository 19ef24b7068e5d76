// pdyn/parallel.hpp — splitting per-particle and per-element loops over threads.
//
// pdyn runs with OpenMP (GCC's libgomp). The thread count is set once per
// process by the host (pdyn::set_threads in pdyn/host/threads.hpp: the
// runner calls it with the scene's `simulation.threads` or `pdyn run
// --threads N`), which calls omp_set_num_threads. A plugin built with -fopenmp (every shipped one
// is) sees that count through OpenMP's own default team size, so nothing needs to be passed to it;
// a plugin built without OpenMP runs its loops on one thread and is still correct.
//
// Determinism: results must be bit-identical for every thread count. The
// helpers below are for loops whose iterations are independent and write
// disjoint elements (y = a + h k, f += m g, ...): every element is computed
// by the same operations whatever thread runs it, so any split gives the
// same bits. A loop that accumulates into shared elements (springs adding
// into both ends) must not race or use atomics: see the spring plugin,
// which writes per-spring forces into a buffer and gathers them per
// particle in a fixed order.
#pragma once

#include <algorithm>

#include "pdyn/export.hpp"
#include "pdyn/types.hpp"

#ifdef _OPENMP
#include <omp.h>
#endif

namespace pdyn {

/// Below this many elements (particles, springs or doubles) a loop runs on
/// the calling thread: waking a team costs a few microseconds, about what
/// streaming a few thousand doubles does.
inline constexpr Index kParallelMinElements = 4096;

/// Number of threads parallel loops use: the process's OpenMP default team
/// size, as the host set it (answered by the kernel, so it is right even
/// in code built without OpenMP).
PDYN_API int max_threads() noexcept;

/// Calls body(begin, end) on contiguous, disjoint ranges that cover [0, n),
/// one per thread (one range, on the calling thread, when n is small, when
/// one thread is configured, or when already inside a parallel region).
/// `body` must not throw: an exception cannot leave an OpenMP region.
template <class Body>
void parallel_ranges(Index n, Body&& body) {
#ifdef _OPENMP
  if (n >= kParallelMinElements && omp_get_max_threads() > 1 && !omp_in_parallel()) {
#pragma omp parallel
    {
      const Index t = omp_get_thread_num(), nt = omp_get_num_threads();
      const Index begin = n * t / nt, end = n * (t + 1) / nt;
      if (begin < end) body(begin, end);
    }
    return;
  }
#endif
  if (n > 0) body(Index{0}, n);
}

/// Elements per chunk of parallel_chunks: 2048 doubles (or 682 columns of
/// a 3 x N matrix) are 16 KiB per array, so the four or five arrays of a
/// solver's update stay in a core's L1/L2 cache between its statements.
inline constexpr Index kChunkElements = 2048;

/// As parallel_ranges, but calls body(begin, end) on consecutive chunks of
/// at most `chunk` elements within each thread's range. A body of several
/// statements over the same elements (Eigen evaluates each statement as
/// its own loop) then streams each array from memory once, the later
/// statements finding the chunk in cache: at sizes beyond the cache that
/// halves the memory traffic of a two-statement update.
template <class Body>
void parallel_chunks(Index n, Index chunk, Body&& body) {
  parallel_ranges(n, [&](Index begin, Index end) {
    for (Index b = begin; b < end; b += chunk) body(b, std::min(end, b + chunk));
  });
}

/// As parallel_chunks over a state vector [x | v] of `dim` = 6N doubles,
/// but each thread takes the same particles' elements in both halves: the
/// elements [b, e) of the positions and [dim/2 + b, dim/2 + e) of the
/// velocities, b and e from a split of the first half. Then a thread
/// updates the positions and velocities of the particles whose forces it
/// gathered (System::derivative splits by particle), and neither half
/// travels between the cores' caches at every stage: with parallel_chunks
/// over all 6N, one thread updated every position and the other every
/// velocity, and 2 threads ran the 316 x 316 cloth only 1.4x faster than 1.
/// The body is called once per chunk of each half, the positions' chunks
/// first.
template <class Body>
void parallel_state_chunks(Index dim, Index chunk, Body&& body) {
  const Index half = dim / 2;
  parallel_ranges(half, [&](Index begin, Index end) {
    for (Index b = begin; b < end; b += chunk) body(b, std::min(end, b + chunk));
    for (Index b = begin; b < end; b += chunk) body(half + b, half + std::min(end, b + chunk));
  });
}

}  // namespace pdyn
