// No heap allocation inside the step loop after the first step, nor in a
// warm neighbor list's updates and rebuilds, nor in a warm Barnes-Hut tree's.
//
// A separate test executable, because it replaces the process's allocator:
// global operator new/delete and malloc/calloc/realloc/free (Eigen's
// temporaries come from malloc, not operator new) are wrapped to count
// calls while a window is open, forwarding to glibc's own __libc_* entry
// points. The definitions in the executable interpose on every shared
// library, so allocations inside plugins (a separate .so each) are counted
// too. Not built under sanitizers, which bring their own allocator.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>
#include <pdyn/neighbors.hpp>
#include <pdyn/parallel.hpp>
#include <random>

#include "pdyn/host/assembly.hpp"
#include "pdyn/host/registry.hpp"
#include "pdyn/host/runner.hpp"
#include "pdyn/host/scene.hpp"
#include "pdyn/host/threads.hpp"

extern "C" {
void* __libc_malloc(std::size_t);
void* __libc_calloc(std::size_t, std::size_t);
void* __libc_realloc(void*, std::size_t);
void* __libc_memalign(std::size_t, std::size_t);
void __libc_free(void*);
}

namespace {

std::atomic<bool> g_counting{false};
std::atomic<long> g_allocations{0};

void note() {
  if (g_counting.load(std::memory_order_relaxed)) {
    g_allocations.fetch_add(1, std::memory_order_relaxed);
  }
}

void* checked(void* p) {
  if (!p) throw std::bad_alloc();
  return p;
}

// Counts the allocations made while it lives.
class AllocationWindow {
 public:
  AllocationWindow() {
    g_allocations = 0;
    g_counting = true;
  }
  ~AllocationWindow() { g_counting = false; }
  long count() const { return g_allocations.load(); }
};

}  // namespace

extern "C" {
void* malloc(std::size_t n) {
  note();
  return __libc_malloc(n);
}
void* calloc(std::size_t n, std::size_t size) {
  note();
  return __libc_calloc(n, size);
}
void* realloc(void* p, std::size_t n) {
  note();
  return __libc_realloc(p, n);
}
void* memalign(std::size_t align, std::size_t n) {
  note();
  return __libc_memalign(align, n);
}
void* aligned_alloc(std::size_t align, std::size_t n) {
  note();
  return __libc_memalign(align, n);
}
int posix_memalign(void** out, std::size_t align, std::size_t n) {
  note();
  *out = __libc_memalign(align, n);
  return *out ? 0 : ENOMEM;
}
void free(void* p) { __libc_free(p); }
}

void* operator new(std::size_t n) {
  note();
  return checked(__libc_malloc(n ? n : 1));
}
void* operator new[](std::size_t n) {
  note();
  return checked(__libc_malloc(n ? n : 1));
}
void* operator new(std::size_t n, const std::nothrow_t&) noexcept {
  note();
  return __libc_malloc(n ? n : 1);
}
void* operator new[](std::size_t n, const std::nothrow_t&) noexcept {
  note();
  return __libc_malloc(n ? n : 1);
}
void* operator new(std::size_t n, std::align_val_t a) {
  note();
  return checked(__libc_memalign(static_cast<std::size_t>(a), n ? n : 1));
}
void* operator new[](std::size_t n, std::align_val_t a) {
  note();
  return checked(__libc_memalign(static_cast<std::size_t>(a), n ? n : 1));
}
void operator delete(void* p) noexcept { __libc_free(p); }
void operator delete[](void* p) noexcept { __libc_free(p); }
void operator delete(void* p, std::size_t) noexcept { __libc_free(p); }
void operator delete[](void* p, std::size_t) noexcept { __libc_free(p); }
void operator delete(void* p, std::align_val_t) noexcept { __libc_free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { __libc_free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { __libc_free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { __libc_free(p); }

namespace pdyn {
namespace {

const PluginRegistry& plugins() {
  static const PluginRegistry r = [] {
    PluginRegistry reg;
    reg.discover({PDYN_PLUGIN_DIR});
    return reg;
  }();
  return r;
}

// The shared hanging cloth (tests/scenes/shared/cloth.yaml) at 64 x 64,
// over a floor plane: large enough that the spring plugin and the solvers
// take their multi-threaded paths when more than one thread is set.
Scene cloth(const std::string& solver, int steps) {
  return load_scene(std::string(PDYN_SOURCE_DIR) + "/tests/scenes/shared/cloth.yaml", plugins(),
                    {{"simulation.steps", std::to_string(steps)},
                     {"simulation.solver", "{ type: " + solver + " }"},
                     {"particles[0].grid.nx", "64"},
                     {"particles[0].grid.ny", "64"},
                     {"colliders", "[{ type: plane, point: [0, 0, 0.99], normal: [0, 0, 1] }]"}});
}

struct Case {
  std::string solver;
  int threads;
};

class StepAllocations : public ::testing::TestWithParam<Case> {};

// Allocations in `steps` solver steps (with collision responses) after the
// first, which may size the solver's scratch; expects that it did step.
long allocations_after_the_first_step(Scene& scene, int threads, int steps) {
  set_threads(threads);
  System& sys = *scene.system;
  scene.solver->step(sys, scene.dt);  // may size its scratch vectors
  SystemAssembly(sys).respond_to_collisions(scene.dt);
  const Eigen::VectorXd after_one = sys.state();
  long count = 0;
  {
    AllocationWindow window;
    for (int k = 0; k < steps; ++k) {
      scene.solver->step(sys, scene.dt);
      SystemAssembly(sys).respond_to_collisions(scene.dt);
    }
    count = window.count();
  }
  EXPECT_NE(sys.state(), after_one);  // it did step
  return count;
}

// The solver's own step, as a host program drives it.
TEST_P(StepAllocations, NoneAfterTheFirstStep) {
  const Case c = GetParam();
  Scene scene = cloth(c.solver, 100);
  EXPECT_EQ(allocations_after_the_first_step(scene, c.threads, 20), 0)
      << c.solver << " with " << c.threads << " threads";
}

INSTANTIATE_TEST_SUITE_P(ExplicitSolvers, StepAllocations,
                         ::testing::Values(Case{"rk4", 1}, Case{"rk4", 2}, Case{"midpoint", 1},
                                           Case{"midpoint", 2}, Case{"euler", 2}, Case{"verlet", 2},
                                           Case{"symplectic_euler", 2}),
                         [](const ::testing::TestParamInfo<Case>& param_info) {
                           return param_info.param.solver + "_" +
                                  std::to_string(param_info.param.threads) + "threads";
                         });

// implicit_euler, with each linear solver: the first step builds the
// matrix's pattern (and, for the direct solve, the factor's symbolic
// analysis and storage); later steps refill and refactorise in place.
TEST(StepAllocations, ImplicitEulerNoneAfterTheFirstStep) {
  for (const std::string linear_solver : {"direct", "cg"}) {
    Scene scene = cloth("implicit_euler, linear_solver: " + linear_solver, 100);
    EXPECT_EQ(allocations_after_the_first_step(scene, 1, 5), 0)
        << "implicit_euler, linear_solver " << linear_solver;
  }
}

// The runner's loop around the solver (fault checks, previous state, time):
// a run of 12 steps allocates exactly as much as a run of 2.
TEST(RunnerAllocations, SameForTwoAndTwelveSteps) {
  auto allocations = [](int steps) {
    Scene scene = cloth("rk4", steps);
    RunOptions options;
    options.threads = 2;
    run_scene(scene, options);  // warms the thread pool and lazy statics
    scene.system->set_time(0.0);
    AllocationWindow window;
    run_scene(scene, options);
    return window.count();
  };
  const long two = allocations(2), twelve = allocations(12);
  EXPECT_EQ(twelve, two) << "the runner allocates " << (twelve - two) / 10.0 << " times per step";
}

// A neighbor list (pdyn/neighbors.hpp) of 6000 particles in random motion,
// periodic and in open space (where the grid follows the spreading cloud):
// once built twice, its updates and the rebuilds they trigger allocate
// nothing.
TEST(NeighborListAllocations, NoneOnceWarm) {
  for (const int threads : {1, 2}) {
    for (const bool periodic : {true, false}) {
      set_threads(threads);
      const Index n = 6000;                    // above kParallelMinElements
      const double L = std::cbrt(n / 0.8442);  // Lennard-Jones melt density
      Domain d;
      if (periodic) {
        d.max = Vec3(L, L, L);
        d.periodic = {true, true, true};
      }
      std::mt19937_64 rng(1);
      std::uniform_real_distribution<double> u(0, L), step(-0.05, 0.05);
      Matrix3X x(3, n);
      for (Index i = 0; i < n; ++i) x.col(i) = Vec3(u(rng), u(rng), u(rng));
      const std::vector<std::uint8_t> members(n, 1);
      NeighborList list(2.5, 0.3);
      list.update(x, d, &members);
      list.build(x, d, &members);
      long count = 0;
      {
        AllocationWindow window;
        for (int s = 0; s < 30; ++s) {
          for (Index i = 0; i < n; ++i) {
            x.col(i) = d.wrap(x.col(i) + Vec3(step(rng), step(rng), step(rng)));
          }
          list.update(x, d, &members);
        }
        count = window.count();
      }
      EXPECT_EQ(count, 0) << threads << " threads, " << (periodic ? "periodic" : "open");
      EXPECT_GT(list.builds(), 5);  // it did rebuild
    }
  }
}

// nbody with method barnes_hut rebuilds its octree at every force and
// energy evaluation: 5000 bodies in a cluster (above kParallelMinElements),
// stepped by verlet; once the tree has been built a few times, neither the
// steps nor the potential energy allocate.
TEST(NBodyTreeAllocations, NoneOnceWarm) {
  for (const int threads : {1, 2}) {
    Scene scene = load_scene_text(
        "simulation: { dt: 0.001, steps: 100, solver: { type: verlet } }\n"
        "particles:\n"
        "  - cloud: { n: 5000, sphere: { center: [0, 0, 0], radius: 1 }, mass: 0.0002, seed: 3 "
        "}\n"
        "forces:\n  - { type: nbody, G: 1, softening: 0.05, method: barnes_hut }\n",
        "nbody.yaml", plugins());
    set_threads(threads);
    System& sys = *scene.system;
    for (int k = 0; k < 3; ++k) {
      scene.solver->step(sys, scene.dt);
      (void)sys.potential_energy();
    }
    const Eigen::VectorXd before = sys.state();
    long count = 0;
    double u = 0.0;
    {
      AllocationWindow window;
      for (int k = 0; k < 20; ++k) {
        scene.solver->step(sys, scene.dt);
        u += sys.potential_energy();
      }
      count = window.count();
    }
    EXPECT_EQ(count, 0) << threads << " threads";
    EXPECT_NE(sys.state(), before);  // it did step
    EXPECT_LT(u, 0.0);
  }
}

}  // namespace
}  // namespace pdyn
