// STREAM's triad a[i] = b[i] + s c[i] (McCalpin) on arrays far larger than
// the caches, split into equal parts over T std::threads: what T cores get
// from memory at this moment. pdyn_bench_cloth --pairs times it beside the
// cloth in every round, so that a 2-thread speed-up is compared with what a
// second core adds to the bandwidth in the same minute (issue 32, item 3);
// bench/triad.cpp is the standalone STREAM program.
#pragma once

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <thread>
#include <vector>

namespace pdyn::bench {

class StreamTriad {
 public:
  /// Three arrays of `mib` MiB each, touched once so that no page fault
  /// falls inside a timing.
  explicit StreamTriad(long mib)
      : n_(mib * (1 << 20) / static_cast<long>(sizeof(double))),
        a_(n_, 0.0),
        b_(n_, 1.0),
        c_(n_, 2.0) {}

  /// Best of `repeats` triads on `threads` threads, s.
  double seconds(int threads, int repeats) {
    double best = 1e300;
    for (int r = 0; r < repeats; ++r) {
      const auto t0 = std::chrono::steady_clock::now();
      std::vector<std::thread> pool;
      for (int t = 1; t < threads; ++t) pool.emplace_back([this, t, threads] { part(t, threads); });
      part(0, threads);
      for (std::thread& th : pool) th.join();
      best = std::min(best,
                      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    }
    // Keep the result observable, so the loop is not optimised away.
    if (a_[n_ / 2] != b_[n_ / 2] + kScale * c_[n_ / 2]) std::abort();
    return best;
  }

 private:
  static constexpr double kScale = 3.0;
  void part(int t, int threads) {
    const long begin = n_ * t / threads, end = n_ * (t + 1) / threads;
    double* a = a_.data();
    const double *b = b_.data(), *c = c_.data();
    for (long i = begin; i < end; ++i) a[i] = b[i] + kScale * c[i];
  }
  long n_;
  std::vector<double> a_, b_, c_;
};

}  // namespace pdyn::bench
