// pdyn/pair.hpp — pair forces: the author writes the law, the kernel runs
// the loop.
//
// A central pair potential U(r) between particles closer than a cutoff rc
// (Lennard-Jones, soft spheres, a cut-off Coulomb or gravity) is one
// function of the distance; everything else, the neighbor search, the loop
// over pairs, Newton's third law, the threads and the periodic images, is
// the same for all of them. As a LAMMPS pair style's compute() is, but
// written once: a plugin supplies a *law*,
//
//   struct Law {
//     // U (J) and -U'(r)/r (N/m) at squared distance r2 < rc^2 (m^2), for
//     // particles of types ti and tj (0 when the scene gives no types).
//     pdyn::PairTerm operator()(double r2, std::int32_t ti, std::int32_t tj) const;
//   };
//
// and derives from, or instantiates, PairForce<Law>. A law that needs more
// than the distance (a contact law: radii, relative velocity, masses) takes
// the pair itself instead and returns the force vector:
//
//   pdyn::PairVector operator()(const pdyn::ParticleView& p, const pdyn::PairPoint& q) const;
//
// with q.d = x_i - x_j (nearest image) and q.r2 = |q.d|^2 < rc^2. The force on i from j
// is F_ij = (-U'(r)/r) (x_i - x_j), on j it is -F_ij, and the energy is
// sum over pairs of U(r_ij). The law's call is inlined into the loop (a
// template, not a virtual call per pair).
//
// Threads and determinism (pdyn/parallel.hpp's rule: bit-identical results
// for every thread count). On one thread the loop is LAMMPS's half-list
// loop: for each i in order, for each listed j > i, F_ij is added to a
// running f_i and subtracted from f_j. On several, the same sums are formed
// in the same order without any two threads writing one particle: pass 1
// computes every pair's F_ij into a buffer (in parallel over i); pass 2
// gives each particle j, starting from the force it already had, first
// -F_ij of every pair (i, j) with i < j in increasing i, then +F_jk of its
// own pairs in list order: exactly the operations, in exactly the order,
// of the one-thread loop. Plugins are built with -ffp-contract=off
// (pdyn_add_plugin) so that no compiler fuses the two paths' arithmetic
// differently.
//
// Checking (PairReference below). Every PairForce also offers the
// conformance kit (`pdyn check`) what it needs to check the pair loop
// against the law: the cutoff, a brute-force sum over all pairs (no
// neighbor list), and whether the energy is continuous at the cutoff. A law
// declares the last with a member
//
//   bool continuous_at_cutoff() const;  // true: U(r) -> 0 as r -> rc
//
// (a shifted energy, or one that vanishes there by itself); a law without
// it declares nothing, and the kit skips that check.
#pragma once

#include <array>
#include <cmath>
#include <concepts>
#include <cstdint>
#include <optional>
#include <span>
#include <type_traits>
#include <vector>

#include "pdyn/error.hpp"
#include "pdyn/force.hpp"
#include "pdyn/neighbors.hpp"
#include "pdyn/parallel.hpp"

namespace pdyn {

/// A pair law's value at one distance.
struct PairTerm {
  double energy = 0.0;        ///< U(r), J
  double force_over_r = 0.0;  ///< -U'(r) / r, N/m (> 0 repulsive)
};

/// One pair as a general law sees it.
struct PairPoint {
  Index i = 0, j = 0;     ///< the particles, i < j
  Vec3 d = Vec3::Zero();  ///< x_i - x_j to the nearest image, m
  double r2 = 0.0;        ///< |d|^2 < cutoff^2, m^2
};

/// A general law's value for one pair.
struct PairVector {
  double energy = 0.0;        ///< potential energy of the pair, J (0 if none)
  Vec3 force = Vec3::Zero();  ///< force on i, N; on j it is -force
};

/// Throws ParamError on "cutoff" unless a list of reach cutoff + skin (m)
/// fits the box along every periodic axis (L >= 2 reach: each particle then
/// meets at most one image of another). Call it from a pair force's factory
/// with SceneContext::particles.domain, so that the scene error points at
/// the force's cutoff.
void check_cutoff_fits(const Domain& domain, double cutoff, double skin);

/// The optional checking hook of a pair force: what the conformance kit
/// (`pdyn check`, the pair.* checks) compares the force's fast path with.
/// PairForce<Law> implements it; a pair force written by hand may too. The
/// kit finds it with dynamic_cast<const PairReference*> on the Force, so it
/// is a separate interface, not a new virtual of Force: forces built against
/// an earlier SDK keep their vtable (no ABI bump).
class PairReference {
 public:
  virtual ~PairReference();
  /// The cutoff rc, m: pairs at r >= rc do not interact.
  virtual double pair_cutoff() const = 0;
  /// True when the force declares its energy continuous at the cutoff: U(r)
  /// -> 0 as r -> rc from below (a shifted energy, or a law that vanishes
  /// there).
  virtual bool continuous_at_cutoff() const = 0;
  /// The reference evaluation: adds to `f` (N) the force of every pair i < j
  /// (of members) closer than the cutoff, measured to the nearest image with
  /// Domain::minimum_image, visiting all N (N - 1) / 2 pairs with no
  /// neighbor list, and returns the pairs' energy, J (0 for a force that
  /// reports none). O(N^2): for checks only.
  virtual double add_forces_all_pairs(const ParticleView& p, Eigen::Ref<Matrix3X> f) const = 0;
};

/// A force from a central pair law within a cutoff (see the top of this
/// file). `members`: N flags (a selection) or empty for every particle; only
/// pairs of two members interact.
template <class Law>
class PairForce : public Force, public PairReference {
 public:
  PairForce(Law law, double cutoff, double skin, std::vector<std::uint8_t> members = {})
      : law_(std::move(law)),
        cutoff2_(cutoff * cutoff),
        list_(cutoff, skin, NeighborList::Kind::Half),
        members_(std::move(members)) {}

  void add_forces(const ParticleView& p, Eigen::Ref<Matrix3X> f) override {
    update(p);
    const Index n = p.size();
    if (n == 0) return;
    if (max_threads() == 1 || n < kParallelMinElements) {
      serial_forces(p, f);
    } else {
      parallel_forces(p, f);
    }
  }

  /// Sum of U over the pairs closer than the cutoff, J.
  std::optional<double> potential_energy(const ParticleView& p) const override {
    update(p);
    double u = 0.0;
    const Images im(p.domain);
    for (Index i = 0; i < p.size(); ++i) {
      for (const Index j : list_.neighbors(i)) {
        const Vec3 d = separation(p, im, i, j);
        const double r2 = d.squaredNorm();
        if (r2 < cutoff2_) u += evaluate(p, i, j, d, r2).energy;
      }
    }
    return u;
  }

  const Law& law() const noexcept { return law_; }
  /// The neighbor list (for statistics: builds, pairs).
  const NeighborList& neighbor_list() const noexcept { return list_; }

  // ---- PairReference ----
  double pair_cutoff() const override { return std::sqrt(cutoff2_); }
  bool continuous_at_cutoff() const override {
    if constexpr (requires(const Law& l) {
                    { l.continuous_at_cutoff() } -> std::convertible_to<bool>;
                  }) {
      return law_.continuous_at_cutoff();
    } else {
      return false;
    }
  }
  double add_forces_all_pairs(const ParticleView& p, Eigen::Ref<Matrix3X> f) const override {
    auto member = [&](Index i) {
      return members_.empty() || (static_cast<std::size_t>(i) < members_.size() &&
                                  members_[static_cast<std::size_t>(i)] != 0);
    };
    double u = 0.0;
    for (Index i = 0; i < p.size(); ++i) {
      if (!member(i)) continue;
      for (Index j = i + 1; j < p.size(); ++j) {
        if (!member(j)) continue;
        const Vec3 d = p.domain.minimum_image(p.x.col(i) - p.x.col(j));
        const double r2 = d.squaredNorm();
        if (!(r2 < cutoff2_)) continue;
        const PairVector t = evaluate(p, i, j, d, r2);
        f.col(i) += t.force;
        f.col(j) -= t.force;
        u += t.energy;
      }
    }
    return u;
  }

 private:
  void update(const ParticleView& p) const {
    // Particles added since (an interactive host's) are not members.
    if (!members_.empty()) members_.resize(static_cast<std::size_t>(p.size()), 0);
    list_.update(p.x, p.domain, members_.empty() ? nullptr : &members_);
  }

  static std::int32_t type_of(const ParticleView& p, Index i) {
    return p.type.empty() ? 0 : p.type[static_cast<std::size_t>(i)];
  }

  // The box as the pair loop needs it, read once per evaluation.
  struct Images {
    std::array<bool, 3> periodic{};
    bool any = false;
    Vec3 length = Vec3::Zero(), half = Vec3::Zero();
    explicit Images(const Domain& d)
        : periodic(d.periodic), any(d.any_periodic()), length(d.length()), half(0.5 * d.length()) {}
  };

  // x_i - x_j, to the nearest image along periodic axes. Positions are
  // wrapped after every step and move little within one, so |d_k| < 1.5 L
  // almost always and one conditional add gives the nearest image without
  // the rounding call of Domain::minimum_image, which stays the fallback.
  [[gnu::always_inline]] static inline Vec3 separation(const ParticleView& p, const Images& im,
                                                       Index i, Index j) {
    Vec3 d = p.x.col(i) - p.x.col(j);
    if (!im.any) return d;
    for (int k = 0; k < 3; ++k) {
      if (!im.periodic[k]) continue;
      if (d[k] > im.half[k]) {
        d[k] -= im.length[k];
      } else if (d[k] < -im.half[k]) {
        d[k] += im.length[k];
      }
      if (!(std::abs(d[k]) <= im.half[k])) d[k] -= im.length[k] * std::round(d[k] / im.length[k]);
    }
    return d;
  }

  // F_ij, or zero beyond the cutoff (the list's skin shell).
  [[gnu::always_inline]] inline Vec3 pair_force(const ParticleView& p, const Images& im, Index i,
                                                Index j) const {
    const Vec3 d = separation(p, im, i, j);
    const double r2 = d.squaredNorm();
    if (!(r2 < cutoff2_)) return Vec3::Zero();
    return evaluate(p, i, j, d, r2).force;
  }

  // The law, in whichever of its two forms it is written.
  static constexpr bool kCentral =
      std::is_invocable_r_v<PairTerm, const Law&, double, std::int32_t, std::int32_t>;
  [[gnu::always_inline]] inline PairVector evaluate(const ParticleView& p, Index i, Index j,
                                                    const Vec3& d, double r2) const {
    if constexpr (kCentral) {
      const PairTerm t = law_(r2, type_of(p, i), type_of(p, j));
      return {t.energy, t.force_over_r * d};
    } else {
      return law_(p, PairPoint{i, j, d, r2});
    }
  }

  void serial_forces(const ParticleView& p, Eigen::Ref<Matrix3X> f) const {
    const Images im(p.domain);
    for (Index i = 0; i < p.size(); ++i) {
      Vec3 fi = f.col(i);
      for (const Index j : list_.neighbors(i)) {
        const Vec3 fij = pair_force(p, im, i, j);
        fi += fij;
        f.col(j) -= fij;
      }
      f.col(i) = fi;
    }
  }

  void parallel_forces(const ParticleView& p, Eigen::Ref<Matrix3X> f) {
    const auto offsets = list_.offsets();
    const auto indices = list_.indices();
    const Index n = p.size();
    if (transposed_build_ != list_.builds()) transpose(n, offsets, indices);
    pair_f_.resize(3 * indices.size());  // grows only: no allocation once warm
    const Images im(p.domain);
    parallel_ranges(n, [&](Index begin, Index end) {
      for (Index i = begin; i < end; ++i) {
        for (Index k = offsets[static_cast<std::size_t>(i)];
             k < offsets[static_cast<std::size_t>(i) + 1]; ++k) {
          const Vec3 fij = pair_force(p, im, i, indices[static_cast<std::size_t>(k)]);
          Eigen::Map<Vec3>(pair_f_.data() + 3 * k) = fij;
        }
      }
    });
    parallel_ranges(n, [&](Index begin, Index end) {
      for (Index j = begin; j < end; ++j) {
        Vec3 fj = f.col(j);
        for (Index t = t_offsets_[static_cast<std::size_t>(j)];
             t < t_offsets_[static_cast<std::size_t>(j) + 1]; ++t) {
          fj -= Eigen::Map<const Vec3>(pair_f_.data() + 3 * t_pairs_[static_cast<std::size_t>(t)]);
        }
        for (Index k = offsets[static_cast<std::size_t>(j)];
             k < offsets[static_cast<std::size_t>(j) + 1]; ++k) {
          fj += Eigen::Map<const Vec3>(pair_f_.data() + 3 * k);
        }
        f.col(j) = fj;
      }
    });
  }

  // For each particle j, the pairs (i, j) with i < j, in increasing i: the
  // order in which the one-thread loop subtracts their forces from f_j.
  // Rebuilt with the list (every 10-20 steps), O(pairs).
  void transpose(Index n, std::span<const Index> offsets, std::span<const Index> indices) {
    t_offsets_.assign(static_cast<std::size_t>(n) + 1, 0);
    for (const Index j : indices) ++t_offsets_[static_cast<std::size_t>(j) + 1];
    for (Index j = 0; j < n; ++j) {
      t_offsets_[static_cast<std::size_t>(j) + 1] += t_offsets_[static_cast<std::size_t>(j)];
    }
    t_pairs_.resize(indices.size());
    t_fill_.assign(t_offsets_.begin(), t_offsets_.end() - 1);
    for (Index i = 0; i < n; ++i) {
      for (Index k = offsets[static_cast<std::size_t>(i)];
           k < offsets[static_cast<std::size_t>(i) + 1]; ++k) {
        const auto j = static_cast<std::size_t>(indices[static_cast<std::size_t>(k)]);
        t_pairs_[static_cast<std::size_t>(t_fill_[j]++)] = k;
      }
    }
    transposed_build_ = list_.builds();
  }

  Law law_;
  double cutoff2_;
  mutable NeighborList list_;  // brought up to date by const potential_energy too
  mutable std::vector<std::uint8_t> members_;
  // The threaded path's scratch: per-pair forces and the transposed list.
  std::vector<double> pair_f_;
  std::vector<Index> t_offsets_, t_pairs_, t_fill_;
  std::int64_t transposed_build_ = -1;
};

}  // namespace pdyn
