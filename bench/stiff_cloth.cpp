// Stiff-cloth time to solution (issue 5): simulate 1 s of tests/scenes/shared/stiff_cloth.yaml
//   (a) with rk4 at its largest stable dt, found by bisection, and
//   (b) with implicit_euler at dt = 0.01 s,
// and print wall time, steps and CG iterations per step as a Markdown table
// (docs/solvers.md). A plain timing program rather than Google Benchmark:
// each configuration is one long run whose wall time, step count and CG
// statistics are the result, and the bisection is part of the measurement.
//
//   pdyn_bench_stiff_cloth [--repeats N] [--duration S] [--cg-tolerance E]...
//                          [--skip-rk4] [--trace]
//
// Each --cg-tolerance adds an implicit_euler row (default: the solver's
// default and 1e-6).
//
// "Stable" means the run reached the end with a finite state and no particle
// farther from its start than the cloth's diagonal (the furthest a particle
// of an inextensible sheet pinned at a corner can get from where it started
// without the sheet tearing).
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

Scene load(const std::string& solver, double dt, double duration) {
  return pdyn::load_scene(PDYN_BENCH_SCENE, registry(),
                          {Override{"simulation.solver", "{ type: " + solver + " }"},
                           Override{"simulation.dt", fmt::format("{:.17g}", dt)},
                           Override{"simulation.duration", fmt::format("{:.17g}", duration)}});
}

struct Outcome {
  bool stable = false;
  std::int64_t steps = 0;
  double wall = 0.0;        // s
  double max_travel = 0.0;  // m, largest distance of a particle from its start
};

Outcome run(Scene& scene) {
  const pdyn::Matrix3X x0 = scene.system->positions();
  const auto start = std::chrono::steady_clock::now();
  const pdyn::RunResult r = pdyn::run_scene(scene);
  Outcome o;
  o.wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  o.steps = r.steps_done;
  o.max_travel = (scene.system->positions() - x0).colwise().norm().maxCoeff();
  const double diagonal = std::sqrt(2.0);  // m, the 1 m x 1 m sheet's diagonal
  o.stable = r.exit_code == 0 && std::isfinite(o.max_travel) && o.max_travel <= diagonal;
  return o;
}

// (a) rk4: bisection on log(dt) between a stable and an unstable step,
// until they differ by less than 0.5%. Returns the stable end.
double largest_stable_rk4_dt(double duration, double* unstable, bool trace) {
  double lo = 1e-5, hi = 1e-2;
  for (;;) {
    Scene s = load("rk4", lo, duration);
    if (run(s).stable) break;
    lo /= 2;
  }
  while (hi / lo > 1.005) {
    const double mid = std::sqrt(lo * hi);
    Scene s = load("rk4", mid, duration);
    const Outcome o = run(s);
    if (trace) {
      std::cerr << fmt::format("rk4 dt = {:.6g} s: {} (max travel {:.4g} m)\n", mid,
                               o.stable ? "stable" : "unstable", o.max_travel);
    }
    (o.stable ? lo : hi) = mid;
  }
  *unstable = hi;
  return lo;
}

// Counts CG iterations per step of the built-in implicit_euler.
class Counting final : public pdyn::Solver {
 public:
  Counting(std::shared_ptr<pdyn::solvers::ImplicitEuler> inner, bool trace)
      : inner_(std::move(inner)), trace_(trace) {}
  void step(pdyn::System& sys, double h) override {
    inner_->step(sys, h);
    max_ = std::max(max_, inner_->last_cg_iterations());
    if (trace_) {
      std::cerr << fmt::format("t = {:.2f} s: {} CG iterations\n", sys.time(),
                               inner_->last_cg_iterations());
    }
  }
  std::int64_t max_iterations() const { return max_; }

 private:
  std::shared_ptr<pdyn::solvers::ImplicitEuler> inner_;
  bool trace_;
  std::int64_t max_ = 0;
};

struct ImplicitOutcome {
  Outcome run;
  double cg_mean = 0.0;
  std::int64_t cg_max = 0;
};

// (b) implicit_euler, built in to read its CG counts.
ImplicitOutcome run_implicit(double dt, double duration, double cg_tolerance, bool trace) {
  Scene s = load("implicit_euler", dt, duration);
  pdyn::solvers::ImplicitEulerOptions options;
  options.cg_tolerance = cg_tolerance;
  auto solver = std::make_shared<pdyn::solvers::ImplicitEuler>(options);
  auto counting = std::make_shared<Counting>(solver, trace);
  s.solver = counting;
  ImplicitOutcome o;
  o.run = run(s);
  o.cg_mean = static_cast<double>(solver->total_cg_iterations()) /
              static_cast<double>(std::max<std::int64_t>(1, solver->steps()));
  o.cg_max = counting->max_iterations();
  return o;
}

}  // namespace

int main(int argc, char** argv) {
  int repeats = 3;
  double duration = 1.0;
  std::vector<double> tolerances;
  bool trace = false, skip_rk4 = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--repeats" && i + 1 < argc) {
      repeats = std::max(1, std::atoi(argv[++i]));
    } else if (a == "--duration" && i + 1 < argc) {
      duration = std::atof(argv[++i]);
    } else if (a == "--cg-tolerance" && i + 1 < argc) {
      tolerances.push_back(std::atof(argv[++i]));
    } else if (a == "--skip-rk4") {
      skip_rk4 = true;
    } else if (a == "--trace") {
      trace = true;
    } else {
      std::cerr << "usage: pdyn_bench_stiff_cloth [--repeats N] [--duration S] "
                   "[--cg-tolerance E] [--skip-rk4] [--trace]\n";
      return 2;
    }
  }
  if (tolerances.empty()) tolerances = {pdyn::solvers::ImplicitEulerOptions{}.cg_tolerance, 1e-6};
  try {
    constexpr double kImplicitDt = 0.01;
    std::vector<ImplicitOutcome> implicit;
    for (const double tol : tolerances) {
      ImplicitOutcome best;
      for (int k = 0; k < repeats; ++k) {
        const ImplicitOutcome o = run_implicit(kImplicitDt, duration, tol, trace && k == 0);
        if (k == 0 || o.run.wall < best.run.wall) best = o;
      }
      implicit.push_back(best);
    }
    double rk4_dt = 0.0, rk4_unstable = 0.0;
    Outcome rk4;
    if (!skip_rk4) {
      rk4_dt = largest_stable_rk4_dt(duration, &rk4_unstable, trace);
      for (int k = 0; k < repeats; ++k) {
        Scene s = load("rk4", rk4_dt, duration);
        const Outcome o = run(s);
        if (k == 0 || o.wall < rk4.wall) rk4 = o;
      }
    }

    std::cout << fmt::format(
        "Stiff cloth: 30 x 30 particles, ks = 1e5 N/m, {} s simulated; best of {} runs\n\n",
        duration, repeats);
    std::cout << "| solver | dt (s) | steps | CG iterations per step (mean / max) | wall time (s) "
                 "| max travel (m) |\n";
    std::cout << "|---|---|---|---|---|---|\n";
    if (!skip_rk4) {
      std::cout << fmt::format("| rk4, largest stable dt | {:.4g} | {} | - | {:.3f} | {:.3f} |\n",
                               rk4_dt, rk4.steps, rk4.wall, rk4.max_travel);
    }
    bool all_stable = true;
    for (std::size_t i = 0; i < implicit.size(); ++i) {
      const ImplicitOutcome& o = implicit[i];
      all_stable = all_stable && o.run.stable;
      std::cout << fmt::format(
          "| implicit_euler, cg_tolerance {:g} | {:.4g} | {} | {:.1f} / {} | {:.3f} | {:.3f} |\n",
          tolerances[i], kImplicitDt, o.run.steps, o.cg_mean, o.cg_max, o.run.wall,
          o.run.max_travel);
    }
    if (!skip_rk4) {
      std::cout << fmt::format("\nrk4 is unstable at dt = {:.4g} s\n", rk4_unstable);
      for (std::size_t i = 0; i < implicit.size(); ++i) {
        std::cout << fmt::format(
            "implicit_euler (cg_tolerance {:g}) is {:.1f}x faster than rk4 (goal: >= 5x)\n",
            tolerances[i], rk4.wall / implicit[i].run.wall);
      }
    }
    return all_stable ? 0 : 1;
  } catch (const std::exception& e) {
    std::cerr << "pdyn_bench_stiff_cloth: " << e.what() << "\n";
    return 1;
  }
}
