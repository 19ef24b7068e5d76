// dihedral_harmonic: LAMMPS's `dihedral_style harmonic`, the periodic
// torsion of CHARMM-like force fields on the dihedral angle phi of each
// quadruple [i, j, k, l] about its edge j-k (pdyn/dihedral.hpp: phi = 0
// cis, pi trans, LAMMPS's convention and atom order):
//
//   U = K [1 + d cos(n phi)],   d = +1 or -1, n = 0, 1, 2, ...
//   f_a = -dU/dphi grad_a phi,   dU/dphi = -K d n sin(n phi)
//
// (not pdyn's `dihedral`, a spring k/2 (phi - phi0)^2 on the angle itself).
// The loop over phi and its gradient is pdyn/dihedral.hpp's TorsionLaw.
#include <array>
#include <cmath>
#include <pdyn/bonded_force.hpp>
#include <pdyn/dihedral.hpp>
#include <pdyn/plugin.hpp>

namespace {

struct Periodic {
  struct Coefficients {
    double k = 0.0;     // K, J
    double sign = 1.0;  // d: +1 or -1
    double n = 1.0;     // multiplicity, a whole number >= 0
  };

  pdyn::TorsionEnergy operator()(double phi, const Coefficients& c) const {
    return {c.k * (1.0 + c.sign * std::cos(c.n * phi)), -c.k * c.sign * c.n * std::sin(c.n * phi)};
  }
};
using PeriodicLaw = pdyn::TorsionLaw<Periodic>;

std::unique_ptr<pdyn::Force> create(const pdyn::Params& p, const pdyn::SceneContext& ctx) {
  const PeriodicLaw law;
  const auto in = pdyn::read_bonded<4>(p, ctx, "quads", {"k", "d", "n"},
                                       [&](const auto& x) { return law.measure(x); });
  std::vector<PeriodicLaw::Coefficients> c(static_cast<std::size_t>(in.n_types));
  for (std::int32_t t = 0; t < in.n_types; ++t) {
    const double sign = pdyn::bonded_coefficient(p, "d", t);
    const double n = pdyn::bonded_coefficient(p, "n", t);
    if (sign != 1.0 && sign != -1.0) {
      throw pdyn::ParamError("d", "is " + std::to_string(sign) + " for type " + std::to_string(t) +
                                      " (expected 1 or -1)");
    }
    if (n != std::floor(n)) {
      throw pdyn::ParamError("n", "is " + std::to_string(n) + " for type " + std::to_string(t) +
                                      " (expected a whole number >= 0)");
    }
    c[static_cast<std::size_t>(t)] = {pdyn::bonded_coefficient(p, "k", t), sign, n};
  }
  return std::make_unique<pdyn::BondedForce<PeriodicLaw>>(law, in, std::move(c),
                                                          ctx.particles.size());
}

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Force;
  d.name = "dihedral_harmonic";
  d.version = "1.0.0";
  d.description =
      "periodic torsion, LAMMPS's dihedral_style harmonic: U = k [1 + d cos(n phi)] on the "
      "dihedral angle phi of each quadruple";
  d.params = {
      pdyn::param::required("quads", pdyn::ParamType::IndexQuads, "",
                            "particle quadruples [[i, j, k, l], ...]: the torsion about the "
                            "edge j-k"),
      pdyn::bonded_types_param(),
      pdyn::param::required("k", pdyn::ParamType::RealList, "J",
                            "K: one for all term types or one per type")
          .with_sample(pdyn::ParamValue(std::vector<double>{1.5})),
      pdyn::param::required("d", pdyn::ParamType::RealList, "",
                            "the sign d, 1 or -1: one for all term types or one per type")
          .at_least(-1)
          .at_most(1)
          .with_sample(pdyn::ParamValue(std::vector<double>{-1.0})),
      pdyn::param::required("n", pdyn::ParamType::RealList, "",
                            "the multiplicity n, a whole number: one for all term types or one "
                            "per type")
          .at_least(0)
          .with_sample(pdyn::ParamValue(std::vector<double>{3.0})),
  };
  d.force_traits.internal = true;
  d.create_force = create;
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
