// @NAME@: a pdyn bonded force. Each triple [i, j, k] holds its outer
// particles i and k at a rest distance: the Urey-Bradley term of CHARMM's
// angles (LAMMPS `angle_style charmm`), a stiffer alternative to an angle
// spring for three particles that must keep their shape:
//
//   q = |x_i - x_k|,   U = k/2 (q - q0)^2,   f = -[k (q - q0) + kd dq/dt] grad q
//
// You write only the coordinate q and its gradient (the struct below),
// once, as a template on the scalar type. Harmonic<Geometry> turns it into
// the damped harmonic law, with exact Jacobians for implicit solvers (it
// differentiates your gradient automatically); BondedForce (pdyn/bonded.hpp)
// runs the loop over the terms, the per-type coefficients (`types`, and `k`
// and `kd` one per type), the rest values a scene leaves out, and the
// threads, bit-identically for every thread count. `pdyn check` tests each
// term (the bonded.* checks: third law, f = -grad U, the Jacobians against
// finite differences, the loop against the terms). For a law that is not a
// harmonic spring on one coordinate, write the law itself: see bonded.md.
#include <cmath>
#include <pdyn/bonded.hpp>
#include <pdyn/plugin.hpp>

namespace {

struct Geometry {
  static constexpr int arity = 3;  // particles per term: 2, 3 or 4

  // q (m) and dq/dx of each particle. T is double in the force loop and an
  // automatic-differentiation scalar when the SDK takes second derivatives:
  // write it with Eigen operations and value_of() for tests on numbers.
  template <class T>
  pdyn::Coordinate<3, T> operator()(const std::array<pdyn::Vector3<T>, 3>& x) const {
    pdyn::Coordinate<3, T> q;
    const pdyn::Vector3<T> d = x[0] - x[2];
    q.value = d.norm();
    if (!(pdyn::value_of(q.value) > 0.0)) return q;  // coincident ends: no direction, no force
    q.gradient[0] = d / q.value;
    q.gradient[1] = pdyn::Vector3<T>::Zero();  // the middle particle does not move q
    q.gradient[2] = -q.gradient[0];
    q.defined = true;
    return q;
  }
};

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Force;
  d.name = "@NAME@";
  d.version = "0.1.0";
  d.description =
      "Urey-Bradley springs between the outer particles i, k of each triple [i, j, k]: U = k/2 "
      "(|x_i - x_k| - q0)^2";
  d.params = {
      pdyn::param::required("triples", pdyn::ParamType::IndexTriples, "",
                            "particle triples [[i, j, k], ...]; the spring joins i and k"),
      pdyn::param::optional("rest", pdyn::ParamType::RealList, "m",
                            "rest distances: one for all triples or one per triple; default: the "
                            "initial distances")
          .at_least(0),
  };
  // After the terms: `types`, `k` and `kd`, one value per term type.
  auto shared = pdyn::harmonic_params("stiffness", "N/m", "N s/m");
  d.params.insert(d.params.begin() + 1, shared.begin(), shared.end());
  d.force_traits.internal = true;  // q is invariant under rigid motions
  // Terms, types, rest values and coefficients, read and checked in one
  // place (pdyn::read_bonded and pdyn::harmonic_coefficients, which a law
  // of your own calls directly: docs/bonded.md).
  d.create_force = [](const pdyn::Params& p, const pdyn::SceneContext& ctx) {
    return pdyn::make_harmonic<Geometry>(p, ctx, "triples");
  };
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
