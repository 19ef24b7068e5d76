// implicit_euler: the plugin's descriptor. The method is in
// implicit_euler_solver.cpp.
#include <fmt/format.h>

#include <pdyn/error.hpp>
#include <pdyn/plugin.hpp>
#include <string>

#include "implicit_euler_solver.hpp"

namespace {

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Solver;
  d.name = "implicit_euler";
  d.version = "1.1.0";
  d.description =
      "linearised backward Euler (Baraff & Witkin 1998), (M - h df/dv - h^2 df/dx) dv = "
      "h (f0 + h df/dx v0) by sparse Cholesky or conjugate gradients; order 1";
  d.params = {
      pdyn::param::string(
          "linear_solver", "auto",
          "direct (sparse Cholesky; every force needs Jacobians), cg (conjugate "
          "gradients), or auto: direct when every force has Jacobians and the factor "
          "fits in 1 GiB, else cg"),
      pdyn::param::real("cg_tolerance", pdyn::solvers::ImplicitEulerOptions{}.cg_tolerance, "",
                        "CG stops when |residual| <= cg_tolerance |right side|, in the "
                        "preconditioner's norm")
          .greater_than(0)
          .at_most(1),
      pdyn::param::integer("cg_max_iterations",
                           pdyn::solvers::ImplicitEulerOptions{}.cg_max_iterations,
                           "CG iterations per step; needing more is an error")
          .at_least(1),
  };
  d.solver_traits.order = 1;
  d.create_solver = [](const pdyn::Params& p, const pdyn::SceneContext&) {
    pdyn::solvers::ImplicitEulerOptions o;
    const std::string& linear_solver = p.string("linear_solver");
    if (linear_solver == "direct") {
      o.linear_solver = pdyn::solvers::LinearSolver::Direct;
    } else if (linear_solver == "cg") {
      o.linear_solver = pdyn::solvers::LinearSolver::Cg;
    } else if (linear_solver != "auto") {
      throw pdyn::ParamError(
          "linear_solver",
          fmt::format("'{}' is not a linear solver (expected one of: auto, direct, cg)",
                      linear_solver));
    }
    o.cg_tolerance = p.real("cg_tolerance");
    o.cg_max_iterations = p.integer("cg_max_iterations");
    return std::make_unique<pdyn::solvers::ImplicitEuler>(o);
  };
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
