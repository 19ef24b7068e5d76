// area: a damped spring on the area of each triangle [i, j, k], for 2-D soft
// bodies and membranes. With e1 = x_j - x_i, e2 = x_k - x_i, c = e1 x e2:
//
//   A = |c| / 2                                        (unsigned, in 3-D)
//   U = k/2 (A - A0)^2
//   f = -[k (A - A0) + kd dA/dt] grad A,   dA/dt = grad A . v
//
// and, with n = c / |c|, the gradient of A with respect to each corner is
// half the normal crossed with the opposite edge, pointing away from it in
// the triangle's plane:
//
//   dA/dx_i = n x (x_k - x_j) / 2,  dA/dx_j = n x (x_i - x_k) / 2,
//   dA/dx_k = n x (x_j - x_i) / 2
//
// The unsigned 3-D area is used rather than the signed area in a fixed
// plane: it needs no plane to be chosen, works for triangles anywhere in
// space (a membrane in 3-D, or a 2-D body in any plane), and is invariant
// under every rigid motion, so the force is internal (zero net force and
// torque). The price: it does not resist inversion, since a triangle folded
// through zero area has the same A as before. A degenerate triangle (A = 0:
// coincident or collinear corners) has no normal; there the triple adds no
// force, and never NaN.
#include <fmt/format.h>

#include <Eigen/Geometry>
#include <cmath>
#include <pdyn/plugin.hpp>

namespace {

using pdyn::Index;
using pdyn::IndexTriple;
using pdyn::Vec3;

struct Triangle {
  double area = 0.0;  // m^2
  Vec3 gi, gj, gk;    // dA/dx of each corner, m
  bool has_gradient = false;
};

Triangle triangle(const Vec3& xi, const Vec3& xj, const Vec3& xk) {
  Triangle t;
  const Vec3 c = (xj - xi).cross(xk - xi);
  const double len = c.norm();
  t.area = 0.5 * len;
  if (!(len > 0.0) || !std::isfinite(len)) return t;
  const Vec3 half_n = (0.5 / len) * c;
  t.gi = half_n.cross(xk - xj);
  t.gj = half_n.cross(xi - xk);
  t.gk = half_n.cross(xj - xi);
  t.has_gradient = true;
  return t;
}

class Area final : public pdyn::Force {
 public:
  Area(std::vector<IndexTriple> triples, std::vector<double> rest, double k, double kd)
      : triples_(std::move(triples)), rest_(std::move(rest)), k_(k), kd_(kd) {}

  void add_forces(const pdyn::ParticleView& p, Eigen::Ref<pdyn::Matrix3X> f) override {
    for (std::size_t s = 0; s < triples_.size(); ++s) {
      const auto [i, j, k] = triples_[s];
      const Triangle t = triangle(p.x.col(i), p.x.col(j), p.x.col(k));
      if (!t.has_gradient) continue;
      const double rate = t.gi.dot(p.v.col(i)) + t.gj.dot(p.v.col(j)) + t.gk.dot(p.v.col(k));
      const double magnitude = k_ * (t.area - rest_[s]) + kd_ * rate;
      f.col(i) -= magnitude * t.gi;
      f.col(j) -= magnitude * t.gj;
      f.col(k) -= magnitude * t.gk;
    }
  }

  // Only the damping term reads velocities.
  pdyn::StateDependence dependence() const override { return {kd_ > 0.0, false}; }

  std::optional<double> potential_energy(const pdyn::ParticleView& p) const override {
    double u = 0.0;
    for (std::size_t s = 0; s < triples_.size(); ++s) {
      const auto [i, j, k] = triples_[s];
      const double d = triangle(p.x.col(i), p.x.col(j), p.x.col(k)).area - rest_[s];
      u += 0.5 * k_ * d * d;
    }
    return u;
  }

 private:
  std::vector<IndexTriple> triples_;
  std::vector<double> rest_;  // rest area of each triangle, m^2
  double k_, kd_;
};

std::unique_ptr<pdyn::Force> create(const pdyn::Params& p, const pdyn::SceneContext& ctx) {
  pdyn::require_distinct_particles(p, "triples");
  const auto& triples = p.triples("triples");
  std::vector<double> rest =
      pdyn::rest_values(p, "rest", triples.size(), "triples", [&](std::size_t s) {
        const auto [i, j, k] = triples[s];
        return triangle(ctx.particles.x.col(i), ctx.particles.x.col(j), ctx.particles.x.col(k))
            .area;
      });
  return std::make_unique<Area>(triples, std::move(rest), p.real("k"), p.real("kd"));
}

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Force;
  d.name = "area";
  d.version = "1.0.0";
  d.description =
      "damped spring on the area A = |(x_j - x_i) x (x_k - x_i)|/2 of each triangle: U = k/2 (A - "
      "A0)^2, f = -[k (A - A0) + kd dA/dt] grad A";
  d.params = {
      pdyn::param::required("triples", pdyn::ParamType::IndexTriples, "",
                            "triangles [[i, j, k], ...] of particle indices"),
      pdyn::param::real("k", 1.0, "N/m^3", "area stiffness (U = k/2 (A - A0)^2)").at_least(0),
      pdyn::param::real("kd", 0.0, "N s/m^3", "damping of the rate of change of area").at_least(0),
      pdyn::param::optional("rest", pdyn::ParamType::RealList, "m^2",
                            "rest areas: one for all triangles or one per triangle; default: the "
                            "initial areas")
          .at_least(0),
  };
  d.force_traits.internal = true;
  d.create_force = create;
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
