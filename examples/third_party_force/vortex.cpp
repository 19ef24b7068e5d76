// vortex: a swirling force field around an axis, as an out-of-tree pdyn
// plugin. For the axis through `center` with unit direction a, and r the
// particle's offset from the axis (r = d - (d.a) a, d = x - center):
//
//   f = strength (a x r) / (|r|^2 + core^2)
//
// Far from the axis the field falls off like 1/|r| (a line vortex, the
// tangential force of a free vortex); the core radius keeps it finite on the
// axis, where it vanishes. The field has a curl, so it has no potential
// energy; it depends on absolute position, so it is not internal; it can do
// positive work, so it is not dissipative.
#include <Eigen/Geometry>  // cross()
#include <pdyn/plugin.hpp>

namespace {

class Vortex final : public pdyn::Force {
 public:
  Vortex(const pdyn::Vec3& center, const pdyn::Vec3& axis, double strength, double core)
      : c_(center), a_(axis.normalized()), s_(strength), core2_(core * core) {}

  void add_forces(const pdyn::ParticleView& p, Eigen::Ref<pdyn::Matrix3X> f) override {
    for (pdyn::Index i = 0; i < p.size(); ++i) {
      const pdyn::Vec3 d = p.x.col(i) - c_;
      const pdyn::Vec3 r = d - d.dot(a_) * a_;
      f.col(i) += (s_ / (r.squaredNorm() + core2_)) * a_.cross(r);
    }
  }

 private:
  pdyn::Vec3 c_, a_;
  double s_, core2_;
};

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Force;
  d.name = "vortex";
  d.version = "1.0.0";
  d.description =
      "swirl around an axis: f = s (a x r) / (|r|^2 + core^2), r the offset from the axis";
  d.params = {
      pdyn::param::vec3("center", {0, 0, 0}, "m", "a point on the vortex axis"),
      pdyn::param::vec3("axis", {0, 0, 1}, "", "direction a of the axis (normalised)").not_zero(),
      pdyn::param::real("strength", 1.0, "N m",
                        "strength s; positive swirls counter-clockwise about a"),
      pdyn::param::real("core", 0.1, "m", "core radius: keeps the force finite on the axis")
          .greater_than(0),
  };
  // Not internal (depends on absolute position), not dissipative, no potential.
  d.create_force = [](const pdyn::Params& p, const pdyn::SceneContext&) {
    return std::make_unique<Vortex>(p.vec3("center"), p.vec3("axis"), p.real("strength"),
                                    p.real("core"));
  };
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
