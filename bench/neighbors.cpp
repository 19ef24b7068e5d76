// Neighbor-list build (pdyn/neighbors.hpp): ns per particle of a full
// rebuild (cell binning + both CSR passes) and of an update() that finds no
// particle moved, for the Lennard-Jones melt: an fcc lattice at reduced
// density 0.8442, cutoff 2.5, skin 0.3, periodic in x, y and z (reduced
// units, sigma = 1 m). 4 m^3 particles for m = 14, 29, 63 unit cells per
// side (10 976, 97 556 and 1 000 188 particles), 1 and 2 threads. A build
// that is O(N) shows the same ns per particle at every size, apart from
// cache effects.
//
//   pdyn_bench_neighbors [google benchmark flags, e.g. --benchmark_out=x.json]
#include <benchmark/benchmark.h>

#include <cmath>
#include <pdyn/host/threads.hpp>
#include <pdyn/neighbors.hpp>
#include <pdyn/parallel.hpp>

namespace {

constexpr double kDensity = 0.8442;  // particles per sigma^3
constexpr double kCutoff = 2.5;      // sigma
constexpr double kSkin = 0.3;        // sigma

struct Melt {
  pdyn::Matrix3X x;
  pdyn::Domain domain;
};

// An fcc lattice of m x m x m unit cells (4 particles each) filling a
// periodic box at kDensity.
Melt fcc(int m) {
  const double a = std::cbrt(4.0 / kDensity);  // lattice constant
  const double basis[4][3] = {{0, 0, 0}, {0.5, 0.5, 0}, {0.5, 0, 0.5}, {0, 0.5, 0.5}};
  Melt melt;
  melt.x.resize(3, 4 * pdyn::Index{m} * m * m);
  pdyn::Index i = 0;
  for (int cx = 0; cx < m; ++cx) {
    for (int cy = 0; cy < m; ++cy) {
      for (int cz = 0; cz < m; ++cz) {
        for (const auto& b : basis) {
          melt.x.col(i++) = a * pdyn::Vec3(cx + b[0], cy + b[1], cz + b[2]);
        }
      }
    }
  }
  const double L = a * m;
  melt.domain.max = pdyn::Vec3(L, L, L);
  melt.domain.periodic = {true, true, true};
  return melt;
}

// ns per particle: iterations x N particles, inverted rate.
void per_particle(benchmark::State& state, pdyn::Index n, const pdyn::NeighborList& list) {
  state.counters["N"] = static_cast<double>(n);
  state.counters["pairs"] = static_cast<double>(list.pair_count());
  state.counters["ns_per_particle"] = benchmark::Counter(
      static_cast<double>(n) * 1e-9,
      benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

void BM_build(benchmark::State& state) {
  const Melt melt = fcc(static_cast<int>(state.range(0)));
  pdyn::set_threads(static_cast<int>(state.range(1)));
  pdyn::NeighborList list(kCutoff, kSkin);
  list.build(melt.x, melt.domain);  // warm: buffers sized
  for (auto _ : state) {
    list.build(melt.x, melt.domain);
    benchmark::DoNotOptimize(list.indices().data());
  }
  per_particle(state, melt.x.cols(), list);
}

void BM_update_kept(benchmark::State& state) {
  const Melt melt = fcc(static_cast<int>(state.range(0)));
  pdyn::set_threads(static_cast<int>(state.range(1)));
  pdyn::NeighborList list(kCutoff, kSkin);
  list.build(melt.x, melt.domain);
  for (auto _ : state) {
    const bool rebuilt = list.update(melt.x, melt.domain);
    benchmark::DoNotOptimize(rebuilt);
  }
  per_particle(state, melt.x.cols(), list);
}

void sizes_and_threads(benchmark::internal::Benchmark* b) {
  for (int m : {14, 29, 63}) {
    for (int t : {1, 2}) b->Args({m, t});
  }
  b->ArgNames({"fcc_cells", "threads"});
}

BENCHMARK(BM_build)
    ->Apply(sizes_and_threads)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(1.0);
BENCHMARK(BM_update_kept)
    ->Apply(sizes_and_threads)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(1.0);

}  // namespace

BENCHMARK_MAIN();
