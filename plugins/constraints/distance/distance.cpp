// distance: rigid rods between particle pairs, one constraint row per pair
// (Witkin, "Constrained Dynamics", SIGGRAPH '97 course notes; Witkin,
// Gleicher & Welch 1990). For a pair [i, j] of rest length L:
//
//   d = x_i - x_j,  r = |d|,  n = d / r,  w = v_i - v_j
//   C   = r - L                                   (m)
//   J_i = n,  J_j = -n                            (dC/dx, dimensionless)
//   b   = Cddot - J a = ndot . w = (|w|^2 - (n.w)^2) / r    (m/s^2)
//   c_t = 0                                       (the rod does not move with time)
//
// Witkin writes the rod as C = (|d|^2 - L^2)/2; C = |d| - L is the same
// constraint, measured in metres, so that the drift a run reports and the
// feedback ks C act in the rod's own unit. Its Jacobian is the unit vector
// n instead of d, which keeps J W J^T of order 1/m whatever the length.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <pdyn/plugin.hpp>
#include <set>
#include <utility>
#include <vector>

namespace {

using pdyn::Index;
using pdyn::IndexPair;
using pdyn::Vec3;

class Distance final : public pdyn::Constraint {
 public:
  Distance(std::vector<IndexPair> pairs, std::vector<double> lengths)
      : pairs_(std::move(pairs)), lengths_(std::move(lengths)) {}

  pdyn::ConstraintPattern pattern() const override {
    pdyn::ConstraintPattern p;
    for (const auto& [i, j] : pairs_) p.add_row({i, j});
    return p;
  }

  // The separation is taken to the nearest periodic image (unchanged in
  // open space), so that a rod across a periodic box's face keeps its
  // length when one end is wrapped.
  void evaluate(const pdyn::ParticleView& p, pdyn::ConstraintValues& out) const override {
    for (Index r = 0; r < static_cast<Index>(pairs_.size()); ++r) {
      const auto [i, j] = pairs_[static_cast<std::size_t>(r)];
      const Vec3 d = p.domain.minimum_image(p.x.col(i) - p.x.col(j));
      const double len = d.norm();
      out.value[r] = len - lengths_[static_cast<std::size_t>(r)];
      out.rate[r] = 0.0;
      // Coincident ends have no direction: the row is zero (finite) there,
      // as a spring adds no force between coincident ends.
      const Vec3 n = len == 0.0 ? Vec3::Zero() : Vec3(d / len);
      const Vec3 w = p.v.col(i) - p.v.col(j);
      out.jacobian.col(2 * r) = n;
      out.jacobian.col(2 * r + 1) = -n;
      // |w|^2 - (n.w)^2 as the squared norm of w's part across the rod: the
      // same number, never negative, and without the cancellation of two
      // nearly equal terms when the ends move along the rod.
      out.bias[r] = len == 0.0 ? 0.0 : (w - n.dot(w) * n).squaredNorm() / len;
    }
  }

 private:
  std::vector<IndexPair> pairs_;
  std::vector<double> lengths_;  // L per pair, m
};

// Two rows on the same two particles make J W J^T singular (the second row
// adds nothing to the first, or contradicts it): each rod once.
void require_distinct_pairs(const std::vector<IndexPair>& pairs) {
  std::set<std::pair<Index, Index>> seen;
  for (std::size_t s = 0; s < pairs.size(); ++s) {
    const auto [i, j] = pairs[s];
    if (!seen.insert({std::min(i, j), std::max(i, j)}).second) {
      throw pdyn::ParamError(
          "pairs",
          fmt::format("joins particles {} and {} a second time (expected each rod once)", i, j),
          static_cast<long>(s));
    }
  }
}

std::unique_ptr<pdyn::Constraint> create(const pdyn::Params& p, const pdyn::SceneContext& ctx) {
  const auto& pairs = p.pairs("pairs");
  if (pairs.empty()) throw pdyn::ParamError("pairs", "is empty (expected at least one pair)");
  pdyn::require_distinct_particles(p, "pairs");
  require_distinct_pairs(pairs);
  // Default: the distances the scene starts with, so that C = 0 there.
  auto lengths = pdyn::rest_values(p, "length", pairs.size(), "pairs", [&](std::size_t s) {
    const auto [i, j] = pairs[s];
    return ctx.particles.domain.minimum_image(ctx.particles.x.col(i) - ctx.particles.x.col(j))
        .norm();
  });
  return std::make_unique<Distance>(pairs, std::move(lengths));
}

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Constraint;
  d.name = "distance";
  d.version = "1.0.0";
  d.description = "rigid rods between particle pairs: C = |x_i - x_j| - L";
  d.params = {
      pdyn::param::required("pairs", pdyn::ParamType::IndexPairs, "",
                            "particle pairs [[i, j], ...] joined by a rod"),
      pdyn::param::optional("length", pdyn::ParamType::RealList, "m",
                            "rod lengths: one for all pairs or one per pair; default: the "
                            "initial distances")
          .at_least(0),
  };
  d.create_constraint = create;
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
