// The run-time binding to BLAS and LAPACK (blas.hpp says why it is not
// linked).
#include "blas.hpp"

#include <dlfcn.h>
#include <fmt/format.h>

#include <cstdlib>
#include <pdyn/error.hpp>
#include <string>
#include <type_traits>
#include <vector>

namespace pdyn::solvers::detail {

namespace {

// PDYN_BLAS, when set, names the library (a path or a soname) and nothing
// else is tried. Loaded for good (RTLD_NODELETE): a threaded OpenBLAS keeps
// a thread pool that must not outlive its code.
Blas load_blas() {
  const char* chosen = std::getenv("PDYN_BLAS");
  const std::vector<std::string> names =
      chosen != nullptr && *chosen != '\0'
          ? std::vector<std::string>{chosen}
          : std::vector<std::string>{"libopenblas.so.0", "liblapack.so.3"};
  std::string tried;
  for (const std::string& name : names) {
    void* handle = dlopen(name.c_str(), RTLD_NOW | RTLD_LOCAL | RTLD_NODELETE);
    if (handle == nullptr) {
      const char* why = dlerror();
      tried += (tried.empty() ? "" : "; ") + std::string(why != nullptr ? why : name);
      continue;
    }
    Blas b;
    std::string missing;
    auto find = [&](auto& fn, const char* symbol) {
      fn = reinterpret_cast<std::remove_reference_t<decltype(fn)>>(dlsym(handle, symbol));
      if (fn == nullptr) missing += (missing.empty() ? "" : ", ") + std::string(symbol);
    };
    find(b.dgemm, "dgemm_");
    find(b.dsyrk, "dsyrk_");
    find(b.dtrsm, "dtrsm_");
    find(b.dtrsv, "dtrsv_");
    find(b.dgemv, "dgemv_");
    find(b.dpotrf, "dpotrf_");
    if (!missing.empty()) {
      tried += (tried.empty() ? "" : "; ") + name + " lacks " + missing;
      continue;
    }
    // OpenBLAS's own: its threaded builds would otherwise start a thread
    // pool that spins beside the runner's OpenMP threads.
    if (auto threads = reinterpret_cast<void (*)(int)>(dlsym(handle, "openblas_set_num_threads"))) {
      threads(1);
    }
    return b;
  }
  throw Error(fmt::format(
      "implicit_euler: cannot load a BLAS and LAPACK for its direct solve: {} (expected "
      "Debian's libopenblas0 installed, or PDYN_BLAS naming a library with dgemm_, dsyrk_, "
      "dtrsm_, dtrsv_, dgemv_ and dpotrf_; linear_solver: cg needs none)",
      tried));
}

}  // namespace

// A failed load throws and is tried again at the next factorisation.
const Blas& blas() {
  static const Blas b = load_blas();
  return b;
}

}  // namespace pdyn::solvers::detail
