// fene: the finitely extensible nonlinear elastic bond of bead-spring
// polymers (Kremer & Grest, J. Chem. Phys. 92, 5057 (1990), eq. 2), as
// LAMMPS's `bond_style fene` computes it, with its Weeks-Chandler-Andersen
// repulsion (the Lennard-Jones potential cut at its minimum and shifted up
// by epsilon):
//
//   U(r) = -K R0^2 / 2 ln(1 - (r/R0)^2)
//          + 4 eps [(sigma/r)^12 - (sigma/r)^6] + eps      (r < 2^(1/6) sigma)
//   f_i = F (x_i - x_j),  F = -K / (1 - (r/R0)^2)
//                             + 48 eps (sigma/r)^6 [(sigma/r)^6 - 1/2] / r^2
//
// The operations are LAMMPS's (bond_fene.cpp): the repulsion where r^2 <
// 2^(1/3) sigma^2, each term's force the scalar F times the separation.
// Where LAMMPS clamps a bond stretched beyond sqrt(0.9) R0 (it warns "FENE
// bond too long" and uses 1 - (r/R0)^2 = 0.1) and stops only beyond 2 R0,
// pdyn keeps the true potential up to R0 and stops the run at R0, naming
// the bond: the potential is infinite there, and a clamped force would be
// a wrong number.
#include <array>
#include <cmath>
#include <limits>
#include <pdyn/bonded_force.hpp>
#include <pdyn/error.hpp>
#include <pdyn/plugin.hpp>
#include <string>

namespace {

using pdyn::BondedPoint;
using pdyn::BondedTerm;

struct FeneLaw {
  static constexpr int arity = 2;
  struct Coefficients {
    double k = 0.0;        // K, N/m (J/m^2)
    double r0 = 0.0;       // R0, m: the bond's greatest length
    double epsilon = 0.0;  // J: the repulsion's depth
    double sigma = 0.0;    // m: the repulsion's range
  };

  [[gnu::always_inline]] inline BondedTerm<2> operator()(const BondedPoint<2>& p,
                                                         const Coefficients& c) const {
    BondedTerm<2> t;
    const double* xi = p.x[0];
    const double* xj = p.x[1];
    const double d0 = xi[0] - xj[0], d1 = xi[1] - xj[1], d2 = xi[2] - xj[2];
    const double rsq = d0 * d0 + d1 * d1 + d2 * d2;
    const double r0sq = c.r0 * c.r0;
    // 1 - (r/R0)^2 <= 0 from R0 on, where the potential is infinite: the
    // force is NaN there (-K / rlogarg would be finite beyond R0, and point
    // the wrong way), which FeneForce turns into a message naming the bond.
    const double rlogarg = 1.0 - rsq / r0sq;
    double f = rlogarg > 0.0 ? -c.k / rlogarg : std::numeric_limits<double>::quiet_NaN();
    t.energy = -0.5 * c.k * r0sq * std::log(rlogarg);
    if (rsq < kCubeRoot2 * c.sigma * c.sigma) {
      const double sr2 = c.sigma * c.sigma / rsq;
      const double sr6 = sr2 * sr2 * sr2;
      f += 48.0 * c.epsilon * sr6 * (sr6 - 0.5) / rsq;
      t.energy += 4.0 * c.epsilon * sr6 * (sr6 - 1.0) + c.epsilon;
    }
    t.force[0] = pdyn::Vec3(f * d0, f * d1, f * d2);
    t.force[1] = -t.force[0];
    return t;
  }

  // FENE has no rest length; read_bonded measures one it does not use.
  double measure(const std::array<pdyn::Vec3, 2>& x) const { return (x[0] - x[1]).norm(); }
  bool reads_velocity(const Coefficients&) const { return false; }

  static constexpr double kCubeRoot2 = 1.2599210498948731648;  // 2^(1/3), LAMMPS's MY_CUBEROOT2
};

// BondedForce<FeneLaw>, which names a bond stretched to R0 or beyond
// instead of passing NaN on: the forces are checked once per evaluation
// (3N numbers, cheap beside the bonds), the bonds only when one failed.
class FeneForce final : public pdyn::BondedForce<FeneLaw> {
 public:
  using pdyn::BondedForce<FeneLaw>::BondedForce;

  void add_forces(const pdyn::ParticleView& p, Eigen::Ref<pdyn::Matrix3X> f) override {
    pdyn::BondedForce<FeneLaw>::add_forces(p, f);
    if (!f.allFinite()) explain_overstretched(p);
  }

 private:
  void explain_overstretched(const pdyn::ParticleView& p) const {
    std::array<pdyn::Vec3, 4> force;
    for (pdyn::Index s = 0; s < bonded_terms(); ++s) {
      bonded_term_forces(p, s, force);
      if (force[0].allFinite()) continue;
      const auto ends = bonded_term(s);
      const double r = p.domain.minimum_image(p.x.col(ends[0]) - p.x.col(ends[1])).norm();
      const std::string bond = "the FENE bond between particles " + std::to_string(ends[0]) +
                               " and " + std::to_string(ends[1]);
      if (r == 0.0) {
        throw pdyn::Error(bond + " has both particles at one place at t = " + std::to_string(p.t) +
                          " s, where its repulsion is infinite");
      }
      throw pdyn::Error(bond + " is stretched to " + std::to_string(r) +
                        " m at t = " + std::to_string(p.t) +
                        " s, where the potential is infinite (expected every bond shorter than "
                        "its r0: a smaller time step, or a start nearer rest; LAMMPS would clamp "
                        "it with the warning 'FENE bond too long')");
    }
  }
};

std::unique_ptr<pdyn::Force> create(const pdyn::Params& p, const pdyn::SceneContext& ctx) {
  const FeneLaw law;
  const auto in = pdyn::read_bonded<2>(p, ctx, "pairs", {"k", "r0", "epsilon", "sigma"},
                                       [&](const auto& x) { return law.measure(x); });
  std::vector<FeneLaw::Coefficients> c(static_cast<std::size_t>(in.n_types));
  for (std::int32_t t = 0; t < in.n_types; ++t) {
    c[static_cast<std::size_t>(t)] = {
        pdyn::bonded_coefficient(p, "k", t), pdyn::bonded_coefficient(p, "r0", t),
        pdyn::bonded_coefficient(p, "epsilon", t), pdyn::bonded_coefficient(p, "sigma", t)};
  }
  return std::make_unique<FeneForce>(law, in, std::move(c), ctx.particles.size());
}

// A required per-type coefficient: one value for all term types or one per type.
pdyn::ParamSpec coefficient(const char* name, const char* unit, const std::string& what,
                            double sample) {
  return pdyn::param::required(name, pdyn::ParamType::RealList, unit,
                               what + ": one for all term types or one per type")
      .with_sample(pdyn::ParamValue(std::vector<double>{sample}));
}

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Force;
  d.name = "fene";
  d.version = "1.0.0";
  d.description =
      "FENE bonds with WCA repulsion, LAMMPS's bond_style fene: U = -k r0^2/2 ln(1 - (r/r0)^2) + "
      "4 eps [(sigma/r)^12 - (sigma/r)^6] + eps for r < 2^(1/6) sigma";
  d.params = {
      pdyn::param::required("pairs", pdyn::ParamType::IndexPairs, "",
                            "particle pairs [[i, j], ...] joined by a FENE bond"),
      pdyn::bonded_types_param(),
      // Required, as LAMMPS's bond_coeff K R0 epsilon sigma (Kremer-Grest:
      // 30, 1.5, 1, 1). The samples are for `pdyn check`, whose random
      // states place particles up to 2 sqrt(3) m apart and step them for
      // 0.5 s: r0 = 5 m keeps them all within reach, k = 1 N/m and sigma = 0.1 m keep
      // the bonds and the repulsion from flinging them apart.
      coefficient("k", "N/m", "K, the stiffness", 1.0).at_least(0),
      coefficient("r0", "m", "R0, the greatest length", 5.0).greater_than(0),
      coefficient("epsilon", "J", "the repulsion's depth", 1.0).at_least(0),
      coefficient("sigma", "m", "the repulsion's range", 0.1).at_least(0),
  };
  d.force_traits.internal = true;
  d.force_traits.singular = true;
  d.create_force = create;
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
