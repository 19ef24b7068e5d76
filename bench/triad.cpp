// The machine's memory bandwidth, the floor a memory-bound step cannot beat
// (issue 17, item 3): McCalpin's STREAM kernels on arrays far larger than the
// caches,
//   copy   a[i] = b[i]              16 bytes per element
//   triad  a[i] = b[i] + s c[i]     24 bytes per element
// counted as STREAM counts them (reads and writes, not the write-allocate
// reads of a[] that a cache without streaming stores adds), best of
// `repeats`, on 1 thread and on every core. docs/performance.md divides
// pdyn's bytes per particle-step by these to give its distance from the
// floor.
//
//   pdyn_bench_triad [MiB per array, default 256] [repeats, default 10]
#include <fmt/format.h>
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <memory>

namespace {

struct Rates {
  double copy = 0.0, triad = 0.0;  // GB/s, best of the repeats
};

Rates measure(long n, int repeats, int threads) {
  const std::unique_ptr<double[]> a(new double[n]), b(new double[n]), c(new double[n]);
  // First touch by the threads that will stream them (their NUMA node, if any).
#pragma omp parallel for num_threads(threads) schedule(static)
  for (long i = 0; i < n; ++i) {
    a[i] = 0.0;
    b[i] = 1.0;
    c[i] = 2.0;
  }
  const double s = 3.0;
  Rates best;
  for (int r = 0; r < repeats; ++r) {
    auto t0 = std::chrono::steady_clock::now();
#pragma omp parallel for num_threads(threads) schedule(static)
    for (long i = 0; i < n; ++i) a[i] = b[i];
    auto t1 = std::chrono::steady_clock::now();
#pragma omp parallel for num_threads(threads) schedule(static)
    for (long i = 0; i < n; ++i) a[i] = b[i] + s * c[i];
    auto t2 = std::chrono::steady_clock::now();
    const double copy = std::chrono::duration<double>(t1 - t0).count();
    const double triad = std::chrono::duration<double>(t2 - t1).count();
    best.copy = std::max(best.copy, 16.0 * static_cast<double>(n) / copy / 1e9);
    best.triad = std::max(best.triad, 24.0 * static_cast<double>(n) / triad / 1e9);
  }
  // Keep the result observable, so the loops are not optimised away.
  if (a[n / 2] != b[n / 2] + s * c[n / 2]) std::abort();
  return best;
}

}  // namespace

int main(int argc, char** argv) {
  const long mib = argc > 1 ? std::atol(argv[1]) : 256;
  const int repeats = argc > 2 ? std::atoi(argv[2]) : 10;
  if (mib <= 0 || repeats <= 0) {
    fmt::print(stderr, "usage: pdyn_bench_triad [MiB per array > 0] [repeats > 0]\n");
    return 2;
  }
  const long n = mib * 1024 * 1024 / 8;
  fmt::print("| threads | copy GB/s | triad GB/s |\n|---|---|---|\n");
  for (int threads : {1, omp_get_num_procs()}) {
    const Rates r = measure(n, repeats, threads);
    fmt::print("| {} | {:.2f} | {:.2f} |\n", threads, r.copy, r.triad);
    if (omp_get_num_procs() == 1) break;
  }
  fmt::print("({} MiB per array, best of {})\n", mib, repeats);
}
