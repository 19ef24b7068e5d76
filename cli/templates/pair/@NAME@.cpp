// @NAME@: a pdyn pair force. Every pair of particles closer than the cutoff
// rc repels through the soft potential of dissipative particle dynamics'
// conservative force (Groot & Warren 1997):
//
//   U(r) = eps (1 - r/rc)^2,    -U'(r)/r = 2 eps (1 - r/rc) / (rc r)
//
// You write only the law (the struct below); PairForce (pdyn/pair.hpp) runs
// the neighbor list, the loop over pairs, Newton's third law, the periodic
// images and the threads, bit-identically for every thread count. `pdyn
// check` compares that loop with the law (the pair.* checks: Newton's third
// law, F = -dU/dr, the list against a sum over all pairs, U(rc) = 0).
#include <cmath>
#include <pdyn/pair.hpp>
#include <pdyn/plugin.hpp>
#include <pdyn/selection.hpp>

namespace {

struct Law {
  double eps, rc;  // J, m
  // U (J) and -U'(r)/r (N/m) at squared distance r2 < rc^2 (m^2), for
  // particles of types ti and tj (0 when the scene gives no types).
  pdyn::PairTerm operator()(double r2, std::int32_t, std::int32_t) const {
    const double r = std::sqrt(r2);
    const double s = 1.0 - r / rc;
    // At r = 0 the force's direction is undefined and its magnitude finite:
    // no force, the energy's maximum.
    return {eps * s * s, r > 0.0 ? 2.0 * eps * s / (rc * r) : 0.0};
  }
  // The loop may call this law at any listed distance, the cutoff's skin
  // included, and discard the value there: it then selects instead of
  // branching per pair: on a liquid the steps take about 0.7 times as long (docs/pairs.md,
  // "Evaluated beyond the cutoff"). True for any law that is finite and cheap
  // at every r2 > 0, as this one and Lennard-Jones or Morse are. Delete the
  // line if yours is not: a table indexed by r2 (read past its end), a law
  // that throws or divides by (rc - r).
  static constexpr bool evaluate_beyond_cutoff = true;
  // U(rc) = 0: the energy is continuous at the cutoff, as `pdyn check`'s
  // pair.continuous_at_cutoff then verifies. Leave it out (or return false)
  // for a law that jumps there.
  bool continuous_at_cutoff() const { return true; }
};

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Force;
  d.name = "@NAME@";
  d.version = "0.1.0";
  d.description = "soft repulsion U = eps (1 - r/rc)^2 between particles closer than rc";
  d.params = {
      pdyn::param::real("eps", 1.0, "J", "strength: the energy of two coincident particles")
          .at_least(0),
      pdyn::param::real("cutoff", 1.0, "m", "range rc").greater_than(0),
      pdyn::param::real("skin", 0.2, "m", "neighbor-list skin: rebuilt after a move of skin/2")
          .at_least(0),
  };
  for (auto& s : pdyn::selection_params()) d.params.push_back(std::move(s));
  d.force_traits.internal = true;  // central pair forces: momentum and angular momentum kept
  d.create_force = [](const pdyn::Params& p, const pdyn::SceneContext& ctx) {
    const double rc = p.real("cutoff"), skin = p.real("skin");
    pdyn::check_cutoff_fits(ctx.particles.domain, rc, skin);  // located error if the box is small
    return std::make_unique<pdyn::PairForce<Law>>(
        Law{p.real("eps"), rc}, rc, skin,
        pdyn::Selection::from_params(p, ctx).mask(ctx.particles.size()));
  };
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
