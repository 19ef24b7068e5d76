// angle: a damped bending spring on the angle at the middle particle of each
// triple [i, j, k], the rope's bending stiffness. With a = x_i - x_j,
// b = x_k - x_j:
//
//   theta = atan2(|a x b|, a . b)                     in [0, pi]
//   U     = k/2 (theta - theta0)^2
//   f     = -[k (theta - theta0) + kd dtheta/dt] grad theta,
//   dtheta/dt = grad theta . v
//
// atan2 rather than acos(a.b / |a||b|): acos loses all precision near 0 and
// pi, where its derivative -1/sqrt(1 - c^2) blows up, while atan2 of the two
// well-conditioned quantities |a x b| and a.b is accurate everywhere.
// Differentiating theta = atan2(s, d), s = |a x b|, d = a.b, n = (a x b)/s:
//
//   dtheta/da = (d (b x n) - s b) / (|a|^2 |b|^2)
//   dtheta/db = (d (n x a) - s a) / (|a|^2 |b|^2)
//   dtheta/dx_i = dtheta/da,  dtheta/dx_k = dtheta/db,
//   dtheta/dx_j = -(dtheta/da + dtheta/db)
//
// |grad theta| is 1/|a| (resp. 1/|b|) at any angle, but its direction is
// undefined when the particles are collinear (s = 0, the tip of a cone in
// theta) or coincide: there the triple adds nothing. For a straight rope
// (theta0 = pi) that is the continuous limit, since theta - theta0 -> 0.
//
// theta is invariant under rigid motions, so grad theta sums to zero and has
// zero moment: the force is internal. The damping term is the bending
// analogue of Witkin's spring damping (SIGGRAPH '97 notes, "Damped Spring"):
// it resists only the rate of bending, f . v = -kd (dtheta/dt)^2 <= 0.
#include <fmt/format.h>

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>
#include <pdyn/plugin.hpp>

namespace {

using pdyn::Index;
using pdyn::IndexTriple;
using pdyn::Vec3;

struct Bend {
  double theta = 0.0;  // rad
  Vec3 ga, gb;         // dtheta/dx_i, dtheta/dx_k (dtheta/dx_j = -(ga + gb)), 1/m
  bool has_gradient = false;
};

Bend bend(const Vec3& xi, const Vec3& xj, const Vec3& xk) {
  Bend r;
  const Vec3 a = xi - xj, b = xk - xj;
  const Vec3 c = a.cross(b);
  const double s = c.norm(), d = a.dot(b);
  r.theta = std::atan2(s, d);
  const double aabb = a.squaredNorm() * b.squaredNorm();
  if (s == 0.0 || !(aabb > 0.0) || !std::isfinite(aabb)) return r;
  const Vec3 n = c / s;
  r.ga = (d * b.cross(n) - s * b) / aabb;
  r.gb = (d * n.cross(a) - s * a) / aabb;
  r.has_gradient = r.ga.allFinite() && r.gb.allFinite();
  return r;
}

class Angle final : public pdyn::Force {
 public:
  Angle(std::vector<IndexTriple> triples, std::vector<double> rest, double k, double kd)
      : triples_(std::move(triples)), rest_(std::move(rest)), k_(k), kd_(kd) {}

  void add_forces(const pdyn::ParticleView& p, Eigen::Ref<pdyn::Matrix3X> f) override {
    for (std::size_t s = 0; s < triples_.size(); ++s) {
      const auto [i, j, k] = triples_[s];
      const Bend b = bend(p.x.col(i), p.x.col(j), p.x.col(k));
      if (!b.has_gradient) continue;
      const Vec3 gj = -(b.ga + b.gb);
      const double rate = b.ga.dot(p.v.col(i)) + gj.dot(p.v.col(j)) + b.gb.dot(p.v.col(k));
      const double magnitude = k_ * (b.theta - rest_[s]) + kd_ * rate;
      f.col(i) -= magnitude * b.ga;
      f.col(j) -= magnitude * gj;
      f.col(k) -= magnitude * b.gb;
    }
  }

  // Only the damping term reads velocities.
  pdyn::StateDependence dependence() const override { return {kd_ > 0.0, false}; }

  std::optional<double> potential_energy(const pdyn::ParticleView& p) const override {
    double u = 0.0;
    for (std::size_t s = 0; s < triples_.size(); ++s) {
      const auto [i, j, k] = triples_[s];
      const double bent = bend(p.x.col(i), p.x.col(j), p.x.col(k)).theta - rest_[s];
      u += 0.5 * k_ * bent * bent;
    }
    return u;
  }

 private:
  std::vector<IndexTriple> triples_;
  std::vector<double> rest_;  // rest angle of each triple, rad
  double k_, kd_;
};

std::unique_ptr<pdyn::Force> create(const pdyn::Params& p, const pdyn::SceneContext& ctx) {
  pdyn::require_distinct_particles(p, "triples");
  const auto& triples = p.triples("triples");
  std::vector<double> rest =
      pdyn::rest_values(p, "rest", triples.size(), "triples", [&](std::size_t s) {
        const auto [i, j, k] = triples[s];
        return bend(ctx.particles.x.col(i), ctx.particles.x.col(j), ctx.particles.x.col(k)).theta;
      });
  return std::make_unique<Angle>(triples, std::move(rest), p.real("k"), p.real("kd"));
}

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Force;
  d.name = "angle";
  d.version = "1.0.0";
  d.description =
      "damped bending spring on the angle at j of each triple [i, j, k]: U = k/2 (theta - "
      "theta0)^2, f = -[k (theta - theta0) + kd dtheta/dt] grad theta";
  d.params = {
      pdyn::param::required("triples", pdyn::ParamType::IndexTriples, "",
                            "particle triples [[i, j, k], ...]; the angle is at the middle one j"),
      pdyn::param::real("k", 1.0, "N m/rad", "bending stiffness").at_least(0),
      pdyn::param::real("kd", 0.0, "N m s/rad", "damping of the bending rate").at_least(0),
      pdyn::param::optional("rest", pdyn::ParamType::RealList, "rad",
                            "rest angles: one for all triples or one per triple; default: the "
                            "initial angles")
          .at_least(0)
          .at_most(std::numbers::pi),
  };
  d.force_traits.internal = true;
  d.create_force = create;
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
