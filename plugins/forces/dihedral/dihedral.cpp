// dihedral: a damped bending spring on the dihedral angle of each quadruple
// [i, j, k, l], the angle between the planes (i, j, k) and (j, k, l) about
// their common edge j-k: cloth's and shells' bending stiffness (two
// triangles sharing an edge; Baraff & Witkin 1998, section 4.3; Bridson,
// Marino & Fedkiw 2003) and the torsion of molecular chains (LAMMPS's
// dihedral styles, with the same atom order). The angle phi and its
// gradient are pdyn/dihedral.hpp's (Blondel & Karplus 1996), shared with the
// `bending` constraint; here
//
//   U = k/2 d(phi, phi0)^2,   f = -[k d + kd dphi/dt] grad phi,
//
// with d(phi, phi0) = phi - phi0 folded into (-pi, pi], so that a flat
// sheet (phi0 = pi) bent slightly either way is pushed back either way and
// the energy has no jump where atan2 wraps. Where the angle is undefined (a
// degenerate triangle or edge) the term adds no force. phi is invariant
// under rigid motions, so the force is internal; the damping resists only
// the rate of bending (power -kd (dphi/dt)^2 <= 0).
//
// The loop, the per-type coefficients, the threads and the Jacobians are
// pdyn/bonded.hpp's (Harmonic<Dihedral>).
#include <pdyn/bonded.hpp>
#include <pdyn/dihedral.hpp>
#include <pdyn/plugin.hpp>

namespace {

using pdyn::Dihedral;

std::unique_ptr<pdyn::Force> create(const pdyn::Params& p, const pdyn::SceneContext& ctx) {
  return pdyn::make_harmonic<Dihedral>(p, ctx, "quads");
}

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Force;
  d.name = "dihedral";
  d.version = "1.0.0";
  d.description =
      "damped bending spring on the dihedral angle phi of each quadruple [i, j, k, l] about the "
      "edge j-k: U = k/2 (phi - phi0)^2, f = -[k (phi - phi0) + kd dphi/dt] grad phi";
  d.params = pdyn::Dihedral::params();
  // After the terms: types, k, kd (pdyn/bonded.hpp); then rest.
  auto shared = pdyn::harmonic_params("bending stiffness", "N m/rad", "N m s/rad");
  d.params.insert(d.params.begin() + 1, shared.begin(), shared.end());
  d.force_traits.internal = true;
  d.create_force = create;
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
