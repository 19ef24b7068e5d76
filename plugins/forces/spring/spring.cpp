// spring: Witkin's damped spring, for any number of particle pairs in one
// force object (SIGGRAPH '97 notes, "Damped Spring"):
//
//   dx = x_i - x_j,  dv = v_i - v_j,  L = |dx|
//   f_i = -[ks (L - r) + kd (dv . dx) / L] dx / L,   f_j = -f_i
//
// The damping term acts only along the spring, so it removes relative
// motion along dx without slowing rigid rotation. Potential U = ks (L-r)^2/2.
//
// The loop over the springs, the per-type coefficients, the 32-bit ids, the
// block-deterministic threads and the energy are pdyn/bonded_force.hpp's
// (BondedForce); this file gives one spring's force and its Jacobians. It
// includes that header rather than pdyn/bonded.hpp: written by hand, the law
// needs none of Harmonic's automatic differentiation (pdyn/harmonic.hpp).
#include <Eigen/Core>
#include <cmath>
#include <pdyn/bonded_force.hpp>
#include <pdyn/plugin.hpp>

namespace {

using pdyn::BondedMatrix;
using pdyn::BondedPoint;
using pdyn::BondedTerm;

struct Hooke {
  static constexpr int arity = 2;
  struct Coefficients {
    double ks = 0.0;  // N/m
    double kd = 0.0;  // N s/m
  };

  // The operations and their order are Witkin's formula as the header gives
  // it, so every thread count and both of BondedForce's accumulation phases
  // round alike. Coincident ends have no direction: the spring adds zero
  // rather than NaN (a zero-length spring at rest exerts no force anyway).
  // Undamped springs skip the velocity term altogether: its reads of both
  // ends' velocities are a third of the loop's memory traffic, and kd = 0 is
  // the common case for cloth under velocity Verlet.
  [[gnu::always_inline]] inline BondedTerm<2> operator()(const BondedPoint<2>& p,
                                                         const Coefficients& c) const {
    BondedTerm<2> t;
    const double* xi = p.x[0];
    const double* xj = p.x[1];
    const double d0 = xi[0] - xj[0], d1 = xi[1] - xj[1], d2 = xi[2] - xj[2];
    const double len = std::sqrt((d0 * d0 + d1 * d1) + d2 * d2);
    const double stretch = len - p.rest;
    // One division, not two: 1/L once, both of Witkin's divisions by L
    // multiplications by it. A division costs as much as a term's other
    // arithmetic together on a cloth (issue 46's profile).
    const double inv = 1.0 / len;
    t.energy = 0.5 * c.ks * stretch * stretch;
    double magnitude = c.ks * stretch;
    if (c.kd > 0.0) {
      const double* vi = p.v[0];
      const double* vj = p.v[1];
      const double w0 = vi[0] - vj[0], w1 = vi[1] - vj[1], w2 = vi[2] - vj[2];
      magnitude += c.kd * ((w0 * d0 + w1 * d1) + w2 * d2) * inv;
    }
    // A select, not an early return: the term then stays in registers.
    const double s = len == 0.0 ? 0.0 : -(magnitude * inv);
    t.force[0] = pdyn::Vec3(s * d0, s * d1, s * d2);
    t.force[1] = -t.force[0];
    return t;
  }

  double measure(const std::array<pdyn::Vec3, 2>& x) const { return (x[0] - x[1]).norm(); }

  // Only the damping term reads velocities: undamped springs (kd = 0) let
  // velocity Verlet reuse their forces.
  bool reads_velocity(const Coefficients& c) const { return c.kd > 0.0; }

  // Jacobians for implicit solvers. With n = dx/L and P = I - n n^T,
  //   df_i/dx_i = -ks [n n^T + (1 - r/L) P],   df_i/dv_i = -kd n n^T,
  // and the (i,j), (j,i) blocks are their negatives, (j,j) equal to (i,i).
  // Two deliberate departures from the exact derivative (exact_jacobian)
  // keep df/dx symmetric negative semidefinite, so that (M - h df/dv -
  // h^2 df/dx) stays symmetric positive definite for conjugate gradients:
  // * the geometric-stiffness factor (1 - r/L) is clamped at 0 under
  //   compression (L < r), where it would be negative and make the matrix
  //   indefinite (Choi & Ko, "Stable but responsive cloth", SIGGRAPH 2002,
  //   section 4);
  // * the damping force's position derivative,
  //   -(kd/L) [n dv^T P + (dv . n) P], which is not symmetric, is left
  //   out (Baraff & Witkin, "Large Steps in Cloth Simulation", 1998,
  //   section 5.2). It vanishes when dv = 0.
  // Elsewhere (stretched or at rest, kd = 0 or dv = 0) the blocks are the
  // exact derivatives of operator(). Given as the (i,i) blocks alone
  // (pdyn/bonded_law.hpp's pair_jacobian): BondedForce reports all four.
  bool pair_jacobian(const BondedPoint<2>& p, const Coefficients& c, Eigen::Matrix3d& k,
                     Eigen::Matrix3d& d) const {
    const pdyn::Vec3 dx = p.position(0) - p.position(1);
    const double len = dx.norm();
    if (len == 0.0) return false;  // operator() adds nothing here either
    const pdyn::Vec3 n = dx / len;
    const Eigen::Matrix3d nn = n * n.transpose();
    const double geometric = std::max(0.0, 1.0 - p.rest / len);
    k = -c.ks * (nn + geometric * (Eigen::Matrix3d::Identity() - nn));
    if (c.kd > 0.0) d = -c.kd * nn;
    return true;
  }

  // The exact derivatives, for the kit: with dv = v_i - v_j,
  //   df_i/dx_i = -ks n n^T - (kd/L) n dv^T P - [ks (1 - r/L) + kd (dv.n)/L] P.
  bool exact_jacobian(const BondedPoint<2>& p, const Coefficients& c, BondedMatrix<2>& dfdx,
                      BondedMatrix<2>& dfdv) const {
    const pdyn::Vec3 dx = p.position(0) - p.position(1);
    const pdyn::Vec3 dv = p.velocity(0) - p.velocity(1);
    const double len = dx.norm();
    if (len == 0.0) return false;
    const pdyn::Vec3 n = dx / len;
    const Eigen::Matrix3d nn = n * n.transpose();
    const Eigen::Matrix3d perp = Eigen::Matrix3d::Identity() - nn;
    const Eigen::Matrix3d kx = -c.ks * nn - (c.kd / len) * n * (perp * dv).transpose() -
                               (c.ks * (1.0 - p.rest / len) + c.kd * dv.dot(n) / len) * perp;
    blocks(kx, dfdx);
    blocks(-c.kd * nn, dfdv);
    return true;
  }

 private:
  // [[k, -k], [-k, k]]: f_j = -f_i and f depends on x_i - x_j (v_i - v_j) only.
  static void blocks(const Eigen::Matrix3d& k, BondedMatrix<2>& m) {
    m.block<3, 3>(0, 0) = k;
    m.block<3, 3>(0, 3) = -k;
    m.block<3, 3>(3, 0) = -k;
    m.block<3, 3>(3, 3) = k;
  }
};

using Spring = pdyn::BondedForce<Hooke>;

std::unique_ptr<pdyn::Force> create(const pdyn::Params& p, const pdyn::SceneContext& ctx) {
  const Hooke law;
  const auto in = pdyn::read_bonded<2>(p, ctx, "pairs", {"ks", "kd"},
                                       [&](const auto& x) { return law.measure(x); });
  std::vector<Hooke::Coefficients> c(static_cast<std::size_t>(in.n_types));
  for (std::int32_t t = 0; t < in.n_types; ++t) {
    c[static_cast<std::size_t>(t)] = {pdyn::bonded_coefficient(p, "ks", t),
                                      pdyn::bonded_coefficient(p, "kd", t)};
  }
  return std::make_unique<Spring>(law, in, std::move(c), ctx.particles.size());
}

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Force;
  d.name = "spring";
  d.version = "1.2.1";
  d.description =
      "damped springs between particle pairs: f_i = -[ks (L - r) + kd (dv.dx)/L] dx/L, f_j = -f_i";
  d.params = {
      pdyn::param::required("pairs", pdyn::ParamType::IndexPairs, "",
                            "particle pairs [[i, j], ...] joined by a spring"),
      pdyn::bonded_types_param(),
      pdyn::param::real_list("ks", 1.0, "N/m", "stiffness: one for all term types or one per type")
          .at_least(0),
      pdyn::param::real_list("kd", 0.0, "N s/m",
                             "damping along the spring: one for all term types or one per type")
          .at_least(0),
      pdyn::param::optional("rest", pdyn::ParamType::RealList, "m",
                            "rest lengths: one for all pairs or one per pair; default: the "
                            "initial distances")
          .at_least(0),
  };
  d.force_traits.internal = true;
  d.create_force = create;
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
