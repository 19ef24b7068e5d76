// plane: Witkin's point-plane collision and contact (SIGGRAPH '97 notes,
// "Bouncing off the Walls"), for the plane through P with normal N.
//
// Collision (after each step): a particle within epsilon of the plane and
// heading in, (X - P).N < eps and N.V < 0, gets V' = V_T - kr V_N. A particle
// below the plane is put back onto it, so no step ends inside the obstacle.
//
// Contact (during derivative evaluation): a particle on the plane, moving
// along it and pushed into it, (X - P).N < eps, |N.V| < eps, N.F < 0, has the
// normal part of its force cancelled: F' = F_T (the wall pushes back).
//
// Resting: a bounce whose outgoing speed kr |V_N| is smaller than what the
// normal acceleration takes away in one step, |a_N| h, would land again
// within the next step: the time step cannot resolve it. Such a bounce is
// made perfectly inelastic (V_N = 0), after which the contact force holds
// the particle on the plane. Without this, a dropped ball keeps micro-
// bouncing at a speed near g h forever instead of coming to rest.
#include <fmt/format.h>

#include <cmath>
#include <pdyn/plugin.hpp>

namespace {

class Plane final : public pdyn::Collider {
 public:
  Plane(const pdyn::Vec3& point, const pdyn::Vec3& normal, double restitution, double epsilon)
      : p_(point), n_(normal.normalized()), kr_(restitution), eps_(epsilon) {}

  void apply_contact_forces(const pdyn::ParticleView& p, Eigen::Ref<pdyn::Matrix3X> f) override {
    for (pdyn::Index i = 0; i < p.size(); ++i) {
      if (p.fixed[i]) continue;
      const double fn = n_.dot(f.col(i));
      if (fn < 0.0 && (p.x.col(i) - p_).dot(n_) < eps_ && std::abs(n_.dot(p.v.col(i))) < eps_) {
        f.col(i) -= fn * n_;
      }
    }
  }

  void respond(pdyn::MutableParticleView& p, double h) override {
    for (pdyn::Index i = 0; i < p.size(); ++i) {
      if (p.fixed[i]) continue;
      const double depth = (p.x.col(i) - p_).dot(n_);
      if (depth >= eps_) continue;
      const double vn = n_.dot(p.v.col(i));
      if (vn < 0.0) {
        const double an = std::min(0.0, n_.dot(p.f.col(i)) / p.mass(i));
        const double vn_out = kr_ * -vn;
        // V' = V_T - kr V_N, or V_T alone for a bounce the step can't resolve.
        p.v.col(i) += ((vn_out < -an * h ? 0.0 : vn_out) - vn) * n_;
      }
      if (depth < 0.0) p.x.col(i) -= depth * n_;
    }
  }

 private:
  pdyn::Vec3 p_, n_;
  double kr_, eps_;
};

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Collider;
  d.name = "plane";
  d.version = "1.0.0";
  d.description =
      "point-plane collision (V' = V_T - kr V_N) and contact (F' = F_T) against an infinite plane";
  d.params = {
      pdyn::param::vec3("point", {0, 0, 0}, "m", "a point P on the plane"),
      pdyn::param::vec3("normal", {0, 0, 1}, "", "normal N, pointing to the free side").not_zero(),
      pdyn::param::real("restitution", 0.5, "", "coefficient of restitution kr").at_least(0).at_most(1),
      pdyn::param::real("epsilon", 1e-4, "m, m/s", "contact tolerance on distance and normal speed")
          .greater_than(0),
  };
  d.create_collider = [](const pdyn::Params& p, const pdyn::SceneContext&) {
    return std::make_unique<Plane>(p.vec3("point"), p.vec3("normal"), p.real("restitution"),
                                   p.real("epsilon"));
  };
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
