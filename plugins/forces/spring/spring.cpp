// spring: Witkin's damped spring, for any number of particle pairs in one
// force object (SIGGRAPH '97 notes, "Damped Spring"):
//
//   dx = x_i - x_j,  dv = v_i - v_j,  L = |dx|
//   f_i = -[ks (L - r) + kd (dv . dx) / L] dx / L,   f_j = -f_i
//
// The damping term acts only along the spring, so it removes relative
// motion along dx without slowing rigid rotation. Potential U = ks (L-r)^2/2.
#include <fmt/format.h>

#include <algorithm>
#include <pdyn/parallel.hpp>
#include <pdyn/plugin.hpp>

namespace {

using pdyn::Index;
using pdyn::IndexPair;

class Spring final : public pdyn::Force {
 public:
  Spring(std::vector<IndexPair> pairs, std::vector<double> rest, double ks, double kd)
      : pairs_(std::move(pairs)), rest_(std::move(rest)), ks_(ks), kd_(kd) {}

  // One thread: each spring adds into both ends directly, the fastest form
  // (one pass over the springs; the ends' columns are still in cache from
  // the neighbouring springs of a grid). Several threads: two ends of
  // different springs may be the same particle, so scattering in parallel
  // would race, and atomics would make the order of the additions (hence
  // the rounding) depend on timing. Instead the springs' forces go into a
  // per-spring buffer in parallel, and then each particle, in parallel,
  // adds the forces of its springs in increasing spring order, read from a
  // precomputed CSR incidence list. That is exactly the sequence of
  // additions the serial scatter applies to that particle's accumulator,
  // so the result is bit-identical for every thread count, 1 included.
  void add_forces(const pdyn::ParticleView& p, Eigen::Ref<pdyn::Matrix3X> f) override {
    const Index n_springs = static_cast<Index>(pairs_.size());
    if (pdyn::max_threads() == 1 || n_springs < pdyn::kParallelMinElements) {
      // The kernel's accumulator is a plain 3 x N matrix: with its stride
      // known at compile time the scatter is plain pointer arithmetic.
      if (f.outerStride() == 3) {
        Eigen::Map<pdyn::Matrix3X> dense(f.data(), 3, f.cols());
        scatter(p, dense);
      } else {
        scatter(p, f);
      }
      return;
    }
    prepare_gather(p.size());  // allocates on the first call only
    pdyn::parallel_ranges(n_springs, [&](Index b, Index e) {
      for (Index s = b; s < e; ++s) buffer_.col(s) = force_on_first(p, s);
    });
    pdyn::parallel_ranges(p.size(), [&](Index b, Index e) {
      for (Index i = b; i < e; ++i) {
        for (Index k = offsets_[i]; k < offsets_[i + 1]; ++k) {
          // incident_ holds 2 s for the spring's first end, 2 s + 1 for its second.
          const Index s = incident_[k] >> 1;
          if (incident_[k] & 1) {
            f.col(i) -= buffer_.col(s);
          } else {
            f.col(i) += buffer_.col(s);
          }
        }
      }
    });
  }

  // Jacobians for implicit solvers. With n = dx/L and P = I - n n^T,
  //   df_i/dx_i = -ks [n n^T + (1 - r/L) P],   df_i/dv_i = -kd n n^T,
  // and the (i,j), (j,i) blocks are their negatives, (j,j) equal to (i,i).
  // Two deliberate departures from the exact derivative keep df/dx
  // symmetric negative semidefinite, so that (M - h df/dv - h^2 df/dx)
  // stays symmetric positive definite for conjugate gradients:
  // * the geometric-stiffness factor (1 - r/L) is clamped at 0 under
  //   compression (L < r), where it would be negative and make the matrix
  //   indefinite (Choi & Ko, "Stable but responsive cloth", SIGGRAPH 2002,
  //   section 4);
  // * the damping force's position derivative,
  //   -(kd/L) [n dv^T P + (dv . n) P], which is not symmetric, is left
  //   out (Baraff & Witkin, "Large Steps in Cloth Simulation", 1998,
  //   section 5.2). It vanishes when dv = 0.
  // Elsewhere (stretched or at rest, kd = 0 or dv = 0) the blocks are the
  // exact derivatives of add_forces.
  bool add_jacobians(const pdyn::ParticleView& p, pdyn::JacobianSink& sink) override {
    for (std::size_t s = 0; s < pairs_.size(); ++s) {
      const Index i = pairs_[s][0], j = pairs_[s][1];
      const pdyn::Vec3 dx = p.x.col(i) - p.x.col(j);
      const double len = dx.norm();
      if (len == 0.0) continue;  // add_forces adds nothing here either
      const pdyn::Vec3 n = dx / len;
      const Eigen::Matrix3d nn = n * n.transpose();
      const double geometric = std::max(0.0, 1.0 - rest_[s] / len);
      const Eigen::Matrix3d kx = -ks_ * (nn + geometric * (Eigen::Matrix3d::Identity() - nn));
      sink.add_dfdx(i, i, kx);
      sink.add_dfdx(i, j, -kx);
      sink.add_dfdx(j, i, -kx);
      sink.add_dfdx(j, j, kx);
      if (kd_ > 0.0) {
        const Eigen::Matrix3d kv = -kd_ * nn;
        sink.add_dfdv(i, i, kv);
        sink.add_dfdv(i, j, -kv);
        sink.add_dfdv(j, i, -kv);
        sink.add_dfdv(j, j, kv);
      }
    }
    return true;
  }

  std::optional<double> potential_energy(const pdyn::ParticleView& p) const override {
    double u = 0.0;
    for (std::size_t s = 0; s < pairs_.size(); ++s) {
      const double stretch = (p.x.col(pairs_[s][0]) - p.x.col(pairs_[s][1])).norm() - rest_[s];
      u += 0.5 * ks_ * stretch * stretch;
    }
    return u;
  }

 private:
  template <class Accumulator>
  void scatter(const pdyn::ParticleView& p, Accumulator& f) const {
    const Index n_springs = static_cast<Index>(pairs_.size());
    for (Index s = 0; s < n_springs; ++s) {
      const pdyn::Vec3 fi = force_on_first(p, s);
      f.col(pairs_[s][0]) += fi;
      f.col(pairs_[s][1]) -= fi;
    }
  }

  // The force on the first end of spring s. Coincident ends have no
  // direction: the spring adds zero rather than NaN (a zero-length spring
  // at rest exerts no force anyway). Zero is added, not skipped, so that
  // both paths of add_forces do the same additions.
  // Inlined into both loops: a call per spring costs a fifth of the loop.
  [[gnu::always_inline]] inline pdyn::Vec3 force_on_first(const pdyn::ParticleView& p,
                                                          Index s) const {
    const Index i = pairs_[s][0], j = pairs_[s][1];
    const pdyn::Vec3 dx = p.x.col(i) - p.x.col(j);
    const double len = dx.norm();
    if (len == 0.0) return pdyn::Vec3::Zero();
    const pdyn::Vec3 dv = p.v.col(i) - p.v.col(j);
    const double magnitude = ks_ * (len - rest_[s]) + kd_ * dv.dot(dx) / len;
    return -(magnitude / len) * dx;
  }

  // Builds the CSR incidence list of the parallel path: particle i's
  // springs are incident_[offsets_[i] .. offsets_[i + 1]), in increasing
  // spring order (a counting sort over the springs, which visits them in
  // order). Costs 8 bytes per particle and 16 + 24 bytes per spring, so it
  // is only built when more than one thread runs.
  void prepare_gather(Index n) {
    if (static_cast<Index>(offsets_.size()) == n + 1) return;
    const Index n_springs = static_cast<Index>(pairs_.size());
    offsets_.assign(static_cast<std::size_t>(n + 1), 0);
    for (const auto& pr : pairs_) {
      ++offsets_[pr[0] + 1];
      ++offsets_[pr[1] + 1];
    }
    for (Index i = 0; i < n; ++i) offsets_[i + 1] += offsets_[i];
    incident_.resize(static_cast<std::size_t>(2 * n_springs));
    std::vector<Index> next(offsets_.begin(), offsets_.end() - 1);
    for (Index s = 0; s < n_springs; ++s) {
      incident_[next[pairs_[s][0]]++] = 2 * s;
      incident_[next[pairs_[s][1]]++] = 2 * s + 1;
    }
    buffer_.resize(3, n_springs);
  }

  std::vector<IndexPair> pairs_;
  std::vector<double> rest_;  // rest length of each pair, m
  double ks_, kd_;
  // Parallel path only (see add_forces).
  std::vector<Index> offsets_;   // N + 1
  std::vector<Index> incident_;  // 2 per spring: 2 s (first end) or 2 s + 1 (second end)
  pdyn::Matrix3X buffer_;        // force on each spring's first end, N
};

std::unique_ptr<pdyn::Force> create(const pdyn::Params& p, const pdyn::SceneContext& ctx) {
  const auto& pairs = p.pairs("pairs");
  for (std::size_t s = 0; s < pairs.size(); ++s) {
    if (pairs[s][0] == pairs[s][1]) {
      throw pdyn::ParamError(
          "pairs",
          fmt::format("joins particle {} to itself (expected two different particles)",
                      pairs[s][0]),
          static_cast<long>(s));
    }
  }
  std::vector<double> rest(pairs.size());
  if (p.has("rest")) {
    const auto& given = p.reals("rest");
    if (given.size() != 1 && given.size() != pairs.size()) {
      throw pdyn::ParamError(
          "rest", fmt::format("has {} values for {} pairs (expected 1 value for all, or {})",
                              given.size(), pairs.size(), pairs.size()));
    }
    for (std::size_t s = 0; s < pairs.size(); ++s)
      rest[s] = given.size() == 1 ? given[0] : given[s];
  } else {
    for (std::size_t s = 0; s < pairs.size(); ++s) {
      rest[s] = (ctx.particles.x.col(pairs[s][0]) - ctx.particles.x.col(pairs[s][1])).norm();
    }
  }
  return std::make_unique<Spring>(pairs, std::move(rest), p.real("ks"), p.real("kd"));
}

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Force;
  d.name = "spring";
  d.version = "1.0.0";
  d.description =
      "damped springs between particle pairs: f_i = -[ks (L - r) + kd (dv.dx)/L] dx/L, f_j = -f_i";
  d.params = {
      pdyn::param::required("pairs", pdyn::ParamType::IndexPairs, "",
                            "particle pairs [[i, j], ...] joined by a spring"),
      pdyn::param::real("ks", 1.0, "N/m", "stiffness").at_least(0),
      pdyn::param::real("kd", 0.0, "N s/m", "damping along the spring").at_least(0),
      pdyn::param::optional("rest", pdyn::ParamType::RealList, "m",
                            "rest lengths: one for all pairs or one per pair; default: the "
                            "initial distances")
          .at_least(0),
  };
  d.force_traits.internal = true;
  d.create_force = create;
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
