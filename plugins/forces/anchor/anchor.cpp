// anchor: damped springs from particles to points fixed in space, a soft
// nail, whose points a host may move while the simulation runs (the
// MovableTargets interface, pdyn/targets.hpp: a viewer's mouse spring).
// For particle i = ids[k] and its target p_k, with d = x_i - p_k, L = |d|:
//
//   f_i = -ks (L - r) d / L - kd v_i          (r > 0)
//   f_i = -ks d - kd v_i                      (r = 0, the default)
//   U   = ks (L - r)^2 / 2
//
// Witkin's damped spring (SIGGRAPH '97 notes, "Damped Spring") with one end
// at rest in the world. Its damping acts on the whole velocity, not only
// along d: the target does not move with the particle, so there is no rigid
// motion to spare, and damping only along d would let a particle circle a
// zero-length anchor for ever.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <pdyn/plugin.hpp>
#include <pdyn/targets.hpp>
#include <pdyn/thermo.hpp>
#include <unordered_set>

namespace {

using pdyn::Index;
using pdyn::Vec3;

class Anchor final : public pdyn::Force, public pdyn::MovableTargets, public pdyn::VirialSource {
 public:
  /// From outside the system: no virial (pdyn/thermo.hpp), as LAMMPS's fixes.
  double virial(const pdyn::ParticleView&) const override { return 0.0; }

  Anchor(std::vector<Index> ids, std::vector<Vec3> targets, double ks, double kd, double rest)
      : ids_(std::move(ids)), targets_(std::move(targets)), ks_(ks), kd_(kd), rest_(rest) {}

  void add_forces(const pdyn::ParticleView& p, Eigen::Ref<pdyn::Matrix3X> f) override {
    for (std::size_t k = 0; k < ids_.size(); ++k) {
      const Index i = ids_[k];
      const Vec3 d = p.x.col(i) - targets_[k];
      f.col(i) -= ks_ * spring_factor(d) * d + kd_ * p.v.col(i);
    }
  }

  std::optional<double> potential_energy(const pdyn::ParticleView& p) const override {
    double u = 0.0;
    for (std::size_t k = 0; k < ids_.size(); ++k) {
      const double stretch = (p.x.col(ids_[k]) - targets_[k]).norm() - rest_;
      u += 0.5 * ks_ * stretch * stretch;
    }
    return u;
  }

  // df_i/dv_i = -kd I. df_i/dx_i = -ks [n n^T + (1 - r/L) (I - n n^T)],
  // n = d/L: -ks I when r = 0. As for `spring`, the factor (1 - r/L) is
  // clamped at 0 under compression (L < r) to keep the matrix negative
  // semidefinite for conjugate gradients (Choi & Ko 2002, section 4); it is
  // the exact derivative elsewhere.
  bool add_jacobians(const pdyn::ParticleView& p, pdyn::JacobianSink& sink) override {
    const Eigen::Matrix3d id3 = Eigen::Matrix3d::Identity();
    for (std::size_t k = 0; k < ids_.size(); ++k) {
      const Index i = ids_[k];
      const Vec3 d = p.x.col(i) - targets_[k];
      const double len = d.norm();
      Eigen::Matrix3d kx = -ks_ * id3;
      if (rest_ > 0.0) {
        if (len == 0.0) {
          kx.setZero();  // add_forces has no spring term there either
        } else {
          const Vec3 n = d / len;
          const Eigen::Matrix3d nn = n * n.transpose();
          kx = -ks_ * (nn + std::max(0.0, 1.0 - rest_ / len) * (id3 - nn));
        }
      }
      sink.add_dfdx(i, i, kx);
      if (kd_ > 0.0) sink.add_dfdv(i, i, -kd_ * id3);
    }
    return true;
  }

  // ---- MovableTargets ----
  std::size_t target_count() const override { return targets_.size(); }
  Vec3 target(std::size_t k) const override { return targets_.at(check(k)); }
  void set_target(std::size_t k, const Vec3& point) override {
    check(k);
    if (!point.allFinite()) {
      throw pdyn::Error(
          fmt::format("anchor: target {} moved to a point that is not finite "
                      "(expected finite coordinates in m)",
                      k));
    }
    targets_[k] = point;
  }

  // The targets as 3 K doubles in native byte order: the checkpoint is read
  // back by the same build on the same machine.
  std::vector<std::uint8_t> save_state() const override {
    std::vector<std::uint8_t> bytes(targets_.size() * 3 * sizeof(double));
    for (std::size_t k = 0; k < targets_.size(); ++k) {
      std::memcpy(bytes.data() + k * 3 * sizeof(double), targets_[k].data(), 3 * sizeof(double));
    }
    return bytes;
  }
  void restore_state(std::span<const std::uint8_t> bytes) override {
    if (bytes.size() != targets_.size() * 3 * sizeof(double)) {
      throw pdyn::Error(fmt::format("anchor: saved state has {} bytes (expected {}: {} targets)",
                                    bytes.size(), targets_.size() * 3 * sizeof(double),
                                    targets_.size()));
    }
    std::vector<Vec3> restored(targets_.size());
    for (std::size_t k = 0; k < targets_.size(); ++k) {
      std::memcpy(restored[k].data(), bytes.data() + k * 3 * sizeof(double), 3 * sizeof(double));
      if (!restored[k].allFinite()) {
        throw pdyn::Error(fmt::format("anchor: saved target {} is not finite", k));
      }
    }
    targets_ = std::move(restored);
  }

 private:
  std::size_t check(std::size_t k) const {
    if (k >= targets_.size()) {
      throw pdyn::Error(fmt::format("anchor: no target {} (expected 0..{})", k,
                                    static_cast<long>(targets_.size()) - 1));
    }
    return k;
  }
  // ks's multiplier of d: (L - r)/L, or 1 for a zero rest length (no
  // division, so smooth through L = 0); 0 where d has no direction.
  double spring_factor(const Vec3& d) const {
    if (rest_ == 0.0) return 1.0;
    const double len = d.norm();
    return len == 0.0 ? 0.0 : (len - rest_) / len;
  }

  std::vector<Index> ids_;
  std::vector<Vec3> targets_;  // target of ids_[k], m
  double ks_, kd_, rest_;
};

std::unique_ptr<pdyn::Force> create(const pdyn::Params& p, const pdyn::SceneContext&) {
  const auto& ids = p.indices("ids");
  const auto& points = p.vec3s("points");
  if (ids.empty()) throw pdyn::ParamError("ids", "is empty (expected at least one particle)");
  std::unordered_set<Index> seen;
  for (std::size_t e = 0; e < ids.size(); ++e) {
    if (!seen.insert(ids[e]).second) {
      throw pdyn::ParamError(
          "ids",
          fmt::format("particle {} is anchored twice (expected each id once; use ks for a "
                      "stiffer anchor)",
                      ids[e]),
          static_cast<long>(e));
    }
  }
  if (points.size() != 1 && points.size() != ids.size()) {
    throw pdyn::ParamError("points",
                           fmt::format("has {} points for {} ids (expected 1 point for all, or {})",
                                       points.size(), ids.size(), ids.size()));
  }
  std::vector<Vec3> targets(ids.size());
  for (std::size_t k = 0; k < ids.size(); ++k)
    targets[k] = points.size() == 1 ? points[0] : points[k];
  return std::make_unique<Anchor>(ids, std::move(targets), p.real("ks"), p.real("kd"),
                                  p.real("rest"));
}

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Force;
  d.name = "anchor";
  d.version = "1.0.0";
  d.description =
      "damped springs from particles to movable points in space: f = -ks (L - r) d/L - kd v, "
      "d = x - p";
  d.params = {
      pdyn::param::required("ids", pdyn::ParamType::IndexList, "", "the anchored particles"),
      pdyn::param::required("points", pdyn::ParamType::VectorList, "m",
                            "target points: one per id, or one for all"),
      pdyn::param::real("ks", 1.0, "N/m", "stiffness").at_least(0),
      pdyn::param::real("kd", 0.0, "N s/m", "damping of the particle's velocity").at_least(0),
      pdyn::param::real("rest", 0.0, "m", "rest length").at_least(0),
  };
  d.create_force = create;
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
