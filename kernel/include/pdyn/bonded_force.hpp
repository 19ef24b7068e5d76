// pdyn/bonded_force.hpp — BondedForce<Law>, the loop of every bonded force
// (since 0.10.0): the author writes one term's law, the kernel runs the
// terms.
//
// A plugin supplies a law (pdyn/bonded_law.hpp) and instantiates
// BondedForce<Law> with the terms read_bonded() read (pdyn/bonded_params.hpp)
// and one set of coefficients per term type. BondedForce owns the loop over
// the terms, the per-type coefficients, the rest values, the threads, the
// energy (J) and virial (J), the Jacobians an implicit solver asks for, and
// the checking hook (pdyn/bonded_reference.hpp), as LAMMPS's bond, angle and
// dihedral styles do, but written once. This header does not bring in
// Harmonic<Geometry> and its automatic differentiation (pdyn/harmonic.hpp):
// a plugin whose law is written by hand (spring) includes this one alone;
// pdyn/bonded.hpp includes both.
//
// Threads and determinism (pdyn/parallel.hpp's rule: bit-identical results
// for every thread count). The particles are cut into fixed blocks of
// consecutive ids, whose size depends on N only. A term whose particles all
// lie in one block is interior to it; the others are boundary terms. Phase
// 1: each block's interior terms add into their particles directly, in term
// order, the blocks spread over the threads; no two threads touch one
// particle. Phase 2: the boundary terms' forces go into a buffer in
// parallel, then each particle they touch adds its entries in term order.
// Each particle's accumulator receives the same terms in the same order
// whatever the thread count. With particles numbered in space (a grid, a
// rope) boundary terms are a few per cent.
//
// Periodic boxes (since 0.10.0). In a box periodic along some axis each
// term is measured with every particle at its image nearest the term's
// first particle (Domain::nearest_image), as LAMMPS computes a bond with
// its partner's closest image: a term may cross a periodic face, and must
// stay shorter than half the box along it. Particles away from the faces
// are read as they are, bit for bit. So moving particles by whole box
// lengths changes no term beyond rounding: a BondedForce is
// PeriodicInvariant (pdyn/periodic_invariant.hpp), and the wrap after each
// step does not make velocity Verlet evaluate the forces a second time.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <concepts>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "pdyn/bonded_law.hpp"
#include "pdyn/bonded_params.hpp"
#include "pdyn/bonded_reference.hpp"
#include "pdyn/domain.hpp"
#include "pdyn/error.hpp"
#include "pdyn/force.hpp"
#include "pdyn/parallel.hpp"
#include "pdyn/periodic_invariant.hpp"
#include "pdyn/thermo.hpp"
#include "pdyn/types.hpp"

namespace pdyn {

/// A force made of bonded terms with law `Law` (pdyn/bonded_law.hpp; its
/// threads: the top of this file).
template <class Law>
class BondedForce : public Force,
                    public BondedReference,
                    public VirialSource,
                    public PeriodicInvariant {
 public:
  static constexpr int N = Law::arity;
  static_assert(N >= 2 && N <= 4, "a bonded term joins 2, 3 or 4 particles");
  using Coefficients = typename Law::Coefficients;
  /// Particle ids as stored per term: 32 bits (the factory checks N fits).
  using Id = std::int32_t;

  /// `coefficients[t]` for terms of type t (`input.types`, or type 0 for all
  /// when it is empty); `n_particles` is the scene's N: the terms are grouped
  /// by particle block here, once, so that stepping never allocates.
  /// Throws Error when N does not fit 32-bit ids or a type has no
  /// coefficients.
  BondedForce(Law law, const BondedInput<N>& input, std::vector<Coefficients> coefficients,
              Index n_particles)
      : law_(std::move(law)), coefficients_(std::move(coefficients)) {
    if (n_particles > std::numeric_limits<Id>::max()) {
      throw Error("a scene of " + std::to_string(n_particles) +
                  " particles (expected at most 2147483647: bonded terms store 32-bit ids)");
    }
    for (const auto t : input.types) {
      if (t < 0 || static_cast<std::size_t>(t) >= coefficients_.size()) {
        throw Error("a bonded term of type " + std::to_string(t) + " has no coefficients");
      }
    }
    if (coefficients_.empty()) throw Error("a bonded force needs coefficients for type 0");
    group_by_block(input, n_particles);
  }

  const Law& law() const noexcept { return law_; }

  void add_forces(const ParticleView& p, Eigen::Ref<Matrix3X> f) override {
    // The kernel's accumulator is a plain 3 x N matrix: with its stride
    // known at compile time the scatter is plain pointer arithmetic.
    if (f.outerStride() == 3) {
      accumulate(p, f.data(), std::integral_constant<Index, 3>{});
    } else {
      accumulate(p, f.data(), static_cast<Index>(f.outerStride()));
    }
  }

  /// Reads velocities if any term type's coefficients do (Law::reads_velocity).
  StateDependence dependence() const override {
    if constexpr (requires(const Law& l, const Coefficients& c) {
                    { l.reads_velocity(c) } -> std::convertible_to<bool>;
                  }) {
      const bool v = std::any_of(coefficients_.begin(), coefficients_.end(),
                                 [&](const Coefficients& c) { return law_.reads_velocity(c); });
      return {v, false};
    } else {
      return {true, false};
    }
  }

  /// Sum of the terms' energies, J.
  std::optional<double> potential_energy(const ParticleView& p) const override {
    double u = 0.0;
    Images images;
    for (Index s = 0; s < term_count(); ++s) {
      u += law_(point(p, s, images), coefficients(s)).energy;
    }
    return u;
  }

  /// Sum over the terms of sum_a (x_a - x_0) . f_a (pdyn/thermo.hpp), J:
  /// the positions as the terms measure them (nearest images in a box).
  double virial(const ParticleView& p) const override {
    double w = 0.0;
    Images images;
    for (Index s = 0; s < term_count(); ++s) {
      const BondedPoint<N> q = point(p, s, images);
      const BondedTerm<N> t = law_(q, coefficients(s));
      const Vec3 x0 = q.position(0);
      for (int a = 1; a < N; ++a) w += (q.position(a) - x0).dot(t.force[a]);
    }
    return w;
  }

  /// The law's jacobian() (or pair_jacobian()) of every term, in term
  /// order; false (numerical differentiation) when the law has neither.
  bool add_jacobians(const ParticleView& p, JacobianSink& sink) override {
    if constexpr (kHasPairJacobian) {
      // The blocks (a, b) of [k -k; -k k] in the order below, as the
      // general loop would report them: the same calls, the same bits.
      Eigen::Matrix3d k, d;
      Images images;
      for (Index s = 0; s < term_count(); ++s) {
        k.setZero();
        d.setZero();
        if (!law_.pair_jacobian(point(p, s, images), coefficients(s), k, d)) continue;
        const bool damped = !d.isZero(0.0);
        const Eigen::Matrix3d minus_k = -k, minus_d = -d;
        const Index ends[2] = {terms_[s][0], terms_[s][1]};
        for (int a = 0; a < 2; ++a) {
          for (int b = 0; b < 2; ++b) {
            sink.add_dfdx(ends[a], ends[b], a == b ? k : minus_k);
            if (damped) sink.add_dfdv(ends[a], ends[b], a == b ? d : minus_d);
          }
        }
      }
      return true;
    } else if constexpr (kHasJacobian) {
      BondedMatrix<N> dfdx, dfdv;
      Images images;
      for (Index s = 0; s < term_count(); ++s) {
        dfdx.setZero();
        dfdv.setZero();
        if (!law_.jacobian(point(p, s, images), coefficients(s), dfdx, dfdv)) continue;
        const bool damped = !dfdv.isZero(0.0);
        for (int a = 0; a < N; ++a) {
          for (int b = 0; b < N; ++b) {
            const Index i = terms_[s][a], j = terms_[s][b];
            sink.add_dfdx(i, j, dfdx.template block<3, 3>(3 * a, 3 * b));
            if (damped) sink.add_dfdv(i, j, dfdv.template block<3, 3>(3 * a, 3 * b));
          }
        }
      }
      return true;
    } else {
      return Force::add_jacobians(p, sink);
    }
  }

  // ---- BondedReference ----
  int bonded_arity() const override { return N; }
  Index bonded_terms() const override { return term_count(); }
  std::array<Index, 4> bonded_term(Index s) const override {
    std::array<Index, 4> out{-1, -1, -1, -1};
    for (int a = 0; a < N; ++a) out[a] = terms_[s][a];
    return out;
  }
  double bonded_term_forces(const ParticleView& p, Index s,
                            std::array<Vec3, 4>& force) const override {
    Images images;
    const BondedTerm<N> t = law_(point(p, s, images), coefficients(s));
    for (int a = 0; a < 4; ++a) force[a] = a < N ? t.force[a] : Vec3::Zero();
    return t.energy;
  }
  bool bonded_term_jacobian(const ParticleView& p, Index s, bool exact, Eigen::MatrixXd& dfdx,
                            Eigen::MatrixXd& dfdv) const override {
    BondedMatrix<N> dx = BondedMatrix<N>::Zero(), dv = BondedMatrix<N>::Zero();
    Images images;
    const BondedPoint<N> q = point(p, s, images);
    if (exact) {
      if constexpr (kHasExactJacobian) {
        law_.exact_jacobian(q, coefficients(s), dx, dv);
      } else if constexpr (kHasJacobian) {
        law_jacobian(q, coefficients(s), dx, dv);
      } else {
        return false;
      }
    } else {
      if constexpr (kHasJacobian) {
        law_jacobian(q, coefficients(s), dx, dv);
      } else {
        return false;
      }
    }
    dfdx = dx;
    dfdv = dv;
    return true;
  }

 private:
  static constexpr bool kHasPairJacobian =
      N == 2 &&
      requires(const Law& l, const BondedPoint<N>& q, const Coefficients& c, Eigen::Matrix3d& k) {
    l.pair_jacobian(q, c, k, k);
  };
  static constexpr bool kHasJacobian =
      kHasPairJacobian ||
      requires(const Law& l, const BondedPoint<N>& q, const Coefficients& c, BondedMatrix<N>& m) {
    l.jacobian(q, c, m, m);
  };

  // The law's jacobian(), or its pair_jacobian() as [k -k; -k k] blocks
  // (dfdx and dfdv given zeroed).
  bool law_jacobian(const BondedPoint<N>& q, const Coefficients& c, BondedMatrix<N>& dfdx,
                    BondedMatrix<N>& dfdv) const {
    if constexpr (kHasPairJacobian) {
      Eigen::Matrix3d k = Eigen::Matrix3d::Zero(), d = Eigen::Matrix3d::Zero();
      if (!law_.pair_jacobian(q, c, k, d)) return false;
      for (int a = 0; a < 2; ++a) {
        for (int b = 0; b < 2; ++b) {
          dfdx.template block<3, 3>(3 * a, 3 * b) = a == b ? k : Eigen::Matrix3d(-k);
          dfdv.template block<3, 3>(3 * a, 3 * b) = a == b ? d : Eigen::Matrix3d(-d);
        }
      }
      return true;
    } else {
      return law_.jacobian(q, c, dfdx, dfdv);
    }
  }
  static constexpr bool kHasExactJacobian =
      requires(const Law& l, const BondedPoint<N>& q, const Coefficients& c, BondedMatrix<N>& m) {
    l.exact_jacobian(q, c, m, m);
  };

  Index term_count() const { return static_cast<Index>(terms_.size()); }
  const Coefficients& coefficients(Index s) const {
    return coefficients_[types_.empty() ? 0 : static_cast<std::size_t>(types_[s])];
  }
  double rest(Index s) const { return uniform_rest_ ? rest0_ : rest_[static_cast<std::size_t>(s)]; }
  // Storage for a term's positions moved to their nearest images.
  using Images = std::array<Vec3, N>;

  // Points q's positions at each particle's image nearest the term's first
  // particle (Domain::nearest_image), stored in `images`: a term across a
  // periodic face then measures its true extent.
  static void to_nearest_images(const Domain& domain, BondedPoint<N>& q, Images& images) {
    images[0] = q.position(0);
    q.x[0] = images[0].data();
    for (int a = 1; a < N; ++a) {
      images[a] = domain.nearest_image(q.position(a), images[0]);
      q.x[a] = images[a].data();
    }
  }

  // Term s as the law sees it; in a periodic box its positions are moved
  // into `images`, which must outlive the returned point.
  BondedPoint<N> point(const ParticleView& p, Index s, Images& images) const {
    BondedPoint<N> q;
    for (int a = 0; a < N; ++a) {
      q.x[a] = p.x.data() + 3 * static_cast<Index>(terms_[s][a]);
      q.v[a] = p.v.data() + 3 * static_cast<Index>(terms_[s][a]);
    }
    q.rest = rest(s);
    if (p.domain.any_periodic()) to_nearest_images(p.domain, q, images);
    return q;
  }

  // What the force loop reads, copied into locals: through `this` and the
  // view, every store into f could alias them, and the compiler would
  // reload the pointers and coefficients once per term (issue 17: 20%
  // slower than the hand-fused reference at 10^6 particles).
  //
  // Periodic: the box's path, one instantiation for all terms (rest values
  // and types chosen per term at run time, positions moved to their
  // nearest images); the open-space paths stay as fast as before.
  template <bool Uniform, bool Typed, bool Periodic>
  struct Kernel {
    Law law;
    const double* __restrict x;  // 3 x N, column-major, stride 3
    const double* __restrict v;
    const std::array<Id, N>* __restrict terms;
    const double* __restrict rest;          // per term, or null if all are rest0
    const std::int32_t* __restrict types;   // per term, or null if all are type 0
    const Coefficients* __restrict coeffs;  // per type
    double rest0;
    Domain domain;  // read on the Periodic path only

    // `c0`: type 0's coefficients, copied by the caller into a local of its
    // loop, so that the compiler keeps them in registers.
    [[gnu::always_inline]] inline BondedTerm<N> term(Index s, const Coefficients& c0) const {
      BondedPoint<N> q;
      for (int a = 0; a < N; ++a) {
        q.x[a] = x + 3 * static_cast<Index>(terms[s][a]);
        q.v[a] = v + 3 * static_cast<Index>(terms[s][a]);
      }
      if constexpr (Periodic) {
        Images images;
        to_nearest_images(domain, q, images);
        q.rest = rest ? rest[s] : rest0;
        return law(q, types ? coeffs[types[s]] : c0);
      }
      q.rest = Uniform ? rest0 : rest[s];
      if constexpr (Typed) {
        return law(q, coeffs[types[s]]);
      } else {
        return law(q, c0);
      }
    }
  };

  template <class Stride>
  void accumulate(const ParticleView& p, double* f, Stride fs) const {
    if (p.domain.any_periodic()) {
      accumulate<false, true, true>(p, f, fs);
      return;
    }
    const bool typed = !types_.empty();
    if (uniform_rest_) {
      typed ? accumulate<true, true, false>(p, f, fs) : accumulate<true, false, false>(p, f, fs);
    } else {
      typed ? accumulate<false, true, false>(p, f, fs) : accumulate<false, false, false>(p, f, fs);
    }
  }

  template <bool Uniform, bool Typed, bool Periodic, class Stride>
  void accumulate(const ParticleView& p, double* f, Stride fs) const {
    const Index n_blocks = static_cast<Index>(block_start_.size()) - 1;
    const bool parallel = max_threads() > 1 && term_count() >= kParallelMinElements;
    const Kernel<Uniform, Typed, Periodic> k{law_,
                                             p.x.data(),
                                             p.v.data(),
                                             terms_.data(),
                                             uniform_rest_ ? nullptr : rest_.data(),
                                             types_.empty() ? nullptr : types_.data(),
                                             coefficients_.data(),
                                             rest0_,
                                             p.domain};
    const Index* block_start = block_start_.data();
    // Terms [begin, end) scattered straight into f, in order.
    auto direct = [&](Index begin, Index end) {
      const Coefficients c0 = k.coeffs[0];
      const auto* terms = k.terms;  // a local: stores into f cannot change it
      for (Index s = begin; s < end; ++s) {
        const BondedTerm<N> t = k.term(s, c0);
        for (int a = 0; a < N; ++a) {
          double* fa = f + fs * terms[s][a];
          fa[0] += t.force[a][0];
          fa[1] += t.force[a][1];
          fa[2] += t.force[a][2];
        }
      }
    };
    // Not `omp parallel for if (parallel)`: libgomp allocates a team for
    // every region, even a serial one, and stepping must not allocate. A
    // plugin built without OpenMP runs the blocks in order on one thread.
    if (!parallel) {
      // On one thread the blocks serve nothing: every term in order, the
      // boundary terms last. Each particle then receives its terms' forces
      // in the order the buffered path below adds them (block by block,
      // then its boundary terms in term order), so the bits are the same.
      direct(0, term_count());
      return;
    }
#ifdef _OPENMP
#pragma omp parallel for schedule(static)
#endif
    for (Index blk = 0; blk < n_blocks; ++blk) direct(block_start[blk], block_start[blk + 1]);
    const Index first = block_start_.back(), n_boundary = term_count() - first;
    if (n_boundary == 0) return;
    double* buffer = buffer_.data();
    parallel_ranges(n_boundary, [&](Index b, Index e) {
      const Coefficients c0 = k.coeffs[0];
      for (Index s = b; s < e; ++s) {
        const BondedTerm<N> t = k.term(first + s, c0);
        for (int a = 0; a < N; ++a) {
          double* out = buffer + 3 * (N * s + a);
          out[0] = t.force[a][0];
          out[1] = t.force[a][1];
          out[2] = t.force[a][2];
        }
      }
    });
    const Index* touched = touched_.data();
    const Index* touched_start = touched_start_.data();
    const Index* incident = incident_.data();
    parallel_ranges(static_cast<Index>(touched_.size()), [&](Index b, Index e) {
      for (Index t = b; t < e; ++t) {
        double* fi = f + fs * touched[t];
        for (Index q = touched_start[t]; q < touched_start[t + 1]; ++q) {
          const double* g = buffer + 3 * incident[q];
          fi[0] += g[0];
          fi[1] += g[1];
          fi[2] += g[2];
        }
      }
    });
  }

  // Orders the terms as add_forces uses them: the interior terms of block
  // 0, of block 1, ..., then the boundary terms, each group in the order
  // given (a stable counting sort), and builds the boundary CSR list. About
  // 64 blocks of at least 4096 particles each: enough to balance any thread
  // count up to a few dozen, few enough that boundary terms stay a small
  // fraction. Below 32768 particles, blocks of N/8 particles but at least
  // 1024, so that two threads share a 100 x 100 cloth evenly.
  void group_by_block(const BondedInput<N>& in, Index n) {
    const Index block = std::max({std::min<Index>(4096, (n + 7) / 8), (n + 63) / 64, Index{1024}});
    const Index n_blocks = std::max<Index>(1, (n + block - 1) / block);
    const Index n_terms = static_cast<Index>(in.terms.size());
    auto bucket = [&](const std::array<Index, N>& term) {
      const Index b = term[0] / block;
      for (int a = 1; a < N; ++a) {
        if (term[a] / block != b) return n_blocks;  // boundary
      }
      return b;
    };
    std::vector<Index> start(static_cast<std::size_t>(n_blocks + 2), 0);
    for (const auto& term : in.terms) ++start[bucket(term) + 1];
    for (Index b = 0; b <= n_blocks; ++b) start[b + 1] += start[b];
    terms_.resize(in.terms.size());
    rest_.resize(in.terms.size());
    if (!in.types.empty()) types_.resize(in.terms.size());
    std::vector<Index> next(start.begin(), start.end() - 1);
    for (Index s = 0; s < n_terms; ++s) {
      const Index to = next[bucket(in.terms[s])]++;
      for (int a = 0; a < N; ++a) terms_[to][a] = static_cast<Id>(in.terms[s][a]);
      rest_[to] = in.rest[s];
      if (!in.types.empty()) types_[to] = in.types[s];
    }
    uniform_rest_ =
        std::all_of(rest_.begin(), rest_.end(), [&](double r) { return r == rest_[0]; });
    rest0_ = rest_.empty() ? 0.0 : rest_[0];
    if (uniform_rest_) std::vector<double>().swap(rest_);
    if (!types_.empty() &&
        std::all_of(types_.begin(), types_.end(), [&](std::int32_t t) { return t == types_[0]; })) {
      // One type for all: keep its coefficients as type 0's.
      coefficients_ = {coefficients_[static_cast<std::size_t>(types_[0])]};
      std::vector<std::int32_t>().swap(types_);
    }
    block_start_.assign(start.begin(), start.end() - 1);  // n_blocks + 1 entries
    const Index first = block_start_.back(), n_boundary = n_terms - first;
    // CSR over the particles the boundary terms touch, in id order.
    std::vector<std::pair<Index, Index>> ends;  // (particle, N s + a)
    ends.reserve(static_cast<std::size_t>(N * n_boundary));
    for (Index s = 0; s < n_boundary; ++s) {
      for (int a = 0; a < N; ++a) ends.emplace_back(terms_[first + s][a], N * s + a);
    }
    std::sort(ends.begin(), ends.end());  // by particle, then term order
    for (std::size_t e = 0; e < ends.size(); ++e) {
      if (e == 0 || ends[e].first != ends[e - 1].first) {
        touched_.push_back(ends[e].first);
        touched_start_.push_back(static_cast<Index>(e));
      }
      incident_.push_back(ends[e].second);
    }
    touched_start_.push_back(static_cast<Index>(ends.size()));
    buffer_.resize(3, N * n_boundary);
  }

  Law law_;
  std::vector<Coefficients> coefficients_;  // per term type
  std::vector<std::array<Id, N>> terms_;    // grouped by block (group_by_block)
  std::vector<double> rest_;                // per term; empty if uniform_rest_
  std::vector<std::int32_t> types_;         // per term; empty if all are type 0
  bool uniform_rest_ = false;               // every term has rest value rest0_
  double rest0_ = 0.0;
  std::vector<Index> block_start_;    // block b's interior terms: [start[b], start[b + 1])
  std::vector<Index> touched_;        // particles with boundary terms, increasing
  std::vector<Index> touched_start_;  // their entries in incident_
  std::vector<Index> incident_;       // N s + a: particle a of boundary term s
  mutable Matrix3X buffer_;           // boundary terms' forces, N
};

}  // namespace pdyn
