// verlet: velocity Verlet (Swope et al. 1982; the leapfrog / Stormer-Verlet
// method of Hairer, Lubich & Wanner, "Geometric Numerical Integration",
// section I.3.1):
//   v_half = v0 + h/2 a0,   x1 = x0 + h v_half,   v1 = v_half + h/2 a1.
// Second order, symmetric, and symplectic when the forces depend on
// positions only.
//
// Two choices differ from the textbook scheme, both for forces that depend
// on velocity or time (drag, damped springs, driven anchors):
//
// * a1 is evaluated at t0 + h, x1 and the first-order velocity predictor
//   v0 + h a0 (not at v_half). Using v_half there would make the velocity
//   update differ from the trapezoidal rule by h/2 (da/dv)(h/2 a1) = O(h^2)
//   per step, i.e. only first order for damped systems; the predictor
//   leaves an O(h^3) local error, so the method stays second order. For
//   velocity-independent forces a1 does not depend on it and the scheme is
//   exactly velocity Verlet.
//
// * `velocity_forces: half_step` evaluates a1 at v_half instead, and reuses
//   it as the next a0 whatever the forces read: the scheme of LAMMPS's
//   fix nve and of most MD codes (Allen & Tildesley, 2nd ed., sec. 3.2.1),
//   first order for damped systems, for scenes converted from LAMMPS that
//   must follow its runs step for step (a langevin bath, issue 44).
//
// * The end-of-step forces a1 are reused as the next step's a0 (one force
//   evaluation per step, as LAMMPS's velocity Verlet does) only when that
//   gives the same bits as evaluating a0 afresh: every force declares that
//   it does not depend on velocity, there is no collider, nothing but the
//   kernel's step wrote the state or evaluated the forces since, and the
//   time matches if a force reads it (pdyn::ForceReuse, pdyn/force_reuse.hpp,
//   lists the conditions). Otherwise a0 is evaluated at the start of the
//   step, as it always was before pdyn 0.4.
// * With velocity-independent forces the step is the textbook one written in
//   place, v += h/2 a0, x += h v, evaluate, v += h/2 a1, with no scratch
//   state. The same operations in the same order as the general form
//   (v_half = v0 + h/2 a0, x1 = x0 + h v_half, v1 = v_half + h/2 a1), so
//   the two give the same bits whenever both apply.
// * `reuse_forces: true` is a scene's promise, for forces that do not
//   declare their dependence (plugins built before ABI 6), that they depend
//   on positions and time only. It keeps the rule it had before (Promised
//   below), so that scenes using it give the same bits as before: a1 is
//   reused even after a wrap into a periodic box, when the positions and
//   force objects are those the last step ended with and the time matches
//   to within rounding.
// * With constraints in the system (pdyn/constraint.hpp), the step is RATTLE
//   (rattle.hpp; Andersen 1983): the positions are projected onto C = 0
//   after the drift and the velocities onto Cdot = 0 after the kick, to
//   `rattle_tolerance`, and the kernel adds no constraint force
//   (pdyn/constraint_solver.hpp). `constraints: force` keeps Witkin's
//   constraint force instead, as every other solver has it. For the
//   pressure, the virial of RATTLE's constraint forces is that of the
//   position stage of the step starting at the frame's state, as LAMMPS's
//   fix rattle tallies it (rattle_virial.hpp).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <pdyn/constraint_solver.hpp>
#include <pdyn/error.hpp>
#include <pdyn/force_reuse.hpp>
#include <pdyn/parallel.hpp>
#include <pdyn/plugin.hpp>
#include <pdyn/system.hpp>
#include <pdyn/thermo.hpp>

#include "rattle.hpp"
#include "rattle_virial.hpp"

namespace {

using pdyn::Index;

class Verlet final : public pdyn::Solver,
                     public pdyn::ForceReuseHolder,
                     public pdyn::ConstraintSolver,
                     public pdyn::ConstraintVirialSource {
 public:
  Verlet(bool promise, bool half_step, bool rattle, double tolerance, Index max_iterations)
      : promise_(promise),
        half_step_(half_step),
        rattle_on_(rattle),
        tolerance_(tolerance),
        rattle_(tolerance, max_iterations) {}

  bool enforces_constraints() const noexcept override { return rattle_on_; }

  // Only asked while RATTLE keeps the constraints (pdyn::total_virial).
  double constraint_virial(const pdyn::System& sys, double h) const override {
    return pdyn_verlet::rattle_virial(sys, h, tolerance_);
  }

  // A checkpoint carries the kept a1 (pdyn/force_reuse.hpp).
  const pdyn::Matrix3X* kept_accelerations(const pdyn::System& sys) const override {
    if (promise_) return promised_.still_valid(sys) ? &promised_.a1 : nullptr;
    return reuse_.current(sys);
  }
  void restore_kept_accelerations(const pdyn::System& sys, const pdyn::Matrix3X& a1) override {
    if (promise_) {
      promised_.remember(sys, a1);
    } else {
      reuse_.restore(sys, a1, needs_of(sys));
    }
  }

  void step(pdyn::System& sys, double h) override {
    // Asked before this step takes its own writable views of the state.
    const double t0 = sys.time();
    const Needs needs = needs_of(sys);
    const pdyn::Matrix3X* reusable = nullptr;
    if (promise_) {
      if (promised_.still_valid(sys)) reusable = &promised_.a1;
    } else {
      reusable = reuse_.kept(sys, needs);
    }
    auto x = sys.positions();
    auto v = sys.velocities();
    const Index n = sys.size();
    const pdyn::Matrix3X& a0 = reusable != nullptr ? *reusable : sys.compute_accelerations();
    const bool rattle = rattle_on_ && sys.constraint_rows() > 0;
    if (rattle) rattle_.begin(sys);  // J(x0), before the drift moves x
    // Column ranges split over the host's threads; columns are independent,
    // so the result does not depend on the thread count. In chunks of columns
    // that stay in cache between the statements of a pass.
    constexpr Index kChunk = pdyn::kChunkElements / 3;
    if (!needs.velocity) {
      pdyn::parallel_chunks(n, kChunk, [&](Index b, Index e) {
        v.middleCols(b, e - b) += (0.5 * h) * a0.middleCols(b, e - b);  // v_half
        x.middleCols(b, e - b) += h * v.middleCols(b, e - b);
      });
    } else {
      half_.resize(3, n);  // no-op after the first step
      pdyn::parallel_chunks(n, kChunk, [&](Index b, Index e) {
        const Index m = e - b;
        half_.middleCols(b, m) = v.middleCols(b, m) + (0.5 * h) * a0.middleCols(b, m);
        x.middleCols(b, m) += h * half_.middleCols(b, m);
        v.middleCols(b, m) += h * a0.middleCols(b, m);  // predictor, only seen by a1's forces
      });
    }
    sys.set_time(t0 + h);
    if (rattle) rattle_.project_positions(sys, h, needs.velocity ? &half_ : nullptr);

    const pdyn::Matrix3X& a1 = sys.compute_accelerations();
    if (!needs.velocity) {
      pdyn::parallel_chunks(n, kChunk, [&](Index b, Index e) {
        v.middleCols(b, e - b) += (0.5 * h) * a1.middleCols(b, e - b);
      });
    } else {
      pdyn::parallel_chunks(n, kChunk, [&](Index b, Index e) {
        v.middleCols(b, e - b) = half_.middleCols(b, e - b) + (0.5 * h) * a1.middleCols(b, e - b);
      });
    }
    if (rattle) {
      rattle_.project_velocities(sys);
      rattle_.end(sys);
    }
    if (promise_) {
      // With a collider a0 is always evaluated (still_valid): nothing to keep.
      if (sys.collider_objects().empty()) promised_.remember(sys, a1);
      return;
    }
    // Valid as the next a0 only if nothing writes or evaluates before it.
    reuse_.keep(sys, a1, needs);
  }

 private:
  using Needs = pdyn::ForceReuse::Needs;

  // The promise stands for the forces' declarations: only a collider makes
  // the step read velocities. With half_step the forces read v_half in
  // place, and a1 stands for the next a0 whatever they read.
  Needs needs_of(const pdyn::System& sys) const {
    if (promise_) return Needs{!sys.collider_objects().empty(), false};
    Needs n = pdyn::ForceReuse::needs(sys);
    if (half_step_) n.velocity = false;
    return n;
  }

  // reuse_forces: true keeps the rule it had before forces declared their
  // dependence, so that the scenes using it give the same bits: a1 (a copy)
  // is reused when the positions are those the last step ended with after
  // the kernel's wrap into a periodic box (a1 was evaluated before the wrap:
  // the same system, though its separations may round differently), the time
  // matches to rounding, the force objects are the same and there is no
  // collider. Every write through the state's views is not a reason to
  // evaluate again: the promise is that velocities do not matter.
  struct Promised {
    pdyn::Matrix3X a1, x;
    double t = 0.0;
    std::vector<const pdyn::Force*> forces;
    bool valid = false;

    bool still_valid(const pdyn::System& sys) const {
      if (!valid || x.cols() != sys.size() ||
          std::abs(sys.time() - t) > 1e-9 * std::max(1.0, std::abs(t))) {
        return false;
      }
      if (!sys.collider_objects().empty()) return false;
      const auto& now = sys.force_objects();
      if (now.size() != forces.size()) return false;
      for (std::size_t k = 0; k < now.size(); ++k) {
        if (now[k].force.get() != forces[k]) return false;
      }
      return x == sys.positions();
    }

    void remember(const pdyn::System& sys, const pdyn::Matrix3X& a) {
      a1 = a;  // copies into storage sized on the first step
      x = sys.positions();
      if (sys.domain().any_periodic()) {
        for (Index i = 0; i < x.cols(); ++i) x.col(i) = sys.domain().wrap(x.col(i));
      }
      t = sys.time();
      forces.resize(sys.force_objects().size());
      for (std::size_t k = 0; k < forces.size(); ++k) {
        forces[k] = sys.force_objects()[k].force.get();
      }
      valid = true;
    }
  };

  bool promise_;
  bool half_step_;  // velocity_forces: half_step
  bool rattle_on_;
  double tolerance_;  // rattle_tolerance
  pdyn_verlet::Rattle rattle_;
  Promised promised_;
  pdyn::Matrix3X half_;     // v_half for velocity-dependent forces, sized on first use
  pdyn::ForceReuse reuse_;  // the last step's a1, while it may stand in for a0
};

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Solver;
  d.name = "verlet";
  d.version = "1.1.0";
  d.description =
      "velocity Verlet: v' = v0 + h/2 a0, x1 = x0 + h v', v1 = v' + h/2 a1; order 2, symplectic";
  d.solver_traits.order = 2;
  d.solver_traits.symplectic = true;
  d.params = {
      pdyn::param::boolean(
          "reuse_forces", false,
          "promise that the forces depend on positions and time only, for forces that do not say "
          "(Force::dependence): reuse the last step's a1 as a0 even then"),
      pdyn::param::string("velocity_forces", "predictor",
                          "the velocities forces at the step's end see: predictor (v0 + h a0; "
                          "order 2 with drag) or half_step (v0 + h/2 a0, LAMMPS's fix nve; a1 "
                          "reused as the next a0)"),
      pdyn::param::string("constraints", "rattle",
                          "how constraints are kept: rattle (positions and velocities projected "
                          "each step) or force (Witkin's constraint force, as other solvers)"),
      pdyn::param::real("rattle_tolerance", 1e-12, "",
                        "RATTLE stops when every |C| is at most this, in each row's unit "
                        "(m for rods)")
          .greater_than(0.0),
      pdyn::param::integer("rattle_max_iterations", 100,
                           "RATTLE's position iterations before the step fails")
          .at_least(1)};
  d.create_solver = [](const pdyn::Params& p, const pdyn::SceneContext&) {
    const std::string& how = p.string("constraints");
    if (how != "rattle" && how != "force") {
      throw pdyn::ParamError("constraints",
                             fmt::format("'{}' is not a way to keep constraints (expected rattle "
                                         "or force)",
                                         how));
    }
    const std::string& velocities = p.string("velocity_forces");
    if (velocities != "predictor" && velocities != "half_step") {
      throw pdyn::ParamError(
          "velocity_forces",
          fmt::format("'{}' is not a choice (expected predictor or half_step)", velocities));
    }
    if (velocities == "half_step" && p.boolean("reuse_forces")) {
      throw pdyn::ParamError("velocity_forces",
                             "half_step reuses the forces already (expected reuse_forces: false)");
    }
    return std::make_unique<Verlet>(p.boolean("reuse_forces"), velocities == "half_step",
                                    how == "rattle", p.real("rattle_tolerance"),
                                    p.integer("rattle_max_iterations"));
  };
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
