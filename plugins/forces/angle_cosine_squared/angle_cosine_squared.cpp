// angle_cosine_squared: LAMMPS's `angle_style cosine/squared`, a bending
// term on the cosine of the angle theta at the middle particle j of each
// triple [i, j, k]:
//
//   U = K (cos theta - cos theta0)^2,   f_a = -2 K (cos theta - cos theta0) grad_a cos theta
//
// with a = x_i - x_j, b = x_k - x_j, c = cos theta = a.b / (|a| |b|) and
//
//   dc/dx_i = (b/|b| - c a/|a|) / |a|,   dc/dx_k = (a/|a| - c b/|b|) / |b|,
//   dc/dx_j = -(dc/dx_i + dc/dx_k).
//
// The cosine's gradient has no singularity at 0 or pi (unlike theta's), so
// a straight triple is handled like any other; only coincident particles
// (|a| or |b| = 0) leave it undefined, and the term then adds no force.
// K is LAMMPS's, without a 1/2 (its angle_coeff K theta0, theta0 here in
// rad).
#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <pdyn/bonded_force.hpp>
#include <pdyn/plugin.hpp>
#include <string>

namespace {

using pdyn::BondedPoint;
using pdyn::BondedTerm;
using pdyn::Vec3;

struct CosineSquared {
  static constexpr int arity = 3;
  struct Coefficients {
    double k = 0.0;       // K, J
    double cos_rest = 1;  // cos theta0
  };

  BondedTerm<3> operator()(const BondedPoint<3>& p, const Coefficients& c) const {
    BondedTerm<3> t;
    const Vec3 a = p.position(0) - p.position(1), b = p.position(2) - p.position(1);
    const double la = a.norm(), lb = b.norm();
    if (!(la > 0.0) || !(lb > 0.0)) return t;
    const Vec3 ua = a / la, ub = b / lb;
    const double cosine = ua.dot(ub), d = cosine - c.cos_rest;
    t.energy = c.k * d * d;
    const Vec3 gi = (ub - cosine * ua) / la, gk = (ua - cosine * ub) / lb;
    const double s = -2.0 * c.k * d;
    t.force[0] = s * gi;
    t.force[2] = s * gk;
    t.force[1] = -(t.force[0] + t.force[2]);
    return t;
  }

  // The angle, rad, for `rest` (theta0) when it is not given.
  double measure(const std::array<Vec3, 3>& x) const {
    const Vec3 a = x[0] - x[1], b = x[2] - x[1];
    return std::atan2(a.cross(b).norm(), a.dot(b));
  }
  bool reads_velocity(const Coefficients&) const { return false; }
};

// The rest angle is a per-type coefficient here, as LAMMPS's theta0.
std::unique_ptr<pdyn::Force> create(const pdyn::Params& p, const pdyn::SceneContext& ctx) {
  const CosineSquared law;
  const auto in = pdyn::read_bonded<3>(p, ctx, "triples", {"k", "theta0"},
                                       [&](const auto& x) { return law.measure(x); });
  std::vector<CosineSquared::Coefficients> c(static_cast<std::size_t>(in.n_types));
  for (std::int32_t t = 0; t < in.n_types; ++t) {
    c[static_cast<std::size_t>(t)] = {pdyn::bonded_coefficient(p, "k", t),
                                      std::cos(pdyn::bonded_coefficient(p, "theta0", t))};
  }
  return std::make_unique<pdyn::BondedForce<CosineSquared>>(law, in, std::move(c),
                                                            ctx.particles.size());
}

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Force;
  d.name = "angle_cosine_squared";
  d.version = "1.0.0";
  d.description =
      "bending on the cosine of the angle at the middle particle, LAMMPS's angle_style "
      "cosine/squared: U = k (cos theta - cos theta0)^2";
  d.params = {
      pdyn::param::required("triples", pdyn::ParamType::IndexTriples, "",
                            "particle triples [[i, j, k], ...]; the angle is at the middle one j"),
      pdyn::bonded_types_param(),
      pdyn::param::required("k", pdyn::ParamType::RealList, "J",
                            "K (no 1/2): one for all term types or one per type")
          .with_sample(pdyn::ParamValue(std::vector<double>{2.0})),
      pdyn::param::required("theta0", pdyn::ParamType::RealList, "rad",
                            "the rest angle: one for all term types or one per type")
          .at_least(0)
          .at_most(3.141592653589793)
          .with_sample(pdyn::ParamValue(std::vector<double>{1.9})),
  };
  d.force_traits.internal = true;
  d.create_force = create;
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
