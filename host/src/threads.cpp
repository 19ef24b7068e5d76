// The host's thread policy (pdyn/host/threads.hpp): the count it sets, and
// the count it picks when the scene and the user name none.
#include "pdyn/host/threads.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <pdyn/parallel.hpp>
#include <thread>

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

int available_threads() noexcept {
#ifdef _OPENMP
  return omp_get_num_procs();
#else
  return 1;
#endif
}

int threads_for(Index particles, int free_cores) noexcept {
  const Index per_work = particles / kParallelMinElements;
  return static_cast<int>(std::clamp<Index>(per_work, 1, std::max(1, free_cores)));
}

namespace {

// Busy and total jiffies of all cores, from the first line of /proc/stat
// ("cpu user nice system idle iowait irq softirq steal ..."); false if it
// cannot be read.
bool cpu_times(unsigned long long& busy, unsigned long long& total) {
  std::FILE* f = std::fopen("/proc/stat", "r");
  if (!f) return false;
  unsigned long long v[8] = {};
  const int n = std::fscanf(f, "cpu %llu %llu %llu %llu %llu %llu %llu %llu", &v[0], &v[1], &v[2],
                            &v[3], &v[4], &v[5], &v[6], &v[7]);
  std::fclose(f);
  if (n < 4) return false;
  total = 0;
  for (const auto x : v) total += x;
  busy = total - v[3] - v[4];  // all but idle and iowait
  return true;
}

// The cores other processes leave idle, measured over `ms` milliseconds
// while this process sleeps; available_threads() if /proc/stat is missing.
int free_cores(int ms) {
  const int cores = available_threads();
  unsigned long long b0 = 0, t0 = 0, b1 = 0, t1 = 0;
  if (!cpu_times(b0, t0)) return cores;
  std::this_thread::sleep_for(std::chrono::milliseconds(ms));
  if (!cpu_times(b1, t1) || t1 <= t0) return cores;
  const double busy = static_cast<double>(b1 - b0) / static_cast<double>(t1 - t0);
  // Rounded: a core busy 60% of the time is taken.
  return std::max(0, cores - static_cast<int>(std::lround(busy * cores)));
}

}  // namespace

int default_threads(Index particles) noexcept {
  const int cores = available_threads();
  if (threads_for(particles, cores) == 1) return 1;  // no need to look
  return threads_for(particles, free_cores(20));
}

}  // namespace pdyn
