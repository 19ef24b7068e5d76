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
// and derives from, or instantiates, PairForce<Law>. A central law may also
// give the derivative of its force for implicit solvers' Jacobians:
//
//     // d/d(r^2) of -U'(r)/r (N/m^3) at r2 < rc^2.
//     double force_over_r_slope(double r2, std::int32_t ti, std::int32_t tj) const;
//
// With g = -U'(r)/r and d = x_i - x_j, F_ij = g d and dF_ij/dx_i =
// g I + 2 g'(r^2) d d^T = -dF_ij/dx_j; PairForce then gives add_jacobians()
// (without it an implicit solver differentiates add_forces numerically, and
// `pdyn check`'s force.jacobians row compares the two). A law that needs more
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
// A central law that is finite and cheap at every r2 > 0 (Lennard-Jones,
// Morse, a soft sphere; not a table indexed by r2) may declare
//
//   static constexpr bool evaluate_beyond_cutoff = true;
//
// The force loop then calls it on every listed pair, the third or so of a
// Verlet list that lies between the cutoff and the list's reach included,
// and keeps the pairs within the cutoff by a select rather than a branch
// (its value beyond the cutoff is never used, whatever it is). That branch
// mispredicts on a liquid, where it decides in no predictable order; without
// it the law's arithmetic also runs in vector registers: on LAMMPS's
// Lennard-Jones melt the whole `pdyn run` took 0.7 times as long. The
// forces are the same bits either way.
//
// Threads and determinism (pdyn/parallel.hpp's rule: bit-identical results
// for every thread count). On one thread the loop is LAMMPS's half-list
// loop: for each i in order, for each listed j > i, F_ij is added to a
// running f_i and subtracted from f_j. So each f_j receives, after the force
// it already had, -F_kj for every listed k < j in increasing k, then +F_jl
// for its own list in order. On T threads each thread owns a contiguous
// range [b, e) of particles and reproduces exactly that sequence for its own
// particles without writing anyone else's: first -F_kj of the pairs that
// reach into its range from earlier ranges (k < b, increasing k: they come
// first in the one-thread order too), then the one-thread loop over its own
// rows, where a partner j >= e is skipped (its owner subtracts F_ij). A pair
// across two ranges is thus evaluated twice, once by each owner, with the
// same arithmetic on the same numbers; with particles numbered in space
// (a lattice, a grid, or after a spatial sort) that is a few per cent of
// the pairs, so T threads run up to nearly T times faster, with no shared
// buffer and no barrier in the force loop. Plugins are built with
// -ffp-contract=off (pdyn_add_plugin) so that no compiler fuses the
// arithmetic of two copies of the pair evaluation differently.
//
// Periodic boxes. Every separation is measured to the nearest image, so a
// PairForce is PeriodicInvariant (pdyn/periodic_invariant.hpp): the wrap
// after each step does not make velocity Verlet evaluate it again.
//
// Special bonds (pdyn/special_bonds.hpp). Given the scene's SpecialBonds,
// the loops run over the neighbor list's rows with the pairs of weight 0
// left out (copied after each list build, O(listed pairs)), and, only when
// some weight lies strictly between 0 and 1, multiply each pair's energy
// and force by its weight. Without special bonds, or with exclusions only
// (LAMMPS's `special_bonds fene`), the loop is the one above.
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

#include <algorithm>
#include <array>
#include <cmath>
#include <concepts>
#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <type_traits>
#include <utility>
#include <vector>

#include "pdyn/error.hpp"
#include "pdyn/export.hpp"
#include "pdyn/force.hpp"
#include "pdyn/neighbors.hpp"
#include "pdyn/parallel.hpp"
#include "pdyn/periodic_invariant.hpp"
#include "pdyn/special_bonds.hpp"
#include "pdyn/thermo.hpp"

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
PDYN_API void check_cutoff_fits(const Domain& domain, double cutoff, double skin);

/// The optional checking hook of a pair force: what the conformance kit
/// (`pdyn check`, the pair.* checks) compares the force's fast path with.
/// PairForce<Law> implements it; a pair force written by hand may too. The
/// kit finds it with dynamic_cast<const PairReference*> on the Force, so it
/// is a separate interface, not a new virtual of Force: forces built against
/// an earlier SDK keep their vtable (no ABI bump).
class PDYN_API PairReference {
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
  /// The force's neighbor list, if it has one (for statistics: builds(),
  /// pair_count()).
  virtual const NeighborList* pair_neighbors() const { return nullptr; }
};

/// The optional report of which loop a pair force runs, beside
/// PairReference: `pdyn check`'s pair.selecting_loop reads it to tell an
/// author whose central law branches at the cutoff that declaring
/// `evaluate_beyond_cutoff` would make it faster. Found with dynamic_cast,
/// so a force built against an SDK without it keeps its vtable and the kit
/// says nothing of its loop.
class PDYN_API PairLoop {
 public:
  virtual ~PairLoop();
  /// True for a central law (U of the distance and the types): one that may
  /// declare evaluate_beyond_cutoff.
  virtual bool central_law() const = 0;
  /// True when the loop evaluates the law on every listed pair and selects
  /// those within the cutoff (the law declares evaluate_beyond_cutoff).
  virtual bool selects_beyond_cutoff() const = 0;
};

/// Since 0.10.0, beside PairReference: how far a pair force's neighbor list
/// reaches, known before any evaluation. A host that cuts the space among
/// MPI ranks chooses each rank's ghost copies by it (pdyn/host/decomposed.hpp).
/// Found with dynamic_cast, so a force built against an earlier SDK keeps
/// its vtable; the host then learns the range from a first evaluation.
class PDYN_API PairRange {
 public:
  virtual ~PairRange();
  /// The skin of the force's neighbor list, m: it lists the pairs closer
  /// than pair_cutoff() + pair_skin().
  virtual double pair_skin() const = 0;
};

/// A force from a central pair law within a cutoff (see the top of this
/// file). `members`: N flags (a selection) or empty for every particle; only
/// pairs of two members interact.
template <class Law>
class PairForce : public Force,
                  public PairReference,
                  public PairLoop,
                  public PairRange,
                  public PeriodicInvariant,
                  public VirialSource,
                  public SpecialBondsTarget {
 public:
  PairForce(Law law, double cutoff, double skin, std::vector<std::uint8_t> members = {})
      : law_(std::move(law)),
        cutoff2_(cutoff * cutoff),
        shared_(cutoff, skin, NeighborList::Kind::Half),
        members_(std::move(members)) {}

  void add_forces(const ParticleView& p, Eigen::Ref<Matrix3X> f) override {
    update(p);
    const Index n = p.size();
    if (n == 0) return;
#ifdef _OPENMP
    if (max_threads() > 1 && n >= kParallelMinElements && !omp_in_parallel()) {
      parallel_forces(p, f);
      return;
    }
#endif
    const Rows r = rows();
    if (r.which) {
      range_forces<true>(p, f, 0, n, 0, r);
    } else {
      range_forces<false>(p, f, 0, n, 0, r);
    }
  }

  /// Sum of w U over the pairs closer than the cutoff (w: the pair's
  /// special-bond weight, 1 without special bonds), J.
  std::optional<double> potential_energy(const ParticleView& p) const override {
    double u = 0.0;
    for_each_pair(p, [&](Index i, Index j, const Vec3& d, double r2, double w) {
      u += w * evaluate(p, i, j, d, r2).energy;
    });
    return u;
  }

  /// Sum over the pairs closer than the cutoff of (x_i - x_j) . f_ij, the
  /// separation to the nearest image (pdyn/thermo.hpp), J.
  double virial(const ParticleView& p) const override {
    if constexpr (kSelect) {
      return selected_virial(p);
    } else {
      double w = 0.0;
      for_each_pair(p, [&](Index i, Index j, const Vec3& d, double r2, double wt) {
        w += d.dot(wt * evaluate(p, i, j, d, r2).force);
      });
      return w;
    }
  }

  const Law& law() const noexcept { return law_; }

  /// A central law is a function of r^2 and the types only; a vector law
  /// sees the whole ParticleView (velocities included).
  StateDependence dependence() const override {
    if constexpr (kCentral) {
      return {false, false};
    } else {
      return {};
    }
  }

  /// df/dx of every listed pair within the cutoff (see the top of this
  /// file), when the law gives force_over_r_slope(); false otherwise. No
  /// df/dv: a central law depends on positions only.
  bool add_jacobians(const ParticleView& p, JacobianSink& sink) override {
    if constexpr (kCentral && requires(const Law& l) {
                    {
                      l.force_over_r_slope(1.0, std::int32_t{}, std::int32_t{})
                      } -> std::convertible_to<double>;
                  }) {
      for_each_pair(p, [&](Index i, Index j, const Vec3& d, double r2, double w) {
        const std::int32_t ti = type_of(p, i), tj = type_of(p, j);
        const double g = law_(r2, ti, tj).force_over_r;
        const Eigen::Matrix3d k =
            w * (g * Eigen::Matrix3d::Identity() +
                 (2.0 * law_.force_over_r_slope(r2, ti, tj)) * d * d.transpose());
        sink.add_dfdx(i, i, k);
        sink.add_dfdx(i, j, -k);
        sink.add_dfdx(j, i, -k);
        sink.add_dfdx(j, j, k);
      });
      return true;
    } else {
      return Force::add_jacobians(p, sink);
    }
  }

  // ---- SpecialBondsTarget ----
  void set_special_bonds(std::shared_ptr<const SpecialBonds> special) override {
    special_ = special && !special->empty() ? std::move(special) : nullptr;
    scales_ = special_ && special_->scales();
    rows_stamp_ = 0;  // rebuild the rows, and the threads' lists, at the next evaluation
    cross_stamp_ = 0;
  }
  const SpecialBonds* special_bonds() const override { return special_.get(); }

  // ---- PairLoop ----
  bool central_law() const override { return kCentral; }
  bool selects_beyond_cutoff() const override { return kSelect; }

  // ---- PairRange ----
  double pair_skin() const override { return shared_.skin(); }

  // ---- PairReference ----
  double pair_cutoff() const override { return std::sqrt(cutoff2_); }
  /// The neighbor list of the last evaluation, shared with the other pair
  /// forces on the same particles (SharedNeighborList); nullptr before the
  /// first evaluation.
  const NeighborList* pair_neighbors() const override { return shared_.list(); }
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
        const double w = special_ ? special_->weight(i, j) : 1.0;
        if (w == 0.0) continue;
        const PairVector t = evaluate(p, i, j, d, r2);
        f.col(i) += w * t.force;
        f.col(j) -= w * t.force;
        u += w * t.energy;
      }
    }
    return u;
  }

 private:
  const NeighborList& update(const ParticleView& p) const {
    // Particles added since (an interactive host's) are not members.
    if (!members_.empty()) members_.resize(static_cast<std::size_t>(p.size()), 0);
    return shared_.update(p.x, p.domain, members_.empty() ? nullptr : &members_);
  }

  // The rows the loops run over (after update()): the neighbor list's, or
  // with special bonds its copy without the excluded pairs, rebuilt after
  // each list build. which (per listed pair, an index into scale) only when
  // some pair is scaled rather than excluded.
  struct Rows {
    const Index* offsets = nullptr;
    const Index* indices = nullptr;
    const std::uint8_t* which = nullptr;
    const double* scale = nullptr;
  };
  Rows rows() const {
    const NeighborList& list = *shared_.list();
    if (!special_) return {list.offsets().data(), list.indices().data(), nullptr, nullptr};
    if (rows_stamp_ != list.stamp()) {
      special_rows_.build(list.offsets(), list.indices(), *special_);
      rows_stamp_ = list.stamp();
    }
    return {special_rows_.offsets(), special_rows_.indices(),
            scales_ ? special_rows_.which() : nullptr, special_rows_.scale().data()};
  }

  // visit(i, j, d, r2, w) for every listed pair closer than the cutoff, w its
  // special-bond weight, in the one-thread loop's order (the serial paths:
  // energy, virial, Jacobians).
  template <class Visit>
  void for_each_pair(const ParticleView& p, Visit&& visit) const {
    update(p);
    const Rows r = rows();
    const Images im(p.domain);
    for (Index i = 0; i < p.size(); ++i) {
      for (Index k = r.offsets[i]; k < r.offsets[i + 1]; ++k) {
        const Index j = r.indices[k];
        const Vec3 d = separation(p, im, i, j);
        const double r2 = d.squaredNorm();
        if (r2 < cutoff2_) visit(i, j, d, r2, r.which ? r.scale[r.which[k]] : 1.0);
      }
    }
  }

  static std::int32_t type_of(const ParticleView& p, Index i) {
    return p.type.empty() ? 0 : p.type[static_cast<std::size_t>(i)];
  }

  // The box as the pair loop needs it, read once per evaluation.
  // Along an open axis length = 0 and half = +inf: nothing is ever folded.
  struct Images {
    bool any = false;
    Vec3 length = Vec3::Zero(), half = Vec3::Zero();
    explicit Images(const Domain& d) : any(d.any_periodic()) {
      for (int k = 0; k < 3; ++k) {
        length[k] = d.periodic[k] ? d.max[k] - d.min[k] : 0.0;
        half[k] = d.periodic[k] ? 0.5 * length[k] : std::numeric_limits<double>::infinity();
      }
    }
  };

  // x_i - x_j, to the nearest image along periodic axes. Positions are
  // wrapped after every step and move little within one, so |d_k| < 1.5 L
  // almost always and one conditional add gives the nearest image without
  // the rounding call of Domain::minimum_image, which stays the fallback.
  // Branches, not arithmetic selects: few pairs straddle a face, and those
  // of one particle come together, so the branches are well predicted; a
  // branch-free fold (an add of -L, 0 or +L chosen by two comparisons) made
  // the LJ melt 1.9 times slower.
  [[gnu::always_inline]] static inline Vec3 separation(const double* xi, const double* xj,
                                                       const Images& im) {
    Vec3 d(xi[0] - xj[0], xi[1] - xj[1], xi[2] - xj[2]);
    if (!im.any) return d;
    if ((std::abs(d[0]) > im.half[0]) | (std::abs(d[1]) > im.half[1]) |
        (std::abs(d[2]) > im.half[2])) [[unlikely]] {
      for (int k = 0; k < 3; ++k) {
        if (d[k] > im.half[k]) {
          d[k] -= im.length[k];
        } else if (d[k] < -im.half[k]) {
          d[k] += im.length[k];
        }
        if (!(std::abs(d[k]) <= im.half[k])) d[k] -= im.length[k] * std::round(d[k] / im.length[k]);
      }
    }
    return d;
  }
  [[gnu::always_inline]] static inline Vec3 separation(const ParticleView& p, const Images& im,
                                                       Index i, Index j) {
    return separation(p.x.data() + 3 * i, p.x.data() + 3 * j, im);
  }

  // The law, in whichever of its two forms it is written.
  static constexpr bool kCentral =
      std::is_invocable_r_v<PairTerm, const Law&, double, std::int32_t, std::int32_t>;
  // A central law that declares `static constexpr bool evaluate_beyond_cutoff
  // = true` may be called at any listed distance, r2 > 0 up to the list's
  // reach, its value there discarded: the force loop then selects instead of
  // branching (range_forces_selected).
  static constexpr bool kSelect = [] {
    if constexpr (kCentral && requires { Law::evaluate_beyond_cutoff; }) {
      return static_cast<bool>(Law::evaluate_beyond_cutoff);
    } else {
      return false;
    }
  }();
  [[gnu::always_inline]] inline PairVector evaluate(const ParticleView& p, Index i, Index j,
                                                    const Vec3& d, double r2) const {
    if constexpr (kCentral) {
      const PairTerm t = law_(r2, type_of(p, i), type_of(p, j));
      return {t.energy, t.force_over_r * d};
    } else {
      return law_(p, PairPoint{i, j, d, r2});
    }
  }

  // The forces on particles [begin, end) (see the top of this file): first
  // the pairs of earlier ranges that reach into it (cross_[0, owner)), then
  // its own rows. With [0, N) it is the one-thread loop. Raw pointers and
  // strides are read once: through the Ref and the span the compiler would
  // reload them after every store to f. Weighted: rows r give each pair's
  // special-bond weight (r.which), which multiplies its force.
  template <bool Weighted>
  void range_forces(const ParticleView& p, Eigen::Ref<Matrix3X> f, Index begin, Index end,
                    std::size_t owner, const Rows& r) const {
    const Images im(p.domain);
    const double* x = p.x.data();
    double* fd = f.data();
    const Index fs = f.outerStride();
    for (std::size_t t = 0; t < owner; ++t) {
      for (const auto& [i, j, which] : cross_[t]) {
        if (j < begin || j >= end) continue;
        const Vec3 d = separation(x + 3 * i, x + 3 * j, im);
        const double r2 = d.squaredNorm();
        if (!(r2 < cutoff2_)) continue;
        Vec3 fij = evaluate(p, i, j, d, r2).force;
        if constexpr (Weighted) fij *= r.scale[which];
        Eigen::Map<Vec3>(fd + fs * j) -= fij;
      }
    }
    const Index* offsets = r.offsets;
    const Index* indices = r.indices;
    if constexpr (kSelect) {
      range_forces_selected<Weighted>(p, fd, fs, r, begin, end, im);
      return;
    }
    for (Index i = begin; i < end; ++i) {
      const double* xi = x + 3 * i;
      Vec3 fi = Eigen::Map<const Vec3>(fd + fs * i);
      for (Index k = offsets[i]; k < offsets[i + 1]; ++k) {
        const Index j = indices[k];
        const Vec3 d = separation(xi, x + 3 * j, im);
        const double r2 = d.squaredNorm();
        if (!(r2 < cutoff2_)) continue;
        Vec3 fij = evaluate(p, i, j, d, r2).force;
        if constexpr (Weighted) fij *= r.scale[r.which[k]];
        fi += fij;
        if (j < end) Eigen::Map<Vec3>(fd + fs * j) -= fij;
      }
      Eigen::Map<Vec3>(fd + fs * i) = fi;
    }
  }

  // g[k] = -U'(r)/r of a block of m pairs of particle type ti with r^2 =
  // r2s[k] and types tj[k], 0 for those beyond the cutoff: the law on every
  // pair, in vector registers, and a select, so that a value beyond the
  // cutoff (even inf or NaN) is never used. The force loop's and the
  // virial's (kSelect).
  [[gnu::always_inline]] inline void selected_law(std::int32_t ti, const double* r2s,
                                                  const std::int32_t* tj, Index m,
                                                  double* g) const {
    const double cutoff2 = cutoff2_;
#ifdef _OPENMP
#pragma omp simd
#endif
    for (Index k = 0; k < m; ++k) {
      const double v = law_(r2s[k], ti, tj[k]).force_over_r;
      g[k] = r2s[k] < cutoff2 ? v : 0.0;
    }
  }

  // g[k] times the special-bond weight of list entry k0 + k.
  static void weigh(const Rows& r, Index k0, Index m, double* g) {
    const std::uint8_t* which = r.which + k0;
    for (Index k = 0; k < m; ++k) g[k] *= r.scale[which[k]];
  }

  // The own rows of range_forces for a law that may be evaluated beyond its
  // cutoff (kSelect): each row in blocks, first the separations, then the
  // law on every listed pair with the out-of-range values replaced by 0 (a
  // select, so that a value beyond the cutoff, even inf or NaN, is never
  // used), then the sums in the same order as the branching loop. About 30%
  // of a Verlet list (skin 0.3 at cutoff 2.5) lies beyond the cutoff, in no
  // predictable order: the branch on r2 mispredicts, the select does not,
  // and the law's arithmetic runs in vector registers. A pair beyond the
  // cutoff adds 0 * d, which leaves every sum unchanged. Weighted: each g
  // is multiplied by its pair's special-bond weight.
  template <bool Weighted>
  void range_forces_selected(const ParticleView& p, double* fd, Index fs, const Rows& r,
                             Index begin, Index end, const Images& im) const {
    const Index* offsets = r.offsets;
    const Index* indices = r.indices;
    constexpr Index kBlock = 64;
    alignas(64) double dx[kBlock], dy[kBlock], dz[kBlock], r2s[kBlock], g[kBlock];
    alignas(64) std::int32_t tj[kBlock];
    const double* x = p.x.data();
    for (Index i = begin; i < end; ++i) {
      const double* xi = x + 3 * i;
      const std::int32_t ti = type_of(p, i);
      Vec3 fi = Eigen::Map<const Vec3>(fd + fs * i);
      for (Index k0 = offsets[i]; k0 < offsets[i + 1]; k0 += kBlock) {
        const Index m = std::min(kBlock, offsets[i + 1] - k0);
        const Index* row = indices + k0;
        for (Index k = 0; k < m; ++k) {
          const Vec3 d = separation(xi, x + 3 * row[k], im);
          dx[k] = d[0];
          dy[k] = d[1];
          dz[k] = d[2];
          r2s[k] = d.squaredNorm();
          tj[k] = type_of(p, row[k]);
        }
        selected_law(ti, r2s, tj, m, g);
        if constexpr (Weighted) weigh(r, k0, m, g);
        for (Index k = 0; k < m; ++k) {
          const Index j = row[k];
          const Vec3 fij = g[k] * Vec3(dx[k], dy[k], dz[k]);
          fi += fij;
          if (j < end) Eigen::Map<Vec3>(fd + fs * j) -= fij;
        }
      }
      Eigen::Map<Vec3>(fd + fs * i) = fi;
    }
  }

  // The virial of a law the force loop selects on (kSelect): per pair
  // r^2 g(r^2) (w) for r < cutoff, g = -U'/r, in blocks whose law runs in
  // vector registers as range_forces_selected's. A barostat asks for it at
  // every step, so it is summed over fixed chunks of rows on the host's
  // threads, each chunk in row order and the chunks' sums in chunk order:
  // the same bits for any thread count.
  double selected_virial(const ParticleView& p) const {
    update(p);
    const Rows r = rows();
    const Images im(p.domain);
    const Index n = p.size();
    constexpr Index kRows = 512;
    std::vector<double> sums(static_cast<std::size_t>((n + kRows - 1) / kRows), 0.0);
    parallel_ranges(n, [&](Index begin, Index end) {
      constexpr Index kBlock = 64;
      alignas(64) double r2s[kBlock], g[kBlock];
      alignas(64) std::int32_t tj[kBlock];
      const double* x = p.x.data();
      for (Index c = (begin + kRows - 1) / kRows; c * kRows < end; ++c) {
        double w = 0.0;
        for (Index i = c * kRows; i < std::min(n, (c + 1) * kRows); ++i) {
          const std::int32_t ti = type_of(p, i);
          for (Index k0 = r.offsets[i]; k0 < r.offsets[i + 1]; k0 += kBlock) {
            const Index m = std::min(kBlock, r.offsets[i + 1] - k0);
            const Index* row = r.indices + k0;
            for (Index k = 0; k < m; ++k) {
              r2s[k] = separation(x + 3 * i, x + 3 * row[k], im).squaredNorm();
              tj[k] = type_of(p, row[k]);
            }
            selected_law(ti, r2s, tj, m, g);
            // r^2 g; beyond the cutoff 0, whatever r^2 is.
            for (Index k = 0; k < m; ++k) g[k] *= r2s[k] < cutoff2_ ? r2s[k] : 0.0;
            if (r.which) weigh(r, k0, m, g);
            for (Index k = 0; k < m; ++k) w += g[k];
          }
        }
        sums[static_cast<std::size_t>(c)] = w;
      }
    });
    double w = 0.0;
    for (const double s : sums) w += s;
    return w;
  }

#ifdef _OPENMP
  // One parallel region: each thread takes the range pdyn::parallel_ranges
  // would give it. After a list rebuild (or a change of N or of the thread
  // count) each thread first lists the pairs of its rows that reach past its
  // range, in row order, and all wait for all.
  void parallel_forces(const ParticleView& p, Eigen::Ref<Matrix3X> f) {
    const Index n = p.size();
    const NeighborList& list = *shared_.list();
    const Rows r = rows();
    const bool listed = cross_stamp_ == list.stamp() && cross_n_ == n;
#pragma omp parallel
    {
      const Index t = omp_get_thread_num(), nt = omp_get_num_threads();
      const Index begin = n * t / nt, end = n * (t + 1) / nt;
      const bool relist = !listed || cross_threads_ != nt;
#pragma omp barrier
      if (relist) {
#pragma omp single
        {
          if (cross_.size() < static_cast<std::size_t>(nt))
            cross_.resize(static_cast<std::size_t>(nt));
          cross_stamp_ = list.stamp();
          cross_n_ = n;
          cross_threads_ = nt;
        }
        auto& out = cross_[static_cast<std::size_t>(t)];
        out.clear();
        for (Index i = begin; i < end; ++i) {
          for (Index k = r.offsets[i]; k < r.offsets[i + 1]; ++k) {
            const Index j = r.indices[k];
            if (j >= end) out.push_back({i, j, r.which ? r.which[k] : std::uint8_t{0}});
          }
        }
#pragma omp barrier
      }
      if (r.which) {
        range_forces<true>(p, f, begin, end, static_cast<std::size_t>(t), r);
      } else {
        range_forces<false>(p, f, begin, end, static_cast<std::size_t>(t), r);
      }
    }
  }
#endif

  Law law_;
  double cutoff2_;
  mutable SharedNeighborList shared_;  // brought up to date by const potential_energy too
  mutable std::vector<std::uint8_t> members_;
  // Special bonds (nullptr: none), whether some weight lies strictly
  // between 0 and 1, and the rows without the excluded pairs, valid for the
  // list build stamped rows_stamp_.
  std::shared_ptr<const SpecialBonds> special_;
  bool scales_ = false;
  mutable SpecialRows special_rows_;
  mutable std::uint64_t rows_stamp_ = 0;
  // The threaded path's pairs across ranges: cross_[t] holds, in row order,
  // the listed (i, j) with i in thread t's range and j past it, and the
  // pair's special-bond weight index; valid for the list build stamped
  // cross_stamp_, N = cross_n_ and cross_threads_ threads.
  struct Cross {
    Index i, j;
    std::uint8_t which;
  };
  std::vector<std::vector<Cross>> cross_;
  std::uint64_t cross_stamp_ = 0;
  Index cross_n_ = -1, cross_threads_ = 0;
};

}  // namespace pdyn
