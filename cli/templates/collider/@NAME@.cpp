// @NAME@: a horizontal floor z = height, with Witkin's point-plane collision
// and contact (SIGGRAPH '97 notes, "Bouncing off the Walls"):
//   collision (after each step): a particle within epsilon of the floor and
//     heading down gets v_z' = -kr v_z, and one below it is put back on it;
//   contact (every derivative evaluation): a particle resting on the floor
//     that is pushed down has the downward part of its force cancelled.
#include <algorithm>
#include <cmath>
#include <pdyn/plugin.hpp>

namespace {

class Floor final : public pdyn::Collider {
 public:
  Floor(double height, double restitution, double epsilon)
      : z0_(height), kr_(restitution), eps_(epsilon) {}

  void apply_contact_forces(const pdyn::ParticleView& p, Eigen::Ref<pdyn::Matrix3X> f) override {
    for (pdyn::Index i = 0; i < p.size(); ++i) {
      if (p.fixed[i]) continue;
      const bool resting = p.x(2, i) - z0_ < eps_ && std::abs(p.v(2, i)) < eps_;
      if (resting && f(2, i) < 0.0) f(2, i) = 0.0;  // the floor pushes back
    }
  }

  void respond(pdyn::MutableParticleView& p, double h) override {
    for (pdyn::Index i = 0; i < p.size(); ++i) {
      if (p.fixed[i]) continue;
      const double depth = p.x(2, i) - z0_;
      if (depth >= eps_) continue;
      if (p.v(2, i) < 0.0) {
        // A bounce slower than what gravity takes away in one step would land
        // again within the step: the step cannot resolve it, so the particle
        // comes to rest and the contact force holds it.
        const double down = std::min(0.0, p.f(2, i) / p.mass(i));
        const double up = -kr_ * p.v(2, i);
        p.v(2, i) = up < -down * h ? 0.0 : up;
      }
      if (depth < 0.0) p.x(2, i) = z0_;  // no step may end inside the floor
    }
  }

 private:
  double z0_, kr_, eps_;
};

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Collider;
  d.name = "@NAME@";
  d.version = "0.1.0";
  d.description = "floor z = height: v_z' = -kr v_z on impact, downward force cancelled at rest";
  d.params = {
      pdyn::param::real("height", 0.0, "m", "height of the floor"),
      pdyn::param::real("restitution", 0.5, "", "coefficient of restitution kr")
          .at_least(0)
          .at_most(1),
      pdyn::param::real("epsilon", 1e-4, "m, m/s", "contact tolerance on distance and speed")
          .greater_than(0),
  };
  d.create_collider = [](const pdyn::Params& p, const pdyn::SceneContext&) {
    return std::make_unique<Floor>(p.real("height"), p.real("restitution"), p.real("epsilon"));
  };
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
