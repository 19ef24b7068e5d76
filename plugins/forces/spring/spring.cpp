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
#include <cmath>
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
      accumulate(p, f.data(), std::integral_constant<Index, 3>{});
    } else {
      accumulate(p, f.data(), static_cast<Index>(f.outerStride()));
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
  template <class Stride>
  void accumulate(const pdyn::ParticleView& p, double* f, Stride fs) const {
    if (kd_ > 0.0) {
      uniform_rest_ ? accumulate<true, true>(p, f, fs) : accumulate<true, false>(p, f, fs);
    } else {
      uniform_rest_ ? accumulate<false, true>(p, f, fs) : accumulate<false, false>(p, f, fs);
    }
  }

  template <bool Damped, bool Uniform, class Stride>
  void accumulate(const pdyn::ParticleView& p, double* f, Stride fs) const {
    const Index n_blocks = static_cast<Index>(block_start_.size()) - 1;
    const bool parallel =
        pdyn::max_threads() > 1 && static_cast<Index>(pairs_.size()) >= pdyn::kParallelMinElements;
    const Kernel<Damped, Uniform> k = kernel<Damped, Uniform>(p);
    const Index* block_start = block_start_.data();
    auto interior = [&](Index blk) {
      const Index begin = block_start[blk], end = block_start[blk + 1];
      for (Index s = begin; s < end; ++s) {
        double fi[3];
        k.force_on_first(s, fi);
        double* a = f + fs * k.pairs[s][0];
        double* b = f + fs * k.pairs[s][1];
        a[0] += fi[0];
        a[1] += fi[1];
        a[2] += fi[2];
        b[0] -= fi[0];
        b[1] -= fi[1];
        b[2] -= fi[2];
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
    double* buffer = buffer_.data();
    pdyn::parallel_ranges(n_boundary, [&](Index b, Index e) {
      for (Index s = b; s < e; ++s) k.force_on_first(first + s, buffer + 3 * s);
    });
    const Index* touched = touched_.data();
    const Index* touched_start = touched_start_.data();
    const Index* incident = incident_.data();
    pdyn::parallel_ranges(static_cast<Index>(touched_.size()), [&](Index b, Index e) {
      for (Index t = b; t < e; ++t) {
        double* fi = f + fs * touched[t];
        for (Index q = touched_start[t]; q < touched_start[t + 1]; ++q) {
          // 2 s for the spring's first end, 2 s + 1 for its second: f_j = -f_i,
          // added as a subtraction, the same operation phase 1 uses.
          const double* g = buffer + 3 * (incident[q] >> 1);
          if (incident[q] & 1) {
            fi[0] -= g[0];
            fi[1] -= g[1];
            fi[2] -= g[2];
          } else {
            fi[0] += g[0];
            fi[1] += g[1];
            fi[2] += g[2];
          }
        }
      }
    });
  }

  // What the force loop reads, copied into locals: through `this` and the
  // view, every store into f could alias them, and the compiler reloaded
  // the pointers, ks, kd and the rest-length flag once per spring (issue 17:
  // 20% slower than the hand-fused reference at 10^6 particles).
  template <bool Damped, bool Uniform>
  struct Kernel {
    const double* __restrict x;  // 3 x N, column-major, stride 3
    const double* __restrict v;
    const IdPair* __restrict pairs;
    const double* __restrict rest;  // per spring, or null if Uniform
    double rest0, ks, kd;

    // The force on the first end of spring s, written into out[3]. The
    // operations and their order are Witkin's formula as the header gives
    // it, so every thread count and both accumulation phases round alike.
    // Coincident ends have no direction: the spring adds zero rather than
    // NaN (a zero-length spring at rest exerts no force anyway).
    [[gnu::always_inline]] inline void force_on_first(Index s, double* out) const {
      const double* xi = x + 3 * static_cast<Index>(pairs[s][0]);
      const double* xj = x + 3 * static_cast<Index>(pairs[s][1]);
      const double d0 = xi[0] - xj[0], d1 = xi[1] - xj[1], d2 = xi[2] - xj[2];
      const double len = std::sqrt((d0 * d0 + d1 * d1) + d2 * d2);
      if (len == 0.0) {
        out[0] = out[1] = out[2] = 0.0;
        return;
      }
      double magnitude = ks * (len - (Uniform ? rest0 : rest[s]));
      if constexpr (Damped) {
        const double* vi = v + 3 * static_cast<Index>(pairs[s][0]);
        const double* vj = v + 3 * static_cast<Index>(pairs[s][1]);
        const double w0 = vi[0] - vj[0], w1 = vi[1] - vj[1], w2 = vi[2] - vj[2];
        magnitude += kd * ((w0 * d0 + w1 * d1) + w2 * d2) / len;
      }
      const double c = -(magnitude / len);
      out[0] = c * d0;
      out[1] = c * d1;
      out[2] = c * d2;
    }
  };

  template <bool Damped, bool Uniform>
  Kernel<Damped, Uniform> kernel(const pdyn::ParticleView& p) const {
    return {p.x.data(), p.v.data(), pairs_.data(), Uniform ? nullptr : rest_.data(), rest0_,
            ks_,        kd_};
  }

  // Orders the springs as add_forces uses them: the interior springs of
  // block 0, of block 1, ..., then the boundary springs, each group in the
  // order given (a stable counting sort). Builds the boundary CSR list.
  // About 64 blocks, at least 4096 particles each: enough to balance any
  // thread count up to a few dozen, few enough that boundary springs stay
  // a small fraction. Below 32768 particles, blocks of N/8 particles but at
  // least 1024: with 4096 the 100 x 100 cloth had 3 blocks, 2 for one
  // thread and 1 for the other, and 2 threads were no faster than 1 (now
  // 1.8x faster).
  void group_by_block(const std::vector<IndexPair>& given, const std::vector<double>& given_rest,
                      Index n) {
    const Index block = std::max({std::min<Index>(4096, (n + 7) / 8), (n + 63) / 64, Index{1024}});
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
  d.version = "1.1.0";
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
