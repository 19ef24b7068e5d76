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
//
// `triples: [[i, j, k], ...]` holds the ends i and k of each triple instead:
// with the bonds i-j and j-k held too, that fixes the angle at j, which is
// how LAMMPS's SHAKE and RATTLE hold an angle (`fix shake ... a 1`;
// Ryckaert, Ciccotti & Berendsen, J. Comput. Phys. 23, 327, 1977). With
// `types` (one per rod, as a data file's Bonds or Angles give them) the
// lengths are given per type, as a bond_coeff's r0 is.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <pdyn/bonded_params.hpp>
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
void require_distinct_pairs(const std::vector<IndexPair>& pairs, const char* key) {
  std::set<std::pair<Index, Index>> seen;
  for (std::size_t s = 0; s < pairs.size(); ++s) {
    const auto [i, j] = pairs[s];
    if (!seen.insert({std::min(i, j), std::max(i, j)}).second) {
      throw pdyn::ParamError(
          key,
          fmt::format("joins particles {} and {} a second time (expected each rod once)", i, j),
          static_cast<long>(s));
    }
  }
}

// The rods: `pairs`, or the ends of each of `triples`; exactly one given.
std::pair<std::vector<IndexPair>, const char*> rods_of(const pdyn::Params& p) {
  if (p.has("pairs") == p.has("triples")) {
    throw pdyn::ParamError(p.has("pairs") ? "triples" : "pairs",
                           p.has("pairs") ? "is given beside pairs (expected one of the two)"
                                          : "is missing (expected pairs, or triples whose ends "
                                            "are held)");
  }
  const char* key = p.has("pairs") ? "pairs" : "triples";
  pdyn::require_distinct_particles(p, key);
  std::vector<IndexPair> rods;
  if (p.has("pairs")) {
    rods = p.pairs("pairs");
  } else {
    for (const auto& t : p.triples("triples")) rods.push_back({t[0], t[2]});
  }
  if (rods.empty()) {
    throw pdyn::ParamError(key, fmt::format("is empty (expected at least one {})",
                                            p.has("pairs") ? "pair" : "triple"));
  }
  return {std::move(rods), key};
}

// Each rod's length: `length` per type with `types` (as bonded
// coefficients), else one for all or one per rod; default: the distances
// the scene starts with, so that C = 0 there.
std::vector<double> lengths_of(const pdyn::Params& p, const pdyn::SceneContext& ctx,
                               const std::vector<IndexPair>& rods, const char* key) {
  auto initial = [&](std::size_t s) {
    const auto [i, j] = rods[s];
    return ctx.particles.domain.minimum_image(ctx.particles.x.col(i) - ctx.particles.x.col(j))
        .norm();
  };
  if (!p.has("types") || !p.has("length"))
    return pdyn::rest_values(p, "length", rods.size(), key, initial);
  const auto& types = p.integers("types");
  if (types.size() != rods.size()) {
    throw pdyn::ParamError("types", fmt::format("has {} values for {} {} (expected one per rod)",
                                                types.size(), rods.size(), key));
  }
  const std::int32_t n_types = pdyn::bonded_type_count(p, {"length"});
  std::vector<double> out(rods.size());
  for (std::size_t s = 0; s < rods.size(); ++s) {
    // One length is every type's.
    if (types[s] < 0 || (n_types > 1 && types[s] >= n_types)) {
      throw pdyn::ParamError("types",
                             fmt::format("{} is not a rod type (expected 0..{}: length gives {})",
                                         types[s], n_types - 1, n_types),
                             static_cast<long>(s));
    }
    out[s] = pdyn::bonded_coefficient(p, "length", static_cast<std::int32_t>(types[s]));
  }
  return out;
}

std::unique_ptr<pdyn::Constraint> create(const pdyn::Params& p, const pdyn::SceneContext& ctx) {
  auto [rods, key] = rods_of(p);
  require_distinct_pairs(rods, key);
  auto lengths = lengths_of(p, ctx, rods, key);
  return std::make_unique<Distance>(std::move(rods), std::move(lengths));
}

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Constraint;
  d.name = "distance";
  d.version = "1.0.0";
  d.description = "rigid rods between particle pairs: C = |x_i - x_j| - L";
  d.params = {
      pdyn::param::optional("pairs", pdyn::ParamType::IndexPairs, "",
                            "particle pairs [[i, j], ...] joined by a rod")
          .with_sample(pdyn::ParamValue(std::vector<IndexPair>{{0, 1}})),
      pdyn::param::optional("triples", pdyn::ParamType::IndexTriples, "",
                            "instead of pairs: triples [[i, j, k], ...] whose ends i, k are joined "
                            "by a rod (an angle held as SHAKE holds it)"),
      pdyn::param::optional("length", pdyn::ParamType::RealList, "m",
                            "rod lengths: one for all, one per rod, or with types one per type; "
                            "default: the initial distances")
          .at_least(0),
      pdyn::param::optional("types", pdyn::ParamType::IntegerList, "",
                            "a type per rod, 0.. (a data file's, LAMMPS's t - 1): length gives "
                            "one value per type")
          .at_least(0),
  };
  d.create_constraint = create;
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
