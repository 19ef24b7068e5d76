// improper_harmonic: LAMMPS's `improper_style harmonic`, keeping four
// particles [i, j, k, l] near an improper angle chi0:
//
//   U = K (chi - chi0)^2          (no 1/2, as LAMMPS)
//
// where chi in [0, pi] is the angle between the planes (i, j, k) and
// (j, k, l), LAMMPS's definition: the unsigned dihedral angle about the
// edge j-k, chi = |phi| with phi from pdyn/dihedral.hpp. So
//
//   f_a = -dU/dphi grad_a phi,   dU/dphi = 2 K (|phi| - chi0) sign(phi).
//
// With chi0 = 0 (keeping a centre planar) U = K phi^2 is smooth. With chi0
// > 0, U has a kink at phi = 0 (both sides measure chi = 0), as in LAMMPS;
// exactly there the term adds no force. Where phi has no gradient (a
// degenerate triangle or edge) the term adds its energy and no force.
#include <array>
#include <cmath>
#include <numbers>
#include <pdyn/bonded_force.hpp>
#include <pdyn/dihedral.hpp>
#include <pdyn/plugin.hpp>

namespace {

struct Improper {
  struct Coefficients {
    double k = 0.0;     // K, J/rad^2
    double chi0 = 0.0;  // rad, in [0, pi]
  };

  pdyn::TorsionEnergy operator()(double phi, const Coefficients& c) const {
    const double d = std::abs(phi) - c.chi0;
    const double sign = phi > 0.0 ? 1.0 : phi < 0.0 ? -1.0 : 0.0;
    return {c.k * d * d, 2.0 * c.k * d * sign};
  }
};
using ImproperLaw = pdyn::TorsionLaw<Improper>;

std::unique_ptr<pdyn::Force> create(const pdyn::Params& p, const pdyn::SceneContext& ctx) {
  const ImproperLaw law;
  const auto in = pdyn::read_bonded<4>(p, ctx, "quads", {"k", "chi0"},
                                       [&](const auto& x) { return law.measure(x); });
  std::vector<ImproperLaw::Coefficients> c(static_cast<std::size_t>(in.n_types));
  for (std::int32_t t = 0; t < in.n_types; ++t) {
    c[static_cast<std::size_t>(t)] = {pdyn::bonded_coefficient(p, "k", t),
                                      pdyn::bonded_coefficient(p, "chi0", t)};
  }
  return std::make_unique<pdyn::BondedForce<ImproperLaw>>(law, in, std::move(c),
                                                          ctx.particles.size());
}

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Force;
  d.name = "improper_harmonic";
  d.version = "1.0.0";
  d.description =
      "improper angle spring, LAMMPS's improper_style harmonic: U = k (chi - chi0)^2, chi the "
      "angle between the planes (i, j, k) and (j, k, l)";
  d.params = {
      pdyn::param::required("quads", pdyn::ParamType::IndexQuads, "",
                            "particle quadruples [[i, j, k, l], ...]: the planes (i, j, k) and "
                            "(j, k, l)"),
      pdyn::bonded_types_param(),
      pdyn::param::required("k", pdyn::ParamType::RealList, "J/rad^2",
                            "K (no 1/2): one for all term types or one per type")
          .at_least(0)
          .with_sample(pdyn::ParamValue(std::vector<double>{1.5})),
      pdyn::param::required("chi0", pdyn::ParamType::RealList, "rad",
                            "the rest angle: one for all term types or one per type")
          .at_least(0)
          .at_most(std::numbers::pi)
          .with_sample(pdyn::ParamValue(std::vector<double>{0.0})),
  };
  d.force_traits.internal = true;
  d.create_force = create;
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
