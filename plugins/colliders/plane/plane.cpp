// plane: Witkin's point-plane collision and contact (SIGGRAPH '97 notes,
// "Bouncing off the Walls"), for the plane through P with normal N.
//
// The plane supplies only its geometry, the signed distance (X - P) . N and
// the normal N; the rules (restitution, the resting rule, contact force,
// put-back, Coulomb friction) are the kernel's, in pdyn/contact.hpp, shared
// with the sphere and box colliders. With friction 0 this is bit-identical
// to the plane collider before friction existed.
//
// It draws itself as a plane through the shape hook (pdyn/shape.hpp), and
// takes its contact parameters from pdyn::with_contact_params.
#include <pdyn/contact.hpp>
#include <pdyn/plugin.hpp>
#include <pdyn/shape.hpp>

namespace {

class Plane final : public pdyn::SurfaceCollider, public pdyn::ShapeSource {
 public:
  Plane(const pdyn::Vec3& point, const pdyn::Vec3& normal, const pdyn::ContactModel& model)
      : SurfaceCollider(model), p_(point), n_(normal.normalized()) {}

  pdyn::SurfacePoint surface(const pdyn::Vec3& x, int) const override {
    return {(x - p_).dot(n_), n_};
  }

  std::vector<pdyn::Shape> shapes() const override { return {pdyn::shape::Plane{p_, n_}}; }

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
  d.params = pdyn::with_contact_params({
      pdyn::param::vec3("point", {0, 0, 0}, "m", "a point P on the plane"),
      pdyn::param::vec3("normal", {0, 0, 1}, "", "normal N, pointing to the free side").not_zero(),
  });
  d.create_collider = [](const pdyn::Params& p, const pdyn::SceneContext&) {
    return std::make_unique<Plane>(p.vec3("point"), p.vec3("normal"),
                                   pdyn::ContactModel::from_params(p));
  };
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
