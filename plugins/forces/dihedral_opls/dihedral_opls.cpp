// dihedral_opls: the OPLS torsion of molecular force fields (Jorgensen,
// Maxwell & Tirado-Rives, J. Am. Chem. Soc. 118, 11225 (1996), eq. 3), as
// LAMMPS's `dihedral_style opls` computes it, on the dihedral angle phi of
// each quadruple [i, j, k, l] about the edge j-k (pdyn/dihedral.hpp: phi =
// 0 cis, pi trans, LAMMPS's convention and atom order):
//
//   U = K1/2 (1 + cos phi) + K2/2 (1 - cos 2 phi) + K3/2 (1 + cos 3 phi)
//       + K4/2 (1 - cos 4 phi)
//   f_a = -dU/dphi grad_a phi,
//   dU/dphi = -K1/2 sin phi + K2 sin 2 phi - 3 K3/2 sin 3 phi + 2 K4 sin 4 phi
//
// Cosines only: U is even in phi, so the sign convention of phi does not
// matter. The loop over phi and its gradient is pdyn/dihedral.hpp's
// TorsionLaw.
#include <array>
#include <cmath>
#include <pdyn/bonded_force.hpp>
#include <pdyn/dihedral.hpp>
#include <pdyn/plugin.hpp>
#include <string>

namespace {

struct Opls {
  struct Coefficients {
    double k1 = 0.0, k2 = 0.0, k3 = 0.0, k4 = 0.0;  // J
  };

  pdyn::TorsionEnergy operator()(double phi, const Coefficients& c) const {
    return {0.5 * (c.k1 * (1.0 + std::cos(phi)) + c.k2 * (1.0 - std::cos(2.0 * phi)) +
                   c.k3 * (1.0 + std::cos(3.0 * phi)) + c.k4 * (1.0 - std::cos(4.0 * phi))),
            -0.5 * c.k1 * std::sin(phi) + c.k2 * std::sin(2.0 * phi) -
                1.5 * c.k3 * std::sin(3.0 * phi) + 2.0 * c.k4 * std::sin(4.0 * phi)};
  }
};
using OplsLaw = pdyn::TorsionLaw<Opls>;

std::unique_ptr<pdyn::Force> create(const pdyn::Params& p, const pdyn::SceneContext& ctx) {
  const OplsLaw law;
  const auto in = pdyn::read_bonded<4>(p, ctx, "quads", {"k1", "k2", "k3", "k4"},
                                       [&](const auto& x) { return law.measure(x); });
  std::vector<Opls::Coefficients> c(static_cast<std::size_t>(in.n_types));
  for (std::int32_t t = 0; t < in.n_types; ++t) {
    c[static_cast<std::size_t>(t)] = {
        pdyn::bonded_coefficient(p, "k1", t), pdyn::bonded_coefficient(p, "k2", t),
        pdyn::bonded_coefficient(p, "k3", t), pdyn::bonded_coefficient(p, "k4", t)};
  }
  return std::make_unique<pdyn::BondedForce<OplsLaw>>(law, in, std::move(c), ctx.particles.size());
}

// A Fourier coefficient, required as LAMMPS's dihedral_coeff K1 K2 K3 K4
// (any sign): one value for all term types or one per type. The sample is
// what `pdyn check` builds the plugin with.
pdyn::ParamSpec coefficient(const char* name, const std::string& what, double sample) {
  return pdyn::param::required(name, pdyn::ParamType::RealList, "J",
                               what + ": one for all term types or one per type")
      .with_sample(pdyn::ParamValue(std::vector<double>{sample}));
}

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Force;
  d.name = "dihedral_opls";
  d.version = "1.0.0";
  d.description =
      "OPLS torsion, LAMMPS's dihedral_style opls: U = k1/2 (1 + cos phi) + k2/2 (1 - cos 2 phi) "
      "+ k3/2 (1 + cos 3 phi) + k4/2 (1 - cos 4 phi)";
  d.params = {
      pdyn::param::required("quads", pdyn::ParamType::IndexQuads, "",
                            "particle quadruples [[i, j, k, l], ...]: the torsion about the "
                            "edge j-k"),
      pdyn::bonded_types_param(),
      coefficient("k1", "K1, the 1-fold term", 1.3),
      coefficient("k2", "K2, the 2-fold term", -0.05),
      coefficient("k3", "K3, the 3-fold term", 0.2),
      coefficient("k4", "K4, the 4-fold term", 0.1),
  };
  d.force_traits.internal = true;
  d.create_force = create;
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
