// Stiff-cloth time to solution (issues 5 and 17): simulate 1 s of
// tests/scenes/shared/stiff_cloth.yaml at one or more grid sizes
//   (a) with rk4 at its largest stable dt, found by bisection, and
//   (b) with implicit_euler at dt = 0.01 s, its linear system solved
//       directly (sparse Cholesky, the default) and, for comparison, by
//       conjugate gradients at each --cg-tolerance,
// and print one Markdown table with a row per size and implicit solve
// (docs/solvers.md). With --llt, then (c) one more implicit_euler run per
// size whose linear system of every step is factorised and solved again,
// by the hand-written supernodal Cholesky and by Eigen's SimplicialLLT, each
// timed, in a second table (docs/solvers.md, "The direct solve against a
// library"). A plain timing program rather than Google Benchmark: each
// configuration is one long run whose wall time and step count are the
// result, and the bisection is part of the measurement.
//
//   pdyn_bench_stiff_cloth [--size N]... [--repeats N] [--duration S]
//                          [--cg-tolerance E]... [--threads T]
//                          [--bisect-steps K] [--rk4-dt S] [--skip-rk4]
//                          [--llt] [--trace]
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

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "implicit_euler_solver.hpp"
#include "pdyn/error.hpp"
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

// (c) The implicit step's linear solve done twice more after each direct
// step of implicit_euler, on the step's own matrix A and right side b: by a
// second SupernodalCholesky (the solver's own code, timed here as the
// library is, so that both see the same matrices in the same state of the
// caches) and by Eigen's SimplicialLLT on the scalar matrix (its default
// ordering, AMD on the 3n x 3n pattern; its lower triangle only). Each
// analyses the pattern once and factorises and solves at every step; which
// goes first alternates from step to step.
struct SolveTimes {
  struct Seconds {
    double analysis = 0.0, factor = 0.0, solve = 0.0;  // s, summed over the steps
  };
  Seconds supernodal, llt;
  std::int64_t steps = 0;
  Eigen::Index unknowns = 0;
  double supernodal_nonzeros = 0.0, llt_nonzeros = 0.0;  // scalar entries of L
  double difference = 0.0;     // max over steps of |x_llt - x| / |x| (max norms)
  bool same_as_solver = true;  // the second SupernodalCholesky gave the solver's dv, bit for bit
};

class SolveComparison final : public pdyn::Solver {
 public:
  SolveTimes t;

  explicit SolveComparison(std::shared_ptr<pdyn::solvers::ImplicitEuler> inner)
      : inner_(std::move(inner)) {}

  void step(pdyn::System& sys, double h) override {
    inner_->step(sys, h);
    if (!inner_->last_step_direct()) throw pdyn::Error("--llt: the step was not solved directly");
    const auto a = inner_->linear_system();
    if (a.free.empty()) return;
    if (a.row_start != row_start_ || a.col != col_) analyze(a);
    load(a);
    if (t.steps % 2 == 0) {
      factor_supernodal(a);
      factor_llt();
    } else {
      factor_llt();
      factor_supernodal(a);
    }
    check(a);
    ++t.steps;
  }

 private:
  static double since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }

  // Both factorisations' symbolic analysis, and where each entry of A's
  // lower triangle goes among matrix_'s values.
  void analyze(const pdyn::solvers::ImplicitEuler::LinearSystem& a) {
    row_start_ = a.row_start;
    col_ = a.col;
    t.unknowns = 3 * static_cast<Eigen::Index>(a.free.size());
    auto start = std::chrono::steady_clock::now();
    cholesky_.analyze(a.free, a.compact, a.row_start, a.col);
    t.supernodal.analysis += since(start);
    // The blocks below the diagonal, and the diagonal blocks' lower triangles.
    t.supernodal_nonzeros = 9.0 * static_cast<double>(cholesky_.factor_blocks()) +
                            6.0 * static_cast<double>(a.free.size());
    std::vector<Eigen::Triplet<double, Eigen::Index>> entries;
    for_each_entry(
        a, [&](Eigen::Index r, Eigen::Index c, double) { entries.emplace_back(r, c, 1.0); });
    matrix_.resize(t.unknowns, t.unknowns);
    matrix_.setFromTriplets(entries.begin(), entries.end());
    position_.clear();
    for_each_entry(a, [&](Eigen::Index r, Eigen::Index c, double) {
      const auto* begin = matrix_.innerIndexPtr() + matrix_.outerIndexPtr()[c];
      const auto* end = matrix_.innerIndexPtr() + matrix_.outerIndexPtr()[c + 1];
      position_.push_back(std::lower_bound(begin, end, static_cast<int>(r)) -
                          matrix_.innerIndexPtr());
    });
    start = std::chrono::steady_clock::now();
    llt_.analyzePattern(matrix_);
    t.llt.analysis += since(start);
  }

  // visit(r, c, value) for each entry of A's lower triangle, at scalar row
  // r and column c of the free particles' unknowns, in a fixed order.
  template <class Visit>
  static void for_each_entry(const pdyn::solvers::ImplicitEuler::LinearSystem& a, Visit&& visit) {
    for (std::size_t row = 0; row < a.free.size(); ++row) {
      const pdyn::Index i = a.free[row];
      for (pdyn::Index s = a.row_start[i]; s < a.row_start[i + 1]; ++s) {
        const auto column = static_cast<Eigen::Index>(a.compact[a.col[s]]);
        for (int cc = 0; cc < 3; ++cc) {
          for (int rr = 0; rr < 3; ++rr) {
            const Eigen::Index r = 3 * static_cast<Eigen::Index>(row) + rr, c = 3 * column + cc;
            if (r >= c) visit(r, c, a.val[s](rr, cc));
          }
        }
      }
    }
  }

  // A's values into matrix_ and b's into b_ (not timed: a caller of the
  // library would have assembled them so).
  void load(const pdyn::solvers::ImplicitEuler::LinearSystem& a) {
    double* values = matrix_.valuePtr();
    std::size_t k = 0;
    for_each_entry(a, [&](Eigen::Index, Eigen::Index, double v) { values[position_[k++]] = v; });
    b_.resize(t.unknowns);
    for (std::size_t row = 0; row < a.free.size(); ++row) {
      b_.segment<3>(3 * static_cast<Eigen::Index>(row)) = a.b.segment<3>(3 * a.free[row]);
    }
  }

  void factor_supernodal(const pdyn::solvers::ImplicitEuler::LinearSystem& a) {
    auto start = std::chrono::steady_clock::now();
    if (cholesky_.factorize(a.val) >= 0) throw pdyn::Error("--llt: A is not positive definite");
    t.supernodal.factor += since(start);
    x_.setZero(a.b.size());
    start = std::chrono::steady_clock::now();
    cholesky_.solve(a.b, x_);
    t.supernodal.solve += since(start);
  }

  void factor_llt() {
    auto start = std::chrono::steady_clock::now();
    llt_.factorize(matrix_);
    t.llt.factor += since(start);
    if (llt_.info() != Eigen::Success) throw pdyn::Error("--llt: SimplicialLLT failed");
    start = std::chrono::steady_clock::now();
    x_llt_ = llt_.solve(b_);
    t.llt.solve += since(start);
    t.llt_nonzeros = static_cast<double>(llt_.matrixL().nestedExpression().nonZeros());
  }

  // The two answers against each other and the second supernodal one
  // against the solver's.
  void check(const pdyn::solvers::ImplicitEuler::LinearSystem& a) {
    double scale = 0.0, worst = 0.0;
    for (std::size_t row = 0; row < a.free.size(); ++row) {
      const auto k = 3 * static_cast<Eigen::Index>(row);
      const Eigen::Vector3d x = x_.segment<3>(3 * a.free[row]);
      t.same_as_solver = t.same_as_solver && x == a.dv.segment<3>(3 * a.free[row]);
      scale = std::max(scale, x.lpNorm<Eigen::Infinity>());
      worst = std::max(worst, (x_llt_.segment<3>(k) - x).lpNorm<Eigen::Infinity>());
    }
    if (scale > 0.0) t.difference = std::max(t.difference, worst / scale);
  }

  std::shared_ptr<pdyn::solvers::ImplicitEuler> inner_;
  std::vector<pdyn::Index> row_start_, col_;  // the pattern analysed
  pdyn::solvers::detail::SupernodalCholesky cholesky_;
  Eigen::SimplicialLLT<Eigen::SparseMatrix<double>, Eigen::Lower> llt_;
  Eigen::SparseMatrix<double> matrix_;    // A's lower triangle, scalar
  std::vector<std::ptrdiff_t> position_;  // entry k of for_each_entry -> matrix_'s value
  Eigen::VectorXd b_, x_, x_llt_;
};

// One implicit_euler run at dt = 0.01 s, its linear solves compared (c).
SolveTimes compare_solves(int size, const Settings& s) {
  Scene scene = load(size, "implicit_euler", 0.01, s.duration);
  pdyn::solvers::ImplicitEulerOptions options;
  options.linear_solver = pdyn::solvers::LinearSolver::Direct;
  auto comparison =
      std::make_shared<SolveComparison>(std::make_shared<pdyn::solvers::ImplicitEuler>(options));
  scene.solver = comparison;
  const Outcome o = run(scene, s.threads);
  if (!o.stable) throw pdyn::Error(fmt::format("--llt: the {0} x {0} run was not stable", size));
  return comparison->t;
}

void print_llt_row(int size, const SolveTimes& c) {
  const double n = static_cast<double>(std::max<std::int64_t>(1, c.steps));
  const auto ms = [n](double seconds) { return fmt::format("{:.2f}", 1e3 * seconds / n); };
  const double ratio = (c.llt.factor + c.llt.solve) / (c.supernodal.factor + c.supernodal.solve);
  std::cout << fmt::format(
      "| {0} x {0} | {1} | {2} | {3:.3f} | {4} | {5} | {6:.3f} | {7} | {8} | **{9:.2f}x** | "
      "{10:.0f} / {11:.0f} | {12:.1e}{13} |\n",
      size, c.unknowns, c.steps, c.supernodal.analysis, ms(c.supernodal.factor),
      ms(c.supernodal.solve), c.llt.analysis, ms(c.llt.factor), ms(c.llt.solve), ratio,
      c.supernodal_nonzeros, c.llt_nonzeros, c.difference,
      c.same_as_solver ? "" : " (the supernodal replica differs from the solver!)");
}

void print_llt_table(const std::vector<int>& sizes, const Settings& s) {
  std::cout << fmt::format(
      "\nThe implicit step's linear solve, {} s simulated at dt = 0.01 s, 1 thread: the "
      "supernodal factorisation against Eigen's SimplicialLLT on the same matrices\n\n",
      s.duration);
  std::cout << "| size | unknowns | steps | supernodal analysis (s) | supernodal factor (ms "
               "per step) | supernodal solve (ms per step) | SimplicialLLT analysis (s) | "
               "SimplicialLLT factor (ms per step) | SimplicialLLT solve (ms per step) | "
               "factor + solve, SimplicialLLT / supernodal | nonzeros of L, supernodal / "
               "SimplicialLLT | max relative difference |\n";
  std::cout << "|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const int size : sizes) {
    print_llt_row(size, compare_solves(size, s));
    std::cout.flush();
  }
}

struct Options {
  Settings s;
  std::vector<int> sizes;
  std::vector<double> tolerances;
  bool skip_rk4 = false, llt = false;
  double given_rk4_dt = 0.0;
};

// The command line into `o`; false on an argument it does not know.
bool parse(int argc, char** argv, Options& o) {
  bool tolerances_given = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool value = i + 1 < argc;
    if (a == "--size" && value) {
      o.sizes.push_back(std::max(2, std::atoi(argv[++i])));
    } else if (a == "--repeats" && value) {
      o.s.repeats = std::max(1, std::atoi(argv[++i]));
    } else if (a == "--duration" && value) {
      o.s.duration = std::atof(argv[++i]);
    } else if (a == "--cg-tolerance" && value) {
      tolerances_given = true;
      const double tol = std::atof(argv[++i]);
      if (tol > 0) o.tolerances.push_back(tol);  // --cg-tolerance 0: no CG rows
    } else if (a == "--threads" && value) {
      o.s.threads = std::max(1, std::atoi(argv[++i]));
    } else if (a == "--bisect-steps" && value) {
      o.s.bisect_steps = std::max(0, std::atoi(argv[++i]));
    } else if (a == "--rk4-dt" && value) {
      o.given_rk4_dt = std::atof(argv[++i]);
    } else if (a == "--skip-rk4") {
      o.skip_rk4 = true;
    } else if (a == "--llt") {
      o.llt = true;
    } else if (a == "--trace") {
      o.s.trace = true;
    } else {
      return false;
    }
  }
  if (o.sizes.empty()) o.sizes = {30};
  if (!tolerances_given) o.tolerances = {1e-3};
  return true;
}

constexpr double kImplicitDt = 0.01;

// (b) at one size: the direct solve, then CG at each tolerance, each the
// best of s.repeats runs.
std::vector<ImplicitOutcome> time_implicit(int size, const Options& o) {
  std::vector<double> solves = {0.0};  // 0: direct
  solves.insert(solves.end(), o.tolerances.begin(), o.tolerances.end());
  std::vector<ImplicitOutcome> implicit;
  for (const double tol : solves) {
    ImplicitOutcome best;
    for (int k = 0; k < o.s.repeats; ++k) {
      ImplicitOutcome r = run_implicit(size, kImplicitDt, tol, o.s, o.s.trace && k == 0);
      if (k == 0 || r.run.wall < best.run.wall) best = std::move(r);
    }
    implicit.push_back(std::move(best));
  }
  return implicit;
}

struct Rk4Timing {
  double dt = 0.0, unstable = 0.0;  // s: the step timed, and the unstable one above it
  Outcome best;
};

// (a) at one size: the step (bisected, or --rk4-dt), then the best of
// s.repeats runs at it.
Rk4Timing time_rk4(int size, const Options& o) {
  Rk4Timing t;
  t.dt = o.given_rk4_dt > 0 ? o.given_rk4_dt : largest_stable_rk4_dt(size, o.s, &t.unstable);
  for (int k = 0; k < o.s.repeats; ++k) {
    Scene scene = load(size, "rk4", t.dt, o.s.duration);
    Outcome r = run(scene, o.s.threads);
    if (!r.stable) {  // only possible with --bisect-steps
      t.dt *= 0.99;
      t.unstable = t.dt / 0.99;
      k = -1;
      continue;
    }
    if (k == 0 || r.wall < t.best.wall) t.best = std::move(r);
  }
  return t;
}

// One row of the table: an implicit run against rk4's (none with --skip-rk4).
void print_row(int size, const ImplicitOutcome& o, const Rk4Timing* rk4) {
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
                o.factor_flops * static_cast<double>(o.run.steps) / o.factor_seconds * 1e-9, rest)
          : fmt::format("CG {:g} ({:.0f} / {} iterations per step; {})", o.cg_tolerance, o.cg_mean,
                        o.cg_max, rest);
  const auto rk4_cell = [rk4](auto&& cell) { return rk4 ? std::string(cell()) : "-"; };
  std::cout << fmt::format(
      "| {} x {} | {} | {} | {} | {} | {:.4g} | {} | {:.3f} | {} | {} / {:.3f} | {} |\n", size,
      size, rk4_cell([&] { return fmt::format("{:.4g}", rk4->dt); }),
      rk4_cell([&] { return std::to_string(rk4->best.steps); }),
      rk4_cell([&] { return fmt::format("{:.3f}", rk4->best.wall); }), solve, kImplicitDt,
      o.run.steps, o.run.wall,
      rk4_cell([&] { return fmt::format("{:.1f}x", rk4->best.wall / o.run.wall); }),
      rk4_cell([&] { return fmt::format("{:.3f}", rk4->best.max_travel); }), o.run.max_travel,
      rk4_cell([&] {
        return fmt::format("{:.3f}", (o.run.x - rk4->best.x).colwise().norm().maxCoeff());
      }));
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  if (!parse(argc, argv, o)) {
    std::cerr << "usage: pdyn_bench_stiff_cloth [--size N]... [--repeats N] [--duration S] "
                 "[--cg-tolerance E]... [--threads T] [--bisect-steps K] [--rk4-dt S] "
                 "[--skip-rk4] [--llt] [--trace]\n";
    return 2;
  }
  try {
    std::cout << fmt::format(
        "Stiff cloth: 1 m x 1 m, 1 kg, ks = 1e5 N/m, {} s simulated, {} thread(s); best of {} "
        "runs\n\n",
        o.s.duration, o.s.threads, o.s.repeats);
    std::cout << "| size | rk4 dt (s) | rk4 steps | rk4 wall (s) | implicit solve | implicit dt "
                 "(s) | steps | implicit wall (s) | speed-up | max travel rk4 / implicit (m) | "
                 "implicit vs rk4 at the end (m) |\n";
    std::cout << "|---|---|---|---|---|---|---|---|---|---|---|\n";
    bool all_stable = true;
    for (const int size : o.sizes) {
      const std::vector<ImplicitOutcome> implicit = time_implicit(size, o);
      for (const ImplicitOutcome& r : implicit) all_stable = all_stable && r.run.stable;
      Rk4Timing rk4;
      if (!o.skip_rk4) rk4 = time_rk4(size, o);
      for (const ImplicitOutcome& r : implicit) print_row(size, r, o.skip_rk4 ? nullptr : &rk4);
      if (!o.skip_rk4 && rk4.unstable > 0) {
        std::cerr << fmt::format("{} x {}: rk4 is unstable at dt = {:.4g} s\n", size, size,
                                 rk4.unstable);
      }
      std::cout.flush();
    }
    if (o.llt) print_llt_table(o.sizes, o.s);
    return all_stable ? 0 : 1;
  } catch (const std::exception& e) {
    std::cerr << "pdyn_bench_stiff_cloth: " << e.what() << "\n";
    return 1;
  }
}
