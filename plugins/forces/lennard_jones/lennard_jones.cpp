// lennard_jones: the 12-6 Lennard-Jones pair potential (Jones 1924; the
// form of LAMMPS's pair style lj/cut), cut off at rc and optionally shifted
// so that U(rc) = 0:
//
//   U(r) = 4 eps [ (sigma/r)^12 - (sigma/r)^6 ] - U_shift,   r < rc
//   F_ij = 24 eps [ 2 (sigma/r)^12 - (sigma/r)^6 ] / r^2 (x_i - x_j)
//
// with U_shift = 4 eps [ (sigma/rc)^12 - (sigma/rc)^6 ] when `shift` is on,
// else 0 (the force is the same either way: shifting only moves the energy).
// The loop, neighbor list, threads and periodic images are the kernel's
// (pdyn/pair.hpp); this file is the law. It is evaluated as LAMMPS does,
// r6inv (lj1 r6inv - lj2) r2inv with lj1 = 48 eps sigma^12 and
// lj2 = 24 eps sigma^6, so that the two programs round alike.
#include <cmath>
#include <pdyn/pair.hpp>
#include <pdyn/plugin.hpp>
#include <pdyn/selection.hpp>

namespace {

struct LennardJones {
  double lj1, lj2, lj3, lj4;  // 48 eps s^12, 24 eps s^6, 4 eps s^12, 4 eps s^6
  double offset;              // U_shift, J

  LennardJones(double epsilon, double sigma, double cutoff, bool shift) {
    const double s6 = std::pow(sigma, 6.0), s12 = s6 * s6;
    lj1 = 48.0 * epsilon * s12;
    lj2 = 24.0 * epsilon * s6;
    lj3 = 4.0 * epsilon * s12;
    lj4 = 4.0 * epsilon * s6;
    const double rc6inv = 1.0 / std::pow(cutoff, 6.0);
    offset = shift ? rc6inv * (lj3 * rc6inv - lj4) : 0.0;
  }

  pdyn::PairTerm operator()(double r2, std::int32_t, std::int32_t) const {
    const double r2inv = 1.0 / r2;
    const double r6inv = r2inv * r2inv * r2inv;
    return {r6inv * (lj3 * r6inv - lj4) - offset, r6inv * (lj1 * r6inv - lj2) * r2inv};
  }
};

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Force;
  d.name = "lennard_jones";
  d.version = "1.0.0";
  d.description =
      "12-6 Lennard-Jones pair potential U = 4 eps [(sigma/r)^12 - (sigma/r)^6] within a cutoff, "
      "optionally shifted to U(rc) = 0";
  d.params = {
      pdyn::param::real("epsilon", 1.0, "J", "depth of the potential well").greater_than(0),
      pdyn::param::real("sigma", 1.0, "m", "distance at which U = 0").greater_than(0),
      pdyn::param::real("cutoff", 2.5, "m", "no interaction beyond this distance rc")
          .greater_than(0),
      pdyn::param::boolean("shift", false, "shift the energy so that U(rc) = 0"),
      pdyn::param::real("skin", 0.3, "m", "neighbor-list skin: rebuilt after a move of skin/2")
          .at_least(0),
  };
  for (auto& s : pdyn::selection_params()) d.params.push_back(std::move(s));
  d.force_traits.internal = true;  // central pair forces: momentum and angular momentum kept
  d.force_traits.singular = true;  // U -> infinity as r -> 0
  d.create_force = [](const pdyn::Params& p, const pdyn::SceneContext& ctx) {
    const double cutoff = p.real("cutoff"), skin = p.real("skin");
    pdyn::check_cutoff_fits(ctx.particles.domain, cutoff, skin);
    const pdyn::Selection selection = pdyn::Selection::from_params(p, ctx);
    return std::make_unique<pdyn::PairForce<LennardJones>>(
        LennardJones(p.real("epsilon"), p.real("sigma"), cutoff, p.boolean("shift")), cutoff, skin,
        selection.mask(ctx.particles.size()));
  };
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
