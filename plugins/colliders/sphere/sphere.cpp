// sphere: Witkin's collision and contact rules (pdyn/contact.hpp) against a
// sphere of centre C and radius R, keeping particles outside it (a ball, an
// obstacle) or inside it (a bowl, a container).
//
// With r = |X - C| and u = (X - C) / r:
//   outside: d = r - R, N = u      (free side: r > R)
//   inside:  d = R - r, N = -u     (free side: r < R)
// Both are exact signed distances, so putting a particle back by -d N lands
// it on the sphere. At the centre (r = 0) u is undefined; any unit vector
// will do there (+z), since the point is R away from the surface.
//
// It draws itself as a sphere through the shape hook (pdyn/shape.hpp), and
// takes its contact parameters from pdyn::with_contact_params.
#include <pdyn/contact.hpp>
#include <pdyn/plugin.hpp>
#include <pdyn/shape.hpp>

namespace {

class Sphere final : public pdyn::SurfaceCollider, public pdyn::ShapeSource {
 public:
  Sphere(const pdyn::Vec3& center, double radius, bool inside, const pdyn::ContactModel& model)
      : SurfaceCollider(model), c_(center), r_(radius), sign_(inside ? -1.0 : 1.0) {}

  pdyn::SurfacePoint surface(const pdyn::Vec3& x, int) const override {
    const pdyn::Vec3 d = x - c_;
    const double r = d.norm();
    const pdyn::Vec3 u = r > 0.0 ? pdyn::Vec3(d / r) : pdyn::Vec3::UnitZ();
    return {sign_ * (r - r_), sign_ * u};
  }

  std::vector<pdyn::Shape> shapes() const override { return {pdyn::shape::Sphere{c_, r_}}; }

 private:
  pdyn::Vec3 c_;
  double r_;
  double sign_;  // +1: particles kept outside, -1: inside
};

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Collider;
  d.name = "sphere";
  d.version = "1.0.0";
  d.description =
      "sphere |X - C| = R keeping particles outside or inside: Witkin's collision, contact and "
      "Coulomb friction";
  d.params = pdyn::with_contact_params({
      pdyn::param::vec3("center", {0, 0, 0}, "m", "centre C"),
      pdyn::param::real("radius", 1.0, "m", "radius R").greater_than(0),
      pdyn::param::boolean("inside", false, "keep particles inside the sphere instead of outside"),
  });
  d.create_collider = [](const pdyn::Params& p, const pdyn::SceneContext&) {
    return std::make_unique<Sphere>(p.vec3("center"), p.real("radius"), p.boolean("inside"),
                                    pdyn::ContactModel::from_params(p));
  };
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
