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
// * a0 is recomputed at the start of every step rather than reused from the
//   previous step's a1 (the "one evaluation per step" form). The cached a1
//   was evaluated at the predicted velocity, not at v1; and after the step
//   the kernel's collider response may change x and v, and a host may set
//   the state between steps (checkpoints, interactive edits). Reusing a1 is
//   only valid when none of that happens and the forces ignore v, which a
//   solver cannot know, so this costs two force evaluations per step.
#include <pdyn/parallel.hpp>
#include <pdyn/plugin.hpp>
#include <pdyn/system.hpp>

namespace {

class Verlet final : public pdyn::Solver {
 public:
  void step(pdyn::System& sys, double h) override {
    const double t0 = sys.time();
    auto x = sys.positions();
    auto v = sys.velocities();

    const pdyn::Index n = sys.size();
    a0_.resize(3, n);  // no-op after the first step
    half_.resize(3, n);
    // Column ranges split over the host's threads; columns are independent,
    // so the result does not depend on the thread count.
    const pdyn::Matrix3X& a = sys.compute_accelerations();
    pdyn::parallel_ranges(n, [&](pdyn::Index b, pdyn::Index e) {
      const pdyn::Index m = e - b;
      a0_.middleCols(b, m) = a.middleCols(b, m);
      half_.middleCols(b, m) = v.middleCols(b, m) + (0.5 * h) * a0_.middleCols(b, m);  // v_half
      x.middleCols(b, m) += h * half_.middleCols(b, m);
      v.middleCols(b, m) +=
          h * a0_.middleCols(b, m);  // velocity predictor, only seen by a1's forces
    });
    sys.set_time(t0 + h);

    const pdyn::Matrix3X& a1 = sys.compute_accelerations();
    pdyn::parallel_ranges(n, [&](pdyn::Index b, pdyn::Index e) {
      v.middleCols(b, e - b) = half_.middleCols(b, e - b) + (0.5 * h) * a1.middleCols(b, e - b);
    });
  }

 private:
  pdyn::Matrix3X a0_, half_;  // sized on the first step, reused after
};

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Solver;
  d.name = "verlet";
  d.version = "1.0.0";
  d.description =
      "velocity Verlet: v' = v0 + h/2 a0, x1 = x0 + h v', v1 = v' + h/2 a1; order 2, symplectic";
  d.solver_traits.order = 2;
  d.solver_traits.symplectic = true;
  d.create_solver = [](const pdyn::Params&, const pdyn::SceneContext&) {
    return std::make_unique<Verlet>();
  };
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
