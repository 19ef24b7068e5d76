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
#include <array>
#include <cstdint>
#include <limits>
#include <pdyn/parallel.hpp>
#include <pdyn/plugin.hpp>

namespace {

using pdyn::Index;
using pdyn::IndexPair;
// Particle ids as stored per spring: 32 bits (a scene's N is checked against
// it in create()). With one rest length for all springs (a grid family)
// a spring is 8 bytes instead of 24: at 10^6 particles and 4 springs each,
// 64 MB less to stream per force evaluation (issue 17, item 3).
using Id = std::int32_t;
using IdPair = std::array<Id, 2>;

class Spring final : public pdyn::Force {
 public:
  // `n_particles` is the scene's N: the springs are grouped by particle
  // block here, once, so that stepping never allocates.
  // `pairs` and `rest` are copied once, straight into block order.
  Spring(const std::vector<IndexPair>& pairs, const std::vector<double>& rest, double ks, double kd,
         Index n_particles)
      : ks_(ks), kd_(kd) {
    group_by_block(pairs, rest, n_particles);
    uniform_rest_ = std::all_of(rest.begin(), rest.end(), [&](double r) { return r == rest[0]; });
    rest0_ = rest.empty() ? 0.0 : rest[0];
    if (uniform_rest_) std::vector<double>().swap(rest_);
  }

  // Parallel without races, atomics or a thread-count-dependent rounding.
  // The particles are cut into fixed blocks of consecutive ids, whose size
  // depends on N only, never on the thread count. A spring with both ends
  // in one block is "interior" to it; the others (a few percent on a grid,
  // whose blocks are bands of rows) are "boundary" springs. Phase 1: each
  // block's interior springs add into their ends directly, in spring order,
  // the blocks spread over the threads; no two threads touch one particle.
  // Phase 2: the boundary springs' forces go into a buffer in parallel, then
  // every particle they touch adds its entries in spring order (a CSR
  // incidence list). So each particle's accumulator receives the same terms
  // in the same order whatever the thread count, 1 included: the result is
  // bit-identical. Phase 1 is as fast as a plain serial scatter (the ends'
  // columns are still in cache from neighbouring springs); the buffer's
  // extra memory traffic is paid by the boundary springs only.
  void add_forces(const pdyn::ParticleView& p, Eigen::Ref<pdyn::Matrix3X> f) override {
    // The kernel's accumulator is a plain 3 x N matrix: with its stride
    // known at compile time the scatter is plain pointer arithmetic.
    if (f.outerStride() == 3) {
      Eigen::Map<pdyn::Matrix3X> dense(f.data(), 3, f.cols());
      accumulate(p, dense);
    } else {
      accumulate(p, f);
    }
  }

  // Only the damping term reads velocities: undamped springs (kd = 0) let
  // velocity Verlet reuse their forces.
  pdyn::StateDependence dependence() const override { return {kd_ > 0.0, false}; }

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
      const double geometric = std::max(0.0, 1.0 - rest(static_cast<Index>(s)) / len);
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
      const double stretch =
          (p.x.col(pairs_[s][0]) - p.x.col(pairs_[s][1])).norm() - rest(static_cast<Index>(s));
      u += 0.5 * ks_ * stretch * stretch;
    }
    return u;
  }

 private:
  // Undamped springs skip the velocity term altogether: its reads of both
  // ends' velocities are a third of the loop's memory traffic, and kd = 0 is
  // the common case for cloth under velocity Verlet.
  template <class Accumulator>
  void accumulate(const pdyn::ParticleView& p, Accumulator& f) const {
    if (kd_ > 0.0) {
      uniform_rest_ ? accumulate<true, true>(p, f) : accumulate<true, false>(p, f);
    } else {
      uniform_rest_ ? accumulate<false, true>(p, f) : accumulate<false, false>(p, f);
    }
  }

  template <bool Damped, bool Uniform, class Accumulator>
  void accumulate(const pdyn::ParticleView& p, Accumulator& f) const {
    const Index n_blocks = static_cast<Index>(block_start_.size()) - 1;
    const bool parallel =
        pdyn::max_threads() > 1 && static_cast<Index>(pairs_.size()) >= pdyn::kParallelMinElements;
    auto interior = [&](Index blk) {
      for (Index s = block_start_[blk]; s < block_start_[blk + 1]; ++s) {
        const pdyn::Vec3 fi = force_on_first<Damped, Uniform>(p, s);
        f.col(pairs_[s][0]) += fi;
        f.col(pairs_[s][1]) -= fi;
      }
    };
    // Not `omp parallel for if (parallel)`: libgomp allocates a team for
    // every region, even a serial one, and stepping must not allocate.
    if (parallel) {
#pragma omp parallel for schedule(static)
      for (Index blk = 0; blk < n_blocks; ++blk) interior(blk);
    } else {
      for (Index blk = 0; blk < n_blocks; ++blk) interior(blk);
    }
    const Index first = block_start_.back(), n_boundary = static_cast<Index>(pairs_.size()) - first;
    if (n_boundary == 0) return;
    pdyn::parallel_ranges(n_boundary, [&](Index b, Index e) {
      for (Index s = b; s < e; ++s) buffer_.col(s) = force_on_first<Damped, Uniform>(p, first + s);
    });
    pdyn::parallel_ranges(static_cast<Index>(touched_.size()), [&](Index b, Index e) {
      for (Index t = b; t < e; ++t) {
        auto fi = f.col(touched_[t]);
        for (Index k = touched_start_[t]; k < touched_start_[t + 1]; ++k) {
          // 2 s for the spring's first end, 2 s + 1 for its second: f_j = -f_i,
          // added as a subtraction, the same operation phase 1 uses.
          const Index s = incident_[k] >> 1;
          if (incident_[k] & 1) {
            fi -= buffer_.col(s);
          } else {
            fi += buffer_.col(s);
          }
        }
      }
    });
  }

  // Orders the springs as add_forces uses them: the interior springs of
  // block 0, of block 1, ..., then the boundary springs, each group in the
  // order given (a stable counting sort). Builds the boundary CSR list.
  // About 64 blocks, at least 4096 particles each: enough to balance any
  // thread count up to a few dozen, few enough that boundary springs stay
  // a small fraction.
  void group_by_block(const std::vector<IndexPair>& given, const std::vector<double>& given_rest,
                      Index n) {
    const Index block = std::max<Index>(4096, (n + 63) / 64);
    const Index n_blocks = std::max<Index>(1, (n + block - 1) / block);
    const Index n_springs = static_cast<Index>(given.size());
    auto bucket = [&](const IndexPair& pr) {
      const Index b = pr[0] / block;
      return b == pr[1] / block ? b : n_blocks;  // n_blocks: boundary
    };
    std::vector<Index> start(static_cast<std::size_t>(n_blocks + 2), 0);
    for (const auto& pr : given) ++start[bucket(pr) + 1];
    for (Index b = 0; b <= n_blocks; ++b) start[b + 1] += start[b];
    pairs_.resize(given.size());
    rest_.resize(given.size());
    std::vector<Index> next(start.begin(), start.end() - 1);
    for (Index s = 0; s < n_springs; ++s) {
      const Index to = next[bucket(given[s])]++;
      pairs_[to] = {static_cast<Id>(given[s][0]), static_cast<Id>(given[s][1])};
      rest_[to] = given_rest[s];
    }
    block_start_.assign(start.begin(), start.end() - 1);  // n_blocks + 1 entries
    const Index first = block_start_.back(), n_boundary = n_springs - first;
    // CSR over the particles the boundary springs touch, in id order.
    std::vector<std::pair<Index, Index>> ends;  // (particle, 2 s + end)
    ends.reserve(static_cast<std::size_t>(2 * n_boundary));
    for (Index s = 0; s < n_boundary; ++s) {
      ends.emplace_back(pairs_[first + s][0], 2 * s);
      ends.emplace_back(pairs_[first + s][1], 2 * s + 1);
    }
    std::sort(ends.begin(), ends.end());  // by particle, then spring order
    touched_.clear();
    touched_start_.clear();
    incident_.clear();
    for (std::size_t k = 0; k < ends.size(); ++k) {
      if (k == 0 || ends[k].first != ends[k - 1].first) {
        touched_.push_back(ends[k].first);
        touched_start_.push_back(static_cast<Index>(k));
      }
      incident_.push_back(ends[k].second);
    }
    touched_start_.push_back(static_cast<Index>(ends.size()));
    buffer_.resize(3, n_boundary);
  }

  // The force on the first end of spring s. Coincident ends have no
  // direction: the spring adds zero rather than NaN (a zero-length spring
  // at rest exerts no force anyway).
  // Inlined into both loops: a call per spring costs a fifth of the loop.
  template <bool Damped, bool Uniform>
  [[gnu::always_inline]] inline pdyn::Vec3 force_on_first(const pdyn::ParticleView& p,
                                                          Index s) const {
    const Index i = pairs_[s][0], j = pairs_[s][1];
    const pdyn::Vec3 dx = p.x.col(i) - p.x.col(j);
    const double len = dx.norm();
    if (len == 0.0) return pdyn::Vec3::Zero();
    double magnitude = ks_ * (len - rest(s));
    if constexpr (Damped) {
      const pdyn::Vec3 dv = p.v.col(i) - p.v.col(j);
      magnitude += kd_ * dv.dot(dx) / len;
    }
    return -(magnitude / len) * dx;
  }

  double rest(Index s) const { return uniform_rest_ ? rest0_ : rest_[static_cast<std::size_t>(s)]; }

  std::vector<IdPair> pairs_;  // grouped by block (group_by_block)
  std::vector<double> rest_;   // rest length of each pair, m; empty if uniform_rest_
  bool uniform_rest_ = false;  // every spring has rest length rest0_
  double rest0_ = 0.0;         // m
  double ks_, kd_;
  std::vector<Index> block_start_;    // block b's interior springs: [start[b], start[b + 1])
  std::vector<Index> touched_;        // particles with boundary springs, increasing
  std::vector<Index> touched_start_;  // their entries in incident_
  std::vector<Index>
      incident_;  // 2 s (first end) or 2 s + 1 (second end), s from the first boundary spring
  mutable pdyn::Matrix3X buffer_;  // boundary springs' forces on their first ends, N
};

std::unique_ptr<pdyn::Force> create(const pdyn::Params& p, const pdyn::SceneContext& ctx) {
  pdyn::require_distinct_particles(p, "pairs");
  const auto& pairs = p.pairs("pairs");
  if (ctx.particles.size() > std::numeric_limits<Id>::max()) {
    throw pdyn::ParamError("pairs",
                           fmt::format("a scene of {} particles (expected at most {}: "
                                       "springs store 32-bit particle ids)",
                                       ctx.particles.size(), std::numeric_limits<Id>::max()));
  }
  std::vector<double> rest =
      pdyn::rest_values(p, "rest", pairs.size(), "pairs", [&](std::size_t s) {
        return (ctx.particles.x.col(pairs[s][0]) - ctx.particles.x.col(pairs[s][1])).norm();
      });
  return std::make_unique<Spring>(pairs, rest, p.real("ks"), p.real("kd"), ctx.particles.size());
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
