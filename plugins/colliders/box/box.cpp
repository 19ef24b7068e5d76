// box: Witkin's collision and contact rules (pdyn/contact.hpp) against an
// axis-aligned box [min, max], keeping particles outside it (a solid block)
// or inside it (a container).
//
// Outside (one surface): the exact signed distance of a box. With centre c,
// half extents e and q = |X - c| - e per axis: outside the box (some q_k > 0)
// d = |max(q, 0)| and N points from the nearest box point to X (a face, edge
// or corner normal); inside (all q_k <= 0) d = max_k q_k, the face of least
// penetration, with N that face's outward normal, so put-back moves X the
// shortest way out.
//
// Inside (six surfaces): the box is the intersection of six half-spaces, so
// each wall is a plane of its own, d = X_a - min_a with N = +e_a and
// d = max_a - X_a with N = -e_a. Treating them separately makes a particle
// that leaves through an edge or corner bounce off every wall it crossed
// and be put back onto all of them, and lets a particle rest in a corner.
//
// It draws itself as a box through the shape hook (pdyn/shape.hpp), and
// takes its contact parameters from pdyn::with_contact_params.
#include <fmt/format.h>

#include <pdyn/contact.hpp>
#include <pdyn/plugin.hpp>
#include <pdyn/shape.hpp>

namespace {

using pdyn::Vec3;

class Box final : public pdyn::SurfaceCollider, public pdyn::ShapeSource {
 public:
  Box(const Vec3& lo, const Vec3& hi, bool inside, const pdyn::ContactModel& model)
      : SurfaceCollider(model), lo_(lo), hi_(hi), inside_(inside) {}

  int surface_count() const noexcept override { return inside_ ? 6 : 1; }

  pdyn::SurfacePoint surface(const Vec3& x, int k) const override {
    if (inside_) {
      const int a = k / 2;
      if (k % 2 == 0) return {x[a] - lo_[a], Vec3::Unit(a)};
      return {hi_[a] - x[a], -Vec3::Unit(a)};
    }
    const Vec3 c = 0.5 * (lo_ + hi_), e = 0.5 * (hi_ - lo_);
    const Vec3 rel = x - c;
    const Vec3 q = rel.cwiseAbs() - e;
    const Vec3 sign = rel.unaryExpr([](double r) { return r < 0.0 ? -1.0 : 1.0; });
    const Vec3 out = q.cwiseMax(0.0);
    const double d_out = out.norm();
    if (d_out > 0.0) return {d_out, sign.cwiseProduct(out) / d_out};
    Eigen::Index a = 0;
    const double d_in = q.maxCoeff(&a);
    return {d_in, sign[a] * Vec3::Unit(a)};
  }

  std::vector<pdyn::Shape> shapes() const override { return {pdyn::shape::Box{lo_, hi_}}; }

 private:
  Vec3 lo_, hi_;
  bool inside_;
};

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Collider;
  d.name = "box";
  d.version = "1.0.0";
  d.description =
      "axis-aligned box [min, max] keeping particles outside or inside: Witkin's collision, "
      "contact and Coulomb friction";
  d.params = pdyn::with_contact_params({
      pdyn::param::vec3("min", {-0.5, -0.5, -0.5}, "m", "corner with the smallest coordinates"),
      pdyn::param::vec3("max", {0.5, 0.5, 0.5}, "m", "corner with the largest coordinates"),
      pdyn::param::boolean("inside", false, "keep particles inside the box instead of outside"),
  });
  d.create_collider = [](const pdyn::Params& p, const pdyn::SceneContext&) {
    const Vec3 lo = p.vec3("min"), hi = p.vec3("max");
    for (int a = 0; a < 3; ++a) {
      if (!(lo[a] < hi[a])) {
        throw pdyn::ParamError(
            "max", fmt::format("[{}, {}, {}] is not above min [{}, {}, {}] in {} (expected max > "
                               "min in every component)",
                               hi.x(), hi.y(), hi.z(), lo.x(), lo.y(), lo.z(), "xyz"[a]));
      }
    }
    return std::make_unique<Box>(lo, hi, p.boolean("inside"), pdyn::ContactModel::from_params(p));
  };
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
