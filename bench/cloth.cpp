// Hanging-cloth throughput (issue 4): ns per particle-step of
//   pdyn_run     pdyn as a user assembles it: bench/hanging_cloth.yaml loaded
//                with its plugins, stepped by the runner (run_scene, with its
//                per-step fault checks), 1 and 2 threads;
//   pdyn_step    the same scene stepped by calling the solver directly (the
//                runner's checks left out), to show what they cost;
//   fused        the hand-fused reference, bench/fused_cloth.hpp;
//   odeint       Boost.Odeint's runge_kutta4 over the reference's derivative;
// at 100 x 100, 316 x 316 and 1000 x 1000 particles. Before timing, all
// variants take the same steps from the same state and must agree to a
// relative 1e-12 (max-norm), or the program exits with status 1.
//
//   pdyn_bench_cloth [google benchmark flags, e.g. --benchmark_out=x.json]
//   pdyn_bench_cloth --memory pdyn|fused N   peak RSS of an N x N cloth after
//                                            3 steps (run each in its own process)
//   pdyn_bench_cloth --load                  scene load times
//
// scripts/bench.sh runs all three and writes docs/performance.md's numbers.
#include <benchmark/benchmark.h>
#include <fmt/format.h>
#include <sys/resource.h>

#include <boost/numeric/odeint/stepper/runge_kutta4.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <pdyn/parallel.hpp>
#include <string>
#include <vector>

#include "fused_cloth.hpp"
#include "registry.hpp"
#include "runner.hpp"
#include "scene.hpp"

namespace {

using pdyn::bench::ClothSpec;
using pdyn::bench::FusedCloth;

constexpr double kDt = 0.0002;  // s, bench/hanging_cloth.yaml's
const int kSizes[] = {100, 316, 1000};

const pdyn::PluginRegistry& registry() {
  static const pdyn::PluginRegistry r = [] {
    pdyn::PluginRegistry reg;
    reg.discover({PDYN_PLUGIN_DIR});
    return reg;
  }();
  return r;
}

pdyn::Scene load_pdyn(int n, int steps) {
  return pdyn::load_scene(PDYN_BENCH_CLOTH, registry(),
                          {{"particles[0].grid.nx", std::to_string(n)},
                           {"particles[0].grid.ny", std::to_string(n)},
                           {"simulation.steps", std::to_string(steps)}});
}

ClothSpec spec(int n) {
  ClothSpec c;
  c.nx = c.ny = n;
  return c;
}

using OdeState = std::vector<double>;
using Odeint = boost::numeric::odeint::runge_kutta4<OdeState>;

// Odeint over the reference's derivative function.
struct OdeintCloth {
  explicit OdeintCloth(int n) : cloth(spec(n)), y(cloth.state()) {}
  void step(double h) {
    stepper.do_step([this](const OdeState& x, OdeState& dxdt,
                           double) { cloth.derivative(x.data(), dxdt.data()); },
                    y, t, h);
    t += h;
  }
  FusedCloth cloth;
  OdeState y;
  Odeint stepper;
  double t = 0.0;
};

// ---- the same-state check ----

double relative_difference(const double* a, const double* b, std::size_t n) {
  double diff = 0.0, scale = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    diff = std::max(diff, std::abs(a[i] - b[i]));
    scale = std::max(scale, std::abs(b[i]));
  }
  return diff / scale;
}

bool same_state_check(int n, int steps) {
  pdyn::set_threads(pdyn::available_threads());
  pdyn::Scene scene = load_pdyn(n, steps);
  const pdyn::RunResult r = pdyn::run_scene(scene);
  pdyn::Scene direct = load_pdyn(n, steps);
  for (int k = 0; k < steps; ++k) {
    direct.solver->step(*direct.system, kDt);
    direct.system->set_time((k + 1) * kDt);
  }
  FusedCloth fused(spec(n));
  for (int k = 0; k < steps; ++k) fused.step(kDt);
  OdeintCloth ode(n);
  for (int k = 0; k < steps; ++k) ode.step(kDt);
  const double* ref = fused.state().data();
  const std::size_t dim = fused.state().size();
  const double d_run = relative_difference(scene.system->state().data(), ref, dim);
  const double d_step = relative_difference(direct.system->state().data(), ref, dim);
  const double d_ode = relative_difference(ode.y.data(), ref, dim);
  const double moved = relative_difference(ref, FusedCloth(spec(n)).state().data(), dim);
  const bool ok =
      r.exit_code == 0 && d_run <= 1e-12 && d_step <= 1e-12 && d_ode <= 1e-12 && moved > 1e-9;
  std::printf(
      "same state after %d steps, %d x %d: |pdyn_run - fused| = %.3g, |pdyn_step - "
      "fused| = %.3g, |odeint - fused| = %.3g (relative, max-norm; the state moved by "
      "%.3g): %s\n",
      steps, n, n, d_run, d_step, d_ode, moved, ok ? "ok" : "FAILED");
  return ok;
}

// ---- benchmarks ----

void set_counters(benchmark::State& state, int n) {
  const double particles = static_cast<double>(n) * n;
  state.counters["particles"] = particles;
  // Seconds per particle-step; docs/performance.md shows it in ns.
  state.counters["per_particle_step"] = benchmark::Counter(
      particles, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

void BM_pdyn_run(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const int threads = static_cast<int>(state.range(1));
  pdyn::Scene scene = load_pdyn(n, 1);
  pdyn::RunOptions options;
  options.threads = threads;
  for (auto _ : state) {
    // One runner step per iteration: step 1 of a 1-step run from t = 0.
    scene.system->set_time(0.0);
    const pdyn::RunResult r = pdyn::run_scene(scene, options);
    if (r.exit_code != 0) state.SkipWithError(r.message.c_str());
  }
  set_counters(state, n);
}

void BM_pdyn_step(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  pdyn::set_threads(static_cast<int>(state.range(1)));
  pdyn::Scene scene = load_pdyn(n, 1);
  for (auto _ : state) {
    scene.solver->step(*scene.system, kDt);
    scene.system->respond_to_collisions(kDt);
  }
  set_counters(state, n);
}

void BM_fused(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  FusedCloth cloth(spec(n));
  for (auto _ : state) cloth.step(kDt);
  set_counters(state, n);
}

void BM_odeint(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  OdeintCloth ode(n);
  for (auto _ : state) ode.step(kDt);
  set_counters(state, n);
}

void sizes_and_threads(benchmark::internal::Benchmark* b) {
  for (int n : kSizes) {
    for (int t : {1, 2}) b->Args({n, t});
  }
}
void sizes(benchmark::internal::Benchmark* b) {
  for (int n : kSizes) b->Args({n});
}

// Interleaved by size so that variants of one size run close together in
// time (the machine is shared; see docs/performance.md).
BENCHMARK(BM_fused)->Apply(sizes)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(1.0);
BENCHMARK(BM_odeint)->Apply(sizes)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(1.0);
BENCHMARK(BM_pdyn_run)
    ->Apply(sizes_and_threads)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(1.0);
BENCHMARK(BM_pdyn_step)
    ->Apply(sizes_and_threads)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(1.0);

// ---- memory ----

long peak_rss_bytes() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss * 1024L;  // Linux reports KiB
}

int memory(const std::string& variant, int n, int threads) {
  const long before = peak_rss_bytes();
  if (variant == "pdyn") {
    pdyn::Scene scene = load_pdyn(n, 3);
    pdyn::RunOptions options;
    options.threads = threads;
    pdyn::run_scene(scene, options);
  } else if (variant == "fused") {
    FusedCloth cloth(spec(n));
    for (int k = 0; k < 3; ++k) cloth.step(kDt);
  } else {
    std::fprintf(stderr,
                 "pdyn_bench_cloth: --memory %s: unknown variant (expected pdyn or fused)\n",
                 variant.c_str());
    return 2;
  }
  const long peak = peak_rss_bytes();
  const double particles = static_cast<double>(n) * n;
  std::printf(
      "{\"variant\": \"%s\", \"n\": %d, \"threads\": %d, \"peak_rss_bytes\": %ld, "
      "\"baseline_rss_bytes\": %ld, \"bytes_per_particle\": %.1f}\n",
      variant.c_str(), n, threads, peak, before, static_cast<double>(peak) / particles);
  return 0;
}

// ---- load times ----

double seconds_to_load(const std::filesystem::path& file, const std::vector<pdyn::Override>& o) {
  const auto t0 = std::chrono::steady_clock::now();
  pdyn::Scene scene = pdyn::load_scene(file, registry(), o);
  const auto t1 = std::chrono::steady_clock::now();
  benchmark::DoNotOptimize(scene.system->state().data());
  return std::chrono::duration<double>(t1 - t0).count();
}

int load_times() {
  registry();  // plugin discovery is not part of a scene's load time
  double best = 1e30;
  for (int r = 0; r < 3; ++r) {
    best = std::min(best, seconds_to_load(PDYN_BENCH_CLOTH, {{"particles[0].grid.nx", "1000"},
                                                             {"particles[0].grid.ny", "1000"}}));
  }
  std::printf(
      "{\"load\": \"grid 1000 x 1000 (1 000 000 particles, 3 996 002 springs)\", "
      "\"seconds\": %.3f}\n",
      best);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc >= 4 && std::strcmp(argv[1], "--memory") == 0) {
    return memory(argv[2], std::atoi(argv[3]), argc >= 5 ? std::atoi(argv[4]) : 1);
  }
  if (argc >= 2 && std::strcmp(argv[1], "--load") == 0) return load_times();
  benchmark::Initialize(&argc, argv);
  bool ok = true;
  for (int n : kSizes) ok = same_state_check(n, n >= 1000 ? 3 : 10) && ok;
  if (!ok) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
