// bending: a sheet's hinges held at their angles, the bending constraint of
// position-based cloth (Muller, Heidelberger, Hennix & Ratcliff 2007,
// "Position Based Dynamics", section 4.2). One row per quadruple
// [i, j, k, l], triangles (i, j, k) and (j, k, l) hinged on the edge j-k:
//
//   C   = d(phi, phi0)        phi the dihedral angle (pdyn/dihedral.hpp),
//                             d folded into (-pi, pi]              (rad)
//   J   = grad phi                                                 (rad/m)
//   c_t = 0
//   b   = v^T (d2 phi / dx2) v                                     (rad/s^2)
//
// b is C's acceleration at zero particle accelerations: d2/ds2 phi(x + v s)
// at s = 0. It is computed exactly, by forward-mode automatic
// differentiation of the gradient along v (one directional derivative:
// Eigen's AutoDiffScalar with a single derivative), rather than by writing
// out the Hessian of Blondel & Karplus's gradient.
//
// With a compliance (the scene's key, rad/(N m)) under xpbd the hinge is a
// bending spring of stiffness 1/alpha whatever the step; compliance 0 keeps
// the angle. Where the angle is undefined (a degenerate triangle or a
// zero-length edge) the row is C with J = 0 and b = 0: it cannot act, as the
// `dihedral` force adds nothing there.
#include <Eigen/Core>
#include <array>
#include <cmath>
#include <pdyn/dihedral.hpp>
#include <pdyn/plugin.hpp>
#include <unsupported/Eigen/AutoDiff>
#include <vector>

namespace {

using pdyn::Index;
using pdyn::IndexQuad;
using pdyn::Vec3;
using pdyn::Vector3;

class Bending final : public pdyn::Constraint {
 public:
  Bending(std::vector<IndexQuad> quads, std::vector<double> rest)
      : quads_(std::move(quads)), rest_(std::move(rest)) {}

  pdyn::ConstraintPattern pattern() const override {
    pdyn::ConstraintPattern p;
    for (const auto& q : quads_) p.add_row({q[0], q[1], q[2], q[3]});
    return p;
  }

  void evaluate(const pdyn::ParticleView& p, pdyn::ConstraintValues& out) const override {
    using Direction = Eigen::Matrix<double, 1, 1>;
    using AD = Eigen::AutoDiffScalar<Direction>;
    for (Index r = 0; r < static_cast<Index>(quads_.size()); ++r) {
      const IndexQuad& q = quads_[static_cast<std::size_t>(r)];
      // Each corner taken to its nearest periodic image of the edge's first
      // end (unchanged in open space), so a hinge across a face keeps its angle.
      std::array<Vector3<double>, 4> x;
      std::array<Vector3<AD>, 4> xs;  // x + v s, differentiated by s
      const Vec3 anchor = p.x.col(q[1]);
      for (int a = 0; a < 4; ++a) {
        x[a] = anchor + p.domain.minimum_image(p.x.col(q[a]) - anchor);
        for (int c = 0; c < 3; ++c) xs[a][c] = AD(x[a][c], Direction(p.v(c, q[a])));
      }
      const pdyn::Coordinate<4> phi = dihedral_(x);
      out.value[r] = pdyn::Dihedral::difference(phi.value, rest_[static_cast<std::size_t>(r)]);
      out.rate[r] = 0.0;
      double bias = 0.0;
      if (phi.defined) {
        const pdyn::Coordinate<4, AD> along = dihedral_(xs);
        for (int a = 0; a < 4; ++a) {
          out.jacobian.col(4 * r + a) = phi.gradient[a];
          for (int c = 0; c < 3; ++c) {
            const AD& g = along.gradient[a][c];
            // A component that does not depend on x carries no derivative.
            if (g.derivatives().size() == 1) bias += g.derivatives()(0) * p.v(c, q[a]);
          }
        }
      } else {
        out.jacobian.middleCols(4 * r, 4).setZero();
      }
      out.bias[r] = bias;
    }
  }

 private:
  pdyn::Dihedral dihedral_;
  std::vector<IndexQuad> quads_;
  std::vector<double> rest_;  // phi0 per quadruple, rad
};

std::unique_ptr<pdyn::Constraint> create(const pdyn::Params& p, const pdyn::SceneContext& ctx) {
  const auto& quads = p.quads("quads");
  if (quads.empty()) throw pdyn::ParamError("quads", "is empty (expected at least one quadruple)");
  pdyn::require_distinct_particles(p, "quads");
  // Default: the angles the scene starts with, so that C = 0 there.
  auto rest = pdyn::rest_values(p, "rest", quads.size(), "quads", [&](std::size_t s) {
    std::array<Vector3<double>, 4> x;
    for (int a = 0; a < 4; ++a) x[a] = ctx.particles.x.col(quads[s][a]);
    return pdyn::Dihedral{}(x).value;
  });
  return std::make_unique<Bending>(quads, std::move(rest));
}

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Constraint;
  d.name = "bending";
  d.version = "1.0.0";
  d.description =
      "hinges held at their dihedral angles: C = phi - phi0 for each quadruple [i, j, k, l] about "
      "the edge j-k (position-based cloth's bending)";
  d.params = pdyn::Dihedral::params();
  d.create_constraint = create;
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
