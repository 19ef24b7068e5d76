// plane: Witkin's point-plane collision and contact (SIGGRAPH '97 notes,
// "Bouncing off the Walls"), for the plane through P with normal N.
//
// The plane supplies only its geometry, the signed distance (X - P) . N and
// the normal N; the rules (restitution, the resting rule, contact force,
// put-back, Coulomb friction) are the kernel's, in pdyn/contact.hpp, shared
// with the sphere and box colliders. With friction 0 this is bit-identical
// to the plane collider before friction existed.
#include <pdyn/contact.hpp>
#include <pdyn/plugin.hpp>

namespace {

class Plane final : public pdyn::SurfaceCollider {
 public:
  Plane(const pdyn::Vec3& point, const pdyn::Vec3& normal, const pdyn::ContactModel& model)
      : SurfaceCollider(model), p_(point), n_(normal.normalized()) {}

  pdyn::SurfacePoint surface(const pdyn::Vec3& x, int) const override {
    return {(x - p_).dot(n_), n_};
  }

 private:
  pdyn::Vec3 p_, n_;
};

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Collider;
  d.name = "plane";
  d.version = "1.1.0";
  d.description =
      "point-plane collision (V' = V_T - kr V_N) and contact (F' = F_T) against an infinite "
      "plane, with Coulomb friction";
  d.params = {
      pdyn::param::vec3("point", {0, 0, 0}, "m", "a point P on the plane"),
      pdyn::param::vec3("normal", {0, 0, 1}, "", "normal N, pointing to the free side").not_zero(),
      pdyn::param::real("restitution", 0.5, "", "coefficient of restitution kr")
          .at_least(0)
          .at_most(1),
      pdyn::param::real("friction", 0.0, "", "Coulomb friction coefficient mu").at_least(0),
      pdyn::param::real("epsilon", 1e-4, "m, m/s", "contact tolerance on distance and speeds")
          .greater_than(0),
  };
  d.create_collider = [](const pdyn::Params& p, const pdyn::SceneContext&) {
    return std::make_unique<Plane>(
        p.vec3("point"), p.vec3("normal"),
        pdyn::ContactModel{p.real("restitution"), p.real("friction"), p.real("epsilon")});
  };
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
