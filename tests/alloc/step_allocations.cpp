// No heap allocation inside the step loop after the first step.
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
#include <pdyn/parallel.hpp>

#include "pdyn/host/registry.hpp"
#include "pdyn/host/runner.hpp"
#include "pdyn/host/scene.hpp"

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

// The solver's own step, as a host program drives it.
TEST_P(StepAllocations, NoneAfterTheFirstStep) {
  const Case c = GetParam();
  Scene scene = cloth(c.solver, 100);
  set_threads(c.threads);
  System& sys = *scene.system;
  scene.solver->step(sys, scene.dt);  // may size its scratch vectors
  sys.respond_to_collisions(scene.dt);
  const Eigen::VectorXd after_one = sys.state();
  long count = 0;
  {
    AllocationWindow window;
    for (int k = 0; k < 20; ++k) {
      scene.solver->step(sys, scene.dt);
      sys.respond_to_collisions(scene.dt);
    }
    count = window.count();
  }
  EXPECT_EQ(count, 0) << c.solver << " with " << c.threads << " threads";
  EXPECT_NE(sys.state(), after_one);  // it did step
}

INSTANTIATE_TEST_SUITE_P(ExplicitSolvers, StepAllocations,
                         ::testing::Values(Case{"rk4", 1}, Case{"rk4", 2}, Case{"midpoint", 1},
                                           Case{"midpoint", 2}, Case{"euler", 2}, Case{"verlet", 2},
                                           Case{"symplectic_euler", 2}),
                         [](const ::testing::TestParamInfo<Case>& param_info) {
                           return param_info.param.solver + "_" +
                                  std::to_string(param_info.param.threads) + "threads";
                         });

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

}  // namespace
}  // namespace pdyn
