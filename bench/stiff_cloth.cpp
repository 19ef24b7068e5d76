// Stiff-cloth time to solution (issues 5 and 17): simulate 1 s of
// tests/scenes/shared/stiff_cloth.yaml at one or more grid sizes
//   (a) with rk4 at its largest stable dt, found by bisection, and
//   (b) with implicit_euler at dt = 0.01 s, its linear system solved
//       directly (sparse Cholesky, the default) and, for comparison, by
//       conjugate gradients at each --cg-tolerance,
// and print one Markdown table with a row per size and implicit solve
// (docs/solvers.md). A plain timing program rather than Google Benchmark:
// each configuration is one long run whose wall time and step count are the
// result, and the bisection is part of the measurement.
//
//   pdyn_bench_stiff_cloth [--size N]... [--repeats N] [--duration S]
//                          [--cg-tolerance E]... [--threads T]
//                          [--bisect-steps K] [--rk4-dt S] [--skip-rk4] [--trace]
//
// --size N (repeatable; default 30) is an N x N grid of the same sheet:
// 1 m x 1 m, 1 kg in all (spacing 1/(N-1) m, 1/N^2 kg per particle), springs
// of the same ks = 1e5 N/m. A square lattice's in-plane stiffness per unit
// width is ks / spacing springs times the spacing, i.e. ks whatever the
// spacing, so every size is the same sheet, only finer; its stiffest mode,
// w ~ sqrt(8 ks / m) ~ N sqrt(8e5) rad/s, is what shrinks rk4's step as 1/N.
//
// Accuracy criterion, the same for both solvers: "stable", i.e. the run
// reaches the end with a finite state and no particle farther from its start
// than the cloth's diagonal (the furthest a particle of an inextensible sheet
// pinned at two opposite corners can get from where it started without the
// sheet tearing). rk4's dt is the largest that meets it; implicit_euler meets
// it at any dt, and runs at dt = 0.01 s, the step of Baraff & Witkin's cloth
// (its answer is overdamped there: the table prints how far its final state
// is from rk4's, and docs/solvers.md discusses it).
//
// Every run uses --threads threads (default 1: the implicit solver's linear
// algebra is serial, so one thread compares the methods, not the cores).
// --bisect-steps K (default 0: off) shortens each bisection run to at most K
// steps of its candidate dt: above rk4's limit the stiffest mode grows by a
// few percent a step, so a few thousand steps show it. The timing run then
// covers the whole duration and, should it not be stable, the step is
// lowered by 1% until it is. --rk4-dt S skips the bisection and times rk4 at
// S (with one --size: a step an earlier bisection found).
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <string>
#include <vector>

#include "implicit_euler_solver.hpp"
#include "pdyn/host/registry.hpp"
#include "pdyn/host/runner.hpp"
#include "pdyn/host/scene.hpp"

namespace {

using pdyn::Override;
using pdyn::Scene;

const pdyn::PluginRegistry& registry() {
  static const pdyn::PluginRegistry r = [] {
    pdyn::PluginRegistry reg;
    reg.discover({PDYN_PLUGIN_DIR});
    return reg;
  }();
  return r;
}

Scene load(int size, const std::string& solver, double dt, double duration) {
  const double spacing = 1.0 / (size - 1);  // m
  const double mass = 1.0 / (size * size);  // kg
  return pdyn::load_scene(PDYN_BENCH_SCENE, registry(),
                          {Override{"simulation.solver", "{ type: " + solver + " }"},
                           Override{"simulation.dt", fmt::format("{:.17g}", dt)},
                           Override{"simulation.duration", fmt::format("{:.17g}", duration)},
                           Override{"particles[0].grid.nx", std::to_string(size)},
                           Override{"particles[0].grid.ny", std::to_string(size)},
                           Override{"particles[0].grid.u", fmt::format("[{:.17g}, 0, 0]", spacing)},
                           Override{"particles[0].grid.v", fmt::format("[0, {:.17g}, 0]", spacing)},
                           Override{"particles[0].grid.mass", fmt::format("{:.17g}", mass)}});
}

struct Outcome {
  bool stable = false;
  std::int64_t steps = 0;
  double wall = 0.0;        // s
  double max_travel = 0.0;  // m, largest distance of a particle from its start
  pdyn::Matrix3X x;         // final positions
};

Outcome run(Scene& scene, int threads) {
  const pdyn::Matrix3X x0 = scene.system->positions();
  pdyn::RunOptions options;
  options.threads = threads;
  const auto start = std::chrono::steady_clock::now();
  const pdyn::RunResult r = pdyn::run_scene(scene, options);
  Outcome o;
  o.wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  o.steps = r.steps_done;
  o.x = scene.system->positions();
  o.max_travel = (o.x - x0).colwise().norm().maxCoeff();
  const double diagonal = std::sqrt(2.0);  // m, the 1 m x 1 m sheet's diagonal
  o.stable = r.exit_code == 0 && std::isfinite(o.max_travel) && o.max_travel <= diagonal;
  return o;
}

struct Settings {
  int repeats = 3;
  double duration = 1.0;
  int threads = 1;
  std::int64_t bisect_steps = 0;
  bool trace = false;
};

// (a) rk4: bisection on log(dt) between a stable and an unstable step until
// they differ by less than 0.5%, starting from the 30 x 30 sheet's limit
// (1.1e-4 s) scaled by 30 / N. Returns the stable end.
double largest_stable_rk4_dt(int size, const Settings& s, double* unstable) {
  auto stable = [&](double dt) {
    const double duration = s.bisect_steps > 0
                                ? std::min(s.duration, static_cast<double>(s.bisect_steps) * dt)
                                : s.duration;
    Scene scene = load(size, "rk4", dt, duration);
    const Outcome o = run(scene, s.threads);
    if (s.trace) {
      std::cerr << fmt::format(
          "{} x {}: rk4 dt = {:.6g} s over {:.4g} s: {} (max travel {:.4g} m, "
          "{:.2f} s)\n",
          size, size, dt, duration, o.stable ? "stable" : "unstable", o.max_travel, o.wall);
    }
    return o.stable;
  };
  const double guess = 1.1e-4 * 30.0 / size;
  double lo = guess / 1.25, hi = guess * 1.25;
  while (!stable(lo)) {
    hi = lo;
    lo /= 1.25;
  }
  while (stable(hi)) {
    lo = hi;
    hi *= 1.25;
  }
  while (hi / lo > 1.005) {
    const double mid = std::sqrt(lo * hi);
    (stable(mid) ? lo : hi) = mid;
  }
  *unstable = hi;
  return lo;
}

struct ImplicitOutcome {
  Outcome run;
  bool direct = false;
  double cg_tolerance = 0.0;
  double cg_mean = 0.0;
  std::int64_t cg_max = 0;
  std::size_t factor_blocks = 0;
  double factor_flops = 0.0;  // per factorisation
  double factor_bytes = 0.0;
  double factor_seconds = 0.0;  // all factorisations of the run
  pdyn::solvers::ImplicitEuler::PartSeconds parts;
};

// Reads the built-in implicit_euler's statistics after every step.
class Counting final : public pdyn::Solver {
 public:
  Counting(std::shared_ptr<pdyn::solvers::ImplicitEuler> inner, bool trace)
      : inner_(std::move(inner)), trace_(trace) {}
  void step(pdyn::System& sys, double h) override {
    inner_->step(sys, h);
    max_ = std::max(max_, inner_->last_cg_iterations());
    if (trace_) {
      std::cerr << fmt::format("t = {:.2f} s: {}\n", sys.time(),
                               inner_->last_step_direct()
                                   ? std::string("direct")
                                   : fmt::format("{} CG iterations", inner_->last_cg_iterations()));
    }
  }
  std::int64_t max_iterations() const { return max_; }

 private:
  std::shared_ptr<pdyn::solvers::ImplicitEuler> inner_;
  bool trace_;
  std::int64_t max_ = 0;
};

// (b) implicit_euler, built in to read its statistics. cg_tolerance 0: the
// direct solve.
ImplicitOutcome run_implicit(int size, double dt, double cg_tolerance, const Settings& s,
                             bool trace) {
  Scene scene = load(size, "implicit_euler", dt, s.duration);
  pdyn::solvers::ImplicitEulerOptions options;
  if (cg_tolerance > 0) {
    options.linear_solver = pdyn::solvers::LinearSolver::Cg;
    options.cg_tolerance = cg_tolerance;
  } else {
    options.linear_solver = pdyn::solvers::LinearSolver::Direct;
  }
  auto solver = std::make_shared<pdyn::solvers::ImplicitEuler>(options);
  auto counting = std::make_shared<Counting>(solver, trace);
  scene.solver = counting;
  ImplicitOutcome o;
  o.run = run(scene, s.threads);
  o.direct = solver->last_step_direct();
  o.cg_tolerance = cg_tolerance;
  o.cg_mean = static_cast<double>(solver->total_cg_iterations()) /
              static_cast<double>(std::max<std::int64_t>(1, solver->steps()));
  o.cg_max = counting->max_iterations();
  o.factor_blocks = solver->factor_blocks();
  o.factor_flops = solver->factor_flops();
  o.factor_bytes = solver->factor_bytes();
  o.factor_seconds = solver->factor_seconds();
  o.parts = solver->part_seconds();
  return o;
}

}  // namespace

int main(int argc, char** argv) {
  Settings s;
  std::vector<int> sizes;
  std::vector<double> tolerances;
  bool skip_rk4 = false, tolerances_given = false;
  double given_rk4_dt = 0.0;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--size" && i + 1 < argc) {
      sizes.push_back(std::max(2, std::atoi(argv[++i])));
    } else if (a == "--repeats" && i + 1 < argc) {
      s.repeats = std::max(1, std::atoi(argv[++i]));
    } else if (a == "--duration" && i + 1 < argc) {
      s.duration = std::atof(argv[++i]);
    } else if (a == "--cg-tolerance" && i + 1 < argc) {
      tolerances_given = true;
      const double tol = std::atof(argv[++i]);
      if (tol > 0) tolerances.push_back(tol);  // --cg-tolerance 0: no CG rows
    } else if (a == "--threads" && i + 1 < argc) {
      s.threads = std::max(1, std::atoi(argv[++i]));
    } else if (a == "--bisect-steps" && i + 1 < argc) {
      s.bisect_steps = std::max(0, std::atoi(argv[++i]));
    } else if (a == "--rk4-dt" && i + 1 < argc) {
      given_rk4_dt = std::atof(argv[++i]);
    } else if (a == "--skip-rk4") {
      skip_rk4 = true;
    } else if (a == "--trace") {
      s.trace = true;
    } else {
      std::cerr << "usage: pdyn_bench_stiff_cloth [--size N]... [--repeats N] [--duration S] "
                   "[--cg-tolerance E]... [--threads T] [--bisect-steps K] [--rk4-dt S] "
                   "[--skip-rk4] "
                   "[--trace]\n";
      return 2;
    }
  }
  if (sizes.empty()) sizes = {30};
  if (!tolerances_given) tolerances = {1e-3};
  constexpr double kImplicitDt = 0.01;
  try {
    std::cout << fmt::format(
        "Stiff cloth: 1 m x 1 m, 1 kg, ks = 1e5 N/m, {} s simulated, {} thread(s); best of {} "
        "runs\n\n",
        s.duration, s.threads, s.repeats);
    std::cout << "| size | rk4 dt (s) | rk4 steps | rk4 wall (s) | implicit solve | implicit dt "
                 "(s) | steps | implicit wall (s) | speed-up | max travel rk4 / implicit (m) | "
                 "implicit vs rk4 at the end (m) |\n";
    std::cout << "|---|---|---|---|---|---|---|---|---|---|---|\n";
    bool all_stable = true;
    for (const int size : sizes) {
      std::vector<double> solves = {0.0};  // 0: direct
      solves.insert(solves.end(), tolerances.begin(), tolerances.end());
      std::vector<ImplicitOutcome> implicit;
      for (const double tol : solves) {
        ImplicitOutcome best;
        for (int k = 0; k < s.repeats; ++k) {
          ImplicitOutcome o = run_implicit(size, kImplicitDt, tol, s, s.trace && k == 0);
          if (k == 0 || o.run.wall < best.run.wall) best = std::move(o);
        }
        all_stable = all_stable && best.run.stable;
        implicit.push_back(std::move(best));
      }
      double rk4_dt = 0.0, rk4_unstable = 0.0;
      Outcome rk4;
      if (!skip_rk4) {
        rk4_dt = given_rk4_dt > 0 ? given_rk4_dt : largest_stable_rk4_dt(size, s, &rk4_unstable);
        for (int k = 0; k < s.repeats; ++k) {
          Scene scene = load(size, "rk4", rk4_dt, s.duration);
          Outcome o = run(scene, s.threads);
          if (!o.stable) {  // only possible with --bisect-steps
            rk4_dt *= 0.99;
            rk4_unstable = rk4_dt / 0.99;
            k = -1;
            continue;
          }
          if (k == 0 || o.wall < rk4.wall) rk4 = std::move(o);
        }
      }
      for (const ImplicitOutcome& o : implicit) {
        // Where the rest of the time goes: the profile printed with a miss.
        const auto share = [&o](double seconds) { return 100.0 * seconds / o.run.wall; };
        const std::string rest =
            fmt::format("Jacobians {:.0f}%, forces {:.0f}%, solve {:.0f}%, analysis {:.0f}%",
                        share(o.parts.jacobians), share(o.parts.forces), share(o.parts.solve),
                        share(o.parts.analysis));
        const std::string solve =
            o.direct
                ? fmt::format(
                      "direct LL^T ({} blocks in L, {:.3f} GB; factorising {:.0f}% of the "
                      "time, {:.1f} GFlop/s; {})",
                      o.factor_blocks, o.factor_bytes * 1e-9, share(o.factor_seconds),
                      o.factor_flops * static_cast<double>(o.run.steps) / o.factor_seconds * 1e-9,
                      rest)
                : fmt::format("CG {:g} ({:.0f} / {} iterations per step; {})", o.cg_tolerance,
                              o.cg_mean, o.cg_max, rest);
        const std::string vs_rk4 =
            skip_rk4 ? "-" : fmt::format("{:.3f}", (o.run.x - rk4.x).colwise().norm().maxCoeff());
        std::cout << fmt::format(
            "| {} x {} | {} | {} | {} | {} | {:.4g} | {} | {:.3f} | {} | {} / {:.3f} | {} |\n",
            size, size, skip_rk4 ? "-" : fmt::format("{:.4g}", rk4_dt),
            skip_rk4 ? "-" : std::to_string(rk4.steps),
            skip_rk4 ? "-" : fmt::format("{:.3f}", rk4.wall), solve, kImplicitDt, o.run.steps,
            o.run.wall, skip_rk4 ? "-" : fmt::format("{:.1f}x", rk4.wall / o.run.wall),
            skip_rk4 ? "-" : fmt::format("{:.3f}", rk4.max_travel), o.run.max_travel, vs_rk4);
      }
      if (!skip_rk4 && rk4_unstable > 0) {
        std::cerr << fmt::format("{} x {}: rk4 is unstable at dt = {:.4g} s\n", size, size,
                                 rk4_unstable);
      }
      std::cout.flush();
    }
    return all_stable ? 0 : 1;
  } catch (const std::exception& e) {
    std::cerr << "pdyn_bench_stiff_cloth: " << e.what() << "\n";
    return 1;
  }
}
