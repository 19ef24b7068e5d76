// on_plane: particles kept on a plane, one row per particle (Witkin,
// "Constrained Dynamics", SIGGRAPH '97 course notes; Witkin, Gleicher &
// Welch 1990). With n the unit normal and d_k the plane's offset for
// particle i = ids[k] (the plane is n.x = d_k):
//
//   C   = n.x_i - d_k          (m: the signed distance from the plane)
//   J   = n                    (dimensionless)
//   b   = 0                    (J is constant)
//   c_t = 0                    (the plane does not move)
//
// A particle on a plane slides freely within it: unlike a collider's floor,
// which only pushes, the constraint also pulls a particle that would leave
// the plane on the other side.
#include <fmt/format.h>

#include <pdyn/plugin.hpp>
#include <unordered_set>
#include <utility>
#include <vector>

namespace {

using pdyn::Index;
using pdyn::Vec3;

class OnPlane final : public pdyn::Constraint {
 public:
  OnPlane(std::vector<Index> ids, Vec3 normal, std::vector<double> offsets)
      : ids_(std::move(ids)), normal_(normal), offsets_(std::move(offsets)) {}

  pdyn::ConstraintPattern pattern() const override {
    pdyn::ConstraintPattern p;
    for (const Index i : ids_) p.add_row({i});
    return p;
  }

  void evaluate(const pdyn::ParticleView& p, pdyn::ConstraintValues& out) const override {
    for (std::size_t k = 0; k < ids_.size(); ++k) {
      const Index row = static_cast<Index>(k);
      out.value[row] = normal_.dot(p.x.col(ids_[k])) - offsets_[k];
      out.rate[row] = 0.0;
      out.bias[row] = 0.0;
      out.jacobian.col(row) = normal_;
    }
  }

 private:
  std::vector<Index> ids_;
  Vec3 normal_;                  // unit
  std::vector<double> offsets_;  // d_k, m
};

// A particle listed twice has two equal rows: J W J^T is singular. Each
// particle once.
void require_distinct_ids(const std::vector<Index>& ids) {
  std::unordered_set<Index> seen;
  for (std::size_t e = 0; e < ids.size(); ++e) {
    if (!seen.insert(ids[e]).second) {
      throw pdyn::ParamError(
          "ids", fmt::format("particle {} is listed twice (expected each id once)", ids[e]),
          static_cast<long>(e));
    }
  }
}

// The offset: given (one plane for all), or each particle's own n.x at the
// start, so that every particle stays on the plane through where it starts
// and C = 0 there.
std::unique_ptr<pdyn::Constraint> create(const pdyn::Params& p, const pdyn::SceneContext& ctx) {
  const auto& ids = p.indices("ids");
  if (ids.empty()) throw pdyn::ParamError("ids", "is empty (expected at least one particle)");
  require_distinct_ids(ids);
  const Vec3 n = p.vec3("normal").normalized();  // not zero: the loader checks
  std::vector<double> offsets(ids.size());
  for (std::size_t k = 0; k < ids.size(); ++k) {
    offsets[k] = p.has("offset") ? p.real("offset") : n.dot(ctx.particles.x.col(ids[k]));
  }
  return std::make_unique<OnPlane>(ids, n, std::move(offsets));
}

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Constraint;
  d.name = "on_plane";
  d.version = "1.0.0";
  d.description = "particles kept on a plane: C = n.x_i - d, n the unit normal";
  d.params = {
      pdyn::param::required("ids", pdyn::ParamType::IndexList, "", "the particles on the plane"),
      pdyn::param::required_vec3("normal", "", "the plane's normal (normalised)").not_zero(),
      pdyn::param::optional("offset", pdyn::ParamType::Real, "m",
                            "the plane n.x = offset, n the unit normal; default: each particle's "
                            "plane through its initial position"),
  };
  d.create_constraint = create;
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
