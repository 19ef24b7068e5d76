// Hanging-cloth throughput (issue 4): ns per particle-step of
//   pdyn_run     pdyn as a user assembles it: tests/scenes/shared/cloth.yaml loaded
//                with its plugins, stepped by the runner (run_scene, with its
//                per-step fault checks), 1 and 2 threads;
//   pdyn_step    the same scene stepped by calling the solver directly (the
//                runner's checks left out), to show what they cost;
//   fused        the hand-fused reference, bench/fused_cloth.hpp;
//   odeint       Boost.Odeint's runge_kutta4 over the reference's derivative;
// at 32 x 32, 100 x 100, 316 x 316 and 1000 x 1000 particles. Before timing, all
// variants take the same steps from the same state and must agree to a
// relative 1e-12 (2-norm over the state), or the program exits with status 1.
//
//   pdyn_bench_cloth [google benchmark flags, e.g. --benchmark_out=x.json]
//   pdyn_bench_cloth --memory pdyn|fused N   peak RSS of an N x N cloth after
//                                            3 steps (run each in its own process)
//   pdyn_bench_cloth --load                  scene load times
//   pdyn_bench_cloth --run VARIANT N STEPS [THREADS]   just step (for callgrind)
//   pdyn_bench_cloth --pairs ROUNDS [N ...]  issue 17's targets, side by side:
//                                            fused, pdyn run 1 thread and 2
//                                            threads in turn, ROUNDS times per
//                                            size: each ratio's median and
//                                            interquartile range
//
// scripts/bench.sh runs all three (docs/performance.md; its dated figures:
// docs/log/performance.md).
#include <benchmark/benchmark.h>
#include <fmt/format.h>
#include <sys/resource.h>

#include <algorithm>
#include <boost/numeric/odeint/stepper/runge_kutta4.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <pdyn/parallel.hpp>
#include <string>
#include <utility>
#include <vector>

#include "fused_cloth.hpp"
#include "pdyn/host/registry.hpp"
#include "pdyn/host/runner.hpp"
#include "pdyn/host/scene.hpp"
#include "pdyn/host/side_files.hpp"
#include "pdyn/host/stepper.hpp"
#include "pdyn/host/threads.hpp"
#include "stream_triad.hpp"

namespace {

using pdyn::bench::ClothSpec;
using pdyn::bench::FusedCloth;

constexpr double kDt = 0.0002;  // s, tests/scenes/shared/cloth.yaml's
const int kSizes[] = {32, 100, 316, 1000};

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

// ||a - b|| / ||b|| in the 2-norm over the whole state (6N).
double relative_difference(const double* a, const double* b, std::size_t n) {
  double diff = 0.0, scale = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    diff += (a[i] - b[i]) * (a[i] - b[i]);
    scale += b[i] * b[i];
  }
  return std::sqrt(diff / scale);
}

// The largest difference of one element relative to the largest element,
// printed alongside: where the variants' roundings drift apart most.
double max_relative_difference(const double* a, const double* b, std::size_t n) {
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
  pdyn::Stepper direct_stepper(*direct.system, *direct.solver, direct.solver_label);
  for (int k = 0; k < steps; ++k) {
    if (!direct_stepper.step_to((k + 1) * kDt)) return false;
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
  const double d_ode_max = max_relative_difference(ode.y.data(), ref, dim);
  const bool ok =
      r.exit_code == 0 && d_run <= 1e-12 && d_step <= 1e-12 && d_ode <= 1e-12 && moved > 1e-9;
  std::printf(
      "same state after %d steps, %d x %d: |pdyn_run - fused| = %.3g, |pdyn_step - "
      "fused| = %.3g, |odeint - fused| = %.3g (relative, 2-norm; odeint's max-norm %.3g; the "
      "state moved by %.3g): %s\n",
      steps, n, n, d_run, d_step, d_ode, d_ode_max, moved, ok ? "ok" : "FAILED");
  return ok;
}

// ---- benchmarks ----

// `steps` steps per benchmark iteration.
void set_counters(benchmark::State& state, int n, int steps = 1) {
  const double particles = static_cast<double>(n) * n;
  state.counters["particles"] = particles;
  // Seconds per particle-step; docs/performance.md shows it in ns.
  state.counters["per_particle_step"] =
      benchmark::Counter(particles * steps, benchmark::Counter::kIsIterationInvariantRate |
                                                benchmark::Counter::kInvert);
}

// Steps of one pdyn_run iteration: a run long enough (2e7 particle-steps,
// 20 to 400 steps) that the runner's set-up per run (threads, output list,
// the energy check's first evaluation) weighs little, as in a real run.
int run_steps(int n) { return std::clamp(20'000'000 / (n * n), 20, 400); }

void BM_pdyn_run(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const int threads = static_cast<int>(state.range(1));
  const int steps = run_steps(n);
  pdyn::Scene scene = load_pdyn(n, steps);
  const Eigen::VectorXd start = std::as_const(*scene.system).state();
  pdyn::RunOptions options;
  options.threads = threads;
  for (auto _ : state) {
    // A whole run of `steps` steps from the same start.
    scene.system->set_state(start);
    scene.system->set_time(0.0);
    const pdyn::RunResult r = pdyn::run_scene(scene, options);
    if (r.exit_code != 0) state.SkipWithError(r.message.c_str());
  }
  set_counters(state, n, steps);
}

void BM_pdyn_step(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  pdyn::set_threads(static_cast<int>(state.range(1)));
  pdyn::Scene scene = load_pdyn(n, 1);
  pdyn::Stepper stepper(*scene.system, *scene.solver, scene.solver_label);
  for (auto _ : state) {
    if (!stepper.step(kDt)) state.SkipWithError(stepper.fault().what.c_str());
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

// The 316 x 316 cloth (99 856 particles, 397 530 springs) written out as a
// scene with CSV side files and as one with the same data inline in YAML.
void write_bulk_scenes(const std::filesystem::path& dir) {
  std::filesystem::create_directories(dir);
  pdyn::Scene cloth = load_pdyn(316, 1);
  const pdyn::System& sys = *cloth.system;
  pdyn::side_files::ParticleRows rows;
  std::vector<pdyn::IndexPair> pairs;
  for (pdyn::Index i = 0; i < sys.size(); ++i) {
    rows.x.push_back(sys.positions().col(i));
    rows.v.push_back(sys.velocities().col(i));
    rows.mass.push_back(sys.masses()(i));
    rows.fixed.push_back(sys.fixed()[static_cast<std::size_t>(i)]);
  }
  for (int j = 0; j < 316; ++j) {
    for (int i = 0; i < 316; ++i) {
      const pdyn::Index a = j * 316 + i;
      if (i + 1 < 316) pairs.push_back({a, a + 1});
      if (j + 1 < 316) pairs.push_back({a, a + 316});
      if (i + 1 < 316 && j + 1 < 316) {
        pairs.push_back({a, a + 317});
        pairs.push_back({a + 1, a + 316});
      }
    }
  }
  pdyn::side_files::write_particles(dir / "cloth.csv", rows);
  pdyn::side_files::write_pairs(dir / "springs.csv", pairs);
  const std::string head = "simulation: { dt: 0.0002, steps: 1 }\n";
  const std::string tail = "  - { type: gravity }\n";
  std::ofstream(dir / "side.yaml") << head << "particles:\n  - file: cloth.csv\nforces:\n"
                                   << "  - { type: spring, ks: 1000, kd: 0.02, pairs: { file: "
                                      "springs.csv } }\n"
                                   << tail;
  std::ofstream inl(dir / "inline.yaml");
  inl << head << "particles:\n";
  for (std::size_t i = 0; i < rows.x.size(); ++i) {
    inl << fmt::format(
        "  - {{ position: [{:.17g}, {:.17g}, {:.17g}], velocity: [{:.17g}, "
        "{:.17g}, {:.17g}], mass: {:.17g}, fixed: {} }}\n",
        rows.x[i].x(), rows.x[i].y(), rows.x[i].z(), rows.v[i].x(), rows.v[i].y(), rows.v[i].z(),
        rows.mass[i], rows.fixed[i] ? "true" : "false");
  }
  inl << "forces:\n  - type: spring\n    ks: 1000\n    kd: 0.02\n    pairs: [";
  for (std::size_t s = 0; s < pairs.size(); ++s) {
    inl << (s ? ", " : "") << "[" << pairs[s][0] << ", " << pairs[s][1] << "]";
  }
  inl << "]\n" << tail;
}

int load_times() {
  registry();  // plugin discovery is not part of a scene's load time
  auto best_of = [](int repeats, auto&& load) {
    double best = 1e30;
    for (int r = 0; r < repeats; ++r) best = std::min(best, load());
    return best;
  };
  const double grid = best_of(3, [] {
    return seconds_to_load(PDYN_BENCH_CLOTH,
                           {{"particles[0].grid.nx", "1000"}, {"particles[0].grid.ny", "1000"}});
  });
  std::printf(
      "{\"load\": \"grid builder, 1000 x 1000 (1 000 000 particles, 3 996 002 "
      "springs)\", \"seconds\": %.3f}\n",
      grid);
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "pdyn_bench_load";
  write_bulk_scenes(dir);
  const double side = best_of(3, [&] { return seconds_to_load(dir / "side.yaml", {}); });
  std::printf(
      "{\"load\": \"CSV side files, 99 856 particles + 397 530 springs\", "
      "\"seconds\": %.3f}\n",
      side);
  const double inline_yaml = best_of(1, [&] { return seconds_to_load(dir / "inline.yaml", {}); });
  std::printf("{\"load\": \"the same inline in YAML\", \"seconds\": %.3f}\n", inline_yaml);
  std::filesystem::remove_all(dir);
  return 0;
}

// ---- side by side (issue 17, items 1 to 3) ----

// The q-quantile of v (0.5: the median), interpolated between order statistics.
double quantile(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  const double at = q * static_cast<double>(v.size() - 1);
  const std::size_t lo = static_cast<std::size_t>(at);
  const std::size_t hi = std::min(lo + 1, v.size() - 1);
  return v[lo] + (at - static_cast<double>(lo)) * (v[hi] - v[lo]);
}
double median(const std::vector<double>& v) { return quantile(v, 0.5); }

template <class F>
double seconds_of(F&& f) {
  const auto t0 = std::chrono::steady_clock::now();
  f();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// The three variants run in turn, round after round, so that the machine's
// drift (a hypervisor may take half the CPU for seconds) hits all three
// alike, and each ratio is taken within its round. A round runs each for
// 5e6 particle-steps (at least 10 steps, about half a second): short, so
// that many rounds fit and a slow spell spoils few of them, long enough
// that the runner's set-up (the energy check's first potential) weighs
// about 1%. Each round also times STREAM's triad on 1 thread just before the
// 1-thread run and on 2 just after the 2-thread one: the speed-up over the
// triad's, in the same minute, is issue 32's alternative target (the second
// core of this machine comes and goes). The median is quoted with the
// interquartile range.
int pairs(int rounds, const std::vector<int>& sizes) {
  const bool ok = std::all_of(sizes.begin(), sizes.end(),
                              [](int n) { return same_state_check(n, n >= 1000 ? 3 : 10); });
  if (!ok || rounds < 1) return 1;
  std::printf(
      "\n| size | steps | fused, ns | pdyn run 1 thread, ns | ratio (target <= 1.05; <= 1.0 at "
      "1000) | pdyn 2 threads, ns | speed-up (target >= 1.8 at 316, 1000) | triad 2 threads / 1 | "
      "speed-up / triad's |\n|---|---|---|---|---|---|---|---|---|\n");
  // 3 x 64 MiB: far beyond the caches, about 20 ms a round on 1 thread.
  pdyn::bench::StreamTriad triad(64);
  for (int n : sizes) {
    const int steps = std::max(10, 5'000'000 / (n * n));
    FusedCloth fused(spec(n));
    const std::vector<double> fused_start = fused.state();
    pdyn::Scene scene = load_pdyn(n, steps);
    const Eigen::VectorXd start = std::as_const(*scene.system).state();
    auto run = [&](int threads) {
      scene.system->set_state(start);
      scene.system->set_time(0.0);
      pdyn::RunOptions options;
      options.threads = threads;
      if (pdyn::run_scene(scene, options).exit_code != 0) std::exit(1);
    };
    std::vector<double> tf, t1, t2, r1, r2, rt, rs;
    for (int r = 0; r < rounds; ++r) {
      auto time_fused = [&] {
        fused.state() = fused_start;
        tf.push_back(seconds_of([&] {
          for (int k = 0; k < steps; ++k) fused.step(kDt);
        }));
      };
      // Odd rounds reverse the order, so that whatever the machine does
      // after a 2-thread run (or before a 1-thread one) falls on both.
      if (r % 2 == 0) time_fused();
      const double triad1 = triad.seconds(1, 3);
      t1.push_back(seconds_of([&] { run(1); }));
      if (r % 2 == 1) time_fused();
      t2.push_back(seconds_of([&] { run(2); }));
      const double triad2 = triad.seconds(2, 3);
      r1.push_back(t1.back() / tf.back());
      r2.push_back(t1.back() / t2.back());
      rt.push_back(triad1 / triad2);
      rs.push_back(r2.back() / rt.back());
    }
    const double per = 1e9 / (static_cast<double>(n) * n * steps);
    std::printf(
        "| %d x %d | %d | %.1f | %.1f | %.3f (%.3f-%.3f) | %.1f | %.2f (%.2f-%.2f) | %.2f "
        "(%.2f-%.2f) | %.2f (%.2f-%.2f) |\n",
        n, n, steps, median(tf) * per, median(t1) * per, median(r1), quantile(r1, 0.25),
        quantile(r1, 0.75), median(t2) * per, median(r2), quantile(r2, 0.25), quantile(r2, 0.75),
        median(rt), quantile(rt, 0.25), quantile(rt, 0.75), median(rs), quantile(rs, 0.25),
        quantile(rs, 0.75));
    std::fflush(stdout);
  }
  return 0;
}

}  // namespace

// Steps one variant without timing it, for instruction counts:
// valgrind --tool=callgrind pdyn_bench_cloth --run VARIANT N STEPS, at two
// step counts; the difference is the cost of the extra steps alone.
int run_only(const std::string& variant, int n, int steps, int threads) {
  if (variant == "pdyn_run") {
    pdyn::Scene scene = load_pdyn(n, steps);
    pdyn::RunOptions options;
    options.threads = threads;
    return pdyn::run_scene(scene, options).exit_code;
  }
  if (variant == "pdyn_step") {
    pdyn::set_threads(threads);
    pdyn::Scene scene = load_pdyn(n, steps);
    pdyn::Stepper stepper(*scene.system, *scene.solver, scene.solver_label);
    for (int k = 0; k < steps; ++k) {
      if (!stepper.step(kDt)) return 1;
    }
    return 0;
  }
  if (variant == "fused") {
    FusedCloth cloth(spec(n));
    for (int k = 0; k < steps; ++k) cloth.step(kDt);
    return 0;
  }
  if (variant == "odeint") {
    OdeintCloth ode(n);
    for (int k = 0; k < steps; ++k) ode.step(kDt);
    return 0;
  }
  std::fprintf(stderr,
               "pdyn_bench_cloth: --run %s: unknown variant (expected pdyn_run, "
               "pdyn_step, fused or odeint)\n",
               variant.c_str());
  return 2;
}

int main(int argc, char** argv) {
  if (argc >= 5 && std::strcmp(argv[1], "--run") == 0) {
    return run_only(argv[2], std::atoi(argv[3]), std::atoi(argv[4]),
                    argc >= 6 ? std::atoi(argv[5]) : 1);
  }
  if (argc >= 4 && std::strcmp(argv[1], "--memory") == 0) {
    return memory(argv[2], std::atoi(argv[3]), argc >= 5 ? std::atoi(argv[4]) : 1);
  }
  if (argc >= 2 && std::strcmp(argv[1], "--load") == 0) return load_times();
  if (argc >= 3 && std::strcmp(argv[1], "--pairs") == 0) {
    std::vector<int> sizes;
    for (int a = 3; a < argc; ++a) sizes.push_back(std::atoi(argv[a]));
    if (sizes.empty()) sizes.assign(std::begin(kSizes), std::end(kSizes));
    return pairs(std::atoi(argv[2]), sizes);
  }
  benchmark::Initialize(&argc, argv);
  bool ok = true;
  for (int n : kSizes) ok = same_state_check(n, n >= 1000 ? 3 : 10) && ok;
  if (!ok) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
