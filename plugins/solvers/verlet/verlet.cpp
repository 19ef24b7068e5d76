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
//   solver cannot know, so by default this costs two force evaluations per
//   step. `reuse_forces: true` is the scene's promise that its forces depend
//   on positions and time only (Lennard-Jones, gravity, undamped springs):
//   then a1 is reused as the next step's a0 (LAMMPS's velocity Verlet, one
//   evaluation per step) whenever the positions (after the kernel's wrap
//   into a periodic box) and the set of force objects are exactly those
//   the last step ended with, the time is, to rounding, and there is no
//   collider (contact forces depend on velocity); any change
//   (a collider's put-back, a checkpoint, an interactive edit) falls back
//   to evaluating a0.
#include <algorithm>
#include <cmath>
#include <pdyn/parallel.hpp>
#include <pdyn/plugin.hpp>
#include <pdyn/system.hpp>

namespace {

class Verlet final : public pdyn::Solver {
 public:
  explicit Verlet(bool reuse) : reuse_(reuse) {}

  void step(pdyn::System& sys, double h) override {
    const double t0 = sys.time();
    auto x = sys.positions();
    auto v = sys.velocities();

    const pdyn::Index n = sys.size();
    a0_.resize(3, n);  // no-op after the first step
    half_.resize(3, n);
    // Column ranges split over the host's threads; columns are independent,
    // so the result does not depend on the thread count.
    const bool reused = reuse_ && still_valid(sys);
    const pdyn::Matrix3X& a = reused ? last_a1_ : sys.compute_accelerations();
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
    // With a collider a0 is always evaluated (still_valid): nothing to keep.
    if (reuse_ && sys.collider_objects().empty()) remember(sys, a1);
  }

 private:
  // The state the last step ended in: positions, time and force objects.
  bool still_valid(const pdyn::System& sys) const {
    // The time only to within rounding: the host sets it to k dt after a
    // step that ended at t0 + h.
    if (!valid_ || last_x_.cols() != sys.size() ||
        std::abs(sys.time() - last_t_) > 1e-9 * std::max(1.0, std::abs(last_t_))) {
      return false;
    }
    // Colliders' contact forces depend on velocity (Witkin's resting
    // contact tests |N . V|): with any collider, a0 is always evaluated.
    if (!sys.collider_objects().empty()) return false;
    const auto& forces = sys.force_objects();
    if (forces.size() != last_forces_.size()) return false;
    for (std::size_t k = 0; k < forces.size(); ++k) {
      if (forces[k].force.get() != last_forces_[k]) return false;
    }
    return last_x_ == sys.positions();
  }

  void remember(const pdyn::System& sys, const pdyn::Matrix3X& a1) {
    last_a1_ = a1;  // copies into storage sized on the first step
    // As the kernel will leave them: wrapped into a periodic box.
    last_x_ = sys.positions();
    if (sys.domain().any_periodic()) {
      for (pdyn::Index i = 0; i < last_x_.cols(); ++i) {
        last_x_.col(i) = sys.domain().wrap(last_x_.col(i));
      }
    }
    last_t_ = sys.time();
    last_forces_.resize(sys.force_objects().size());
    for (std::size_t k = 0; k < last_forces_.size(); ++k) {
      last_forces_[k] = sys.force_objects()[k].force.get();
    }
    valid_ = true;
  }

  bool reuse_;
  pdyn::Matrix3X a0_, half_;  // sized on the first step, reused after
  // reuse_forces: a1, x and t at the end of the last step, and its forces.
  pdyn::Matrix3X last_a1_, last_x_;
  double last_t_ = 0.0;
  std::vector<const pdyn::Force*> last_forces_;
  bool valid_ = false;
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
  d.params = {pdyn::param::boolean(
      "reuse_forces", false,
      "forces depend on positions and time only: reuse the last step's a1 as a0 (one force "
      "evaluation per step)")};
  d.create_solver = [](const pdyn::Params& p, const pdyn::SceneContext&) {
    return std::make_unique<Verlet>(p.boolean("reuse_forces"));
  };
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
