// pdyn/neighbors.hpp — which particles are near which: a cell list that
// builds a Verlet neighbor list with a skin, for pair forces (Lennard-Jones,
// DEM contact, a cut-off n-body).
//
// A pair force with cutoff rc only needs the pairs closer than rc; testing
// all N^2 / 2 pairs at every derivative evaluation is what limits all-pairs
// codes to a few thousand particles. Two classic ideas make it O(N):
//
//   Cell list (Allen & Tildesley, "Computer Simulation of Liquids", 1987,
//   sec. 5.3.2): the box is cut into cells of side >= r; a particle's
//   partners closer than r are then in its own cell or the 26 around it.
//
//   Verlet list with a skin (L. Verlet, Phys. Rev. 159, 98, 1967): list the
//   pairs closer than rc + skin once, and reuse the list while no particle
//   has moved more than skin / 2 since: two particles that are now closer
//   than rc were then closer than rc + skin (triangle inequality), so the
//   list still holds every pair the force needs. A rebuild every 10-20 steps
//   instead of every step, for a force loop a little longer (the pairs in
//   the skin shell, which the force skips with its own r < rc test).
//
// A force owns one NeighborList, calls update() at the start of each
// evaluation and loops over neighbors(i):
//
//   list_.update(view.x, domain_);                 // rebuilds only when needed
//   for (Index i = 0; i < list_.size(); ++i)
//     for (Index j : list_.neighbors(i)) {
//       const Vec3 d = domain_.minimum_image(view.x.col(j) - view.x.col(i));
//       if (d.squaredNorm() < rc * rc) { ... }     // the list also holds the skin shell
//     }
//
// Lists are bit-identical for every thread count (pdyn/parallel.hpp), and
// neighbors(i) is sorted by index, so a force that sums over it in order gets
// the same bits whether or not the list was rebuilt since the last call (a
// pair in the skin shell adds an exact zero).
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "pdyn/domain.hpp"
#include "pdyn/export.hpp"
#include "pdyn/types.hpp"

namespace pdyn {

/// A Verlet neighbor list with a skin, built with a cell list (see the top of
/// this file). The list is stored in compressed sparse row (CSR) form:
/// particle i's neighbors are indices()[offsets()[i] .. offsets()[i + 1]).
///
/// Guarantee: right after update(x, domain), every pair of particles closer
/// than cutoff() at positions x (nearest image along periodic axes) is in the
/// list, whether update() rebuilt or not; the list holds exactly the pairs
/// within reach() = cutoff + skin at the last build (to rounding in the last
/// bits of a distance). Forces must still test r < cutoff.
/// Along a periodic axis a pair is listed once, by index: apply
/// Domain::minimum_image to x_j - x_i to get its separation.
///
/// Particles with a non-finite coordinate (NaN or inf, as in a run that blows
/// up) are never listed and have no neighbors. Not thread-safe: one list per
/// force, updated from the thread that evaluates the force (its builds are
/// themselves parallel).
class PDYN_API NeighborList {
 public:
  /// How pairs are stored.
  enum class Kind {
    /// Each pair once, under its lower index: neighbors(i) holds only j > i.
    /// Half the memory and work; for a force applied to both particles
    /// (Newton's third law), gathered per particle in a fixed order rather
    /// than added from several threads (pdyn/parallel.hpp's rule).
    Half,
    /// Each pair under both particles: neighbors(i) holds every j != i.
    /// For per-particle sums that each thread computes for its own particles
    /// without writing to the partner (densities, coordination numbers).
    Full,
  };

  /// cutoff: the force's interaction range rc, m (> 0, finite).
  /// skin: the extra margin listed, m (>= 0, finite). Larger means rarer
  /// rebuilds but longer lists; 0.1-0.3 rc is usual (0.3 sigma for
  /// Lennard-Jones liquids at rc = 2.5 sigma). skin = 0 rebuilds whenever any
  /// particle has moved at all.
  /// Throws std::invalid_argument when either is out of range.
  NeighborList(double cutoff, double skin, Kind kind = Kind::Half);

  /// Brings the list up to date for positions x (m, 3 x N; a Matrix3X or the
  /// Map of ParticleView::x, read without copying) in `domain`, and returns
  /// true if it rebuilt. It rebuilds when the list was never built, when N,
  /// the domain or the member mask changed, or when a listed particle has
  /// moved more than skin / 2 (nearest image along periodic axes) or became
  /// finite or non-finite since the last build; otherwise it only checks the
  /// displacements, O(N) and allocation-free.
  ///
  /// members: nullptr lists every particle; otherwise a mask of N entries,
  /// non-zero for the particles that take part (a force restricted to a
  /// selection): only pairs of two members are listed, and a non-member has
  /// no neighbors. The mask is compared with the one of the last build.
  ///
  /// Throws std::invalid_argument (and leaves the list as it was) when a
  /// periodic axis is not a finite length > 0, when it is shorter than
  /// 2 reach() (a particle would then meet two images of the same neighbor
  /// within reach), or when the mask does not have N entries.
  bool update(const Eigen::Ref<const Matrix3X>& x, const Domain& domain,
              const std::vector<std::uint8_t>* members = nullptr);

  /// What update() may rebuild for besides a list that must be rebuilt
  /// (never built; N, the domain or the member mask changed).
  enum class Rebuild {
    IfMoved,   ///< a listed particle moved more than skin / 2 (update()'s rule)
    Always,    ///< rebuild whatever the particles did
    IfForced,  ///< only when the list must be rebuilt
  };
  /// How a caller changes update()'s rule (since pdyn 0.10.0: a host's
  /// rebuild schedule, pdyn/kernel/neighbor_schedule.hpp, and a barostat's
  /// box, both through SharedNeighborList).
  struct UpdateRule {
    Rebuild when = Rebuild::IfMoved;
    /// < 0: the domain must be the build's, or the list is rebuilt. >= 0: a
    /// box resized since the build (resizes()) is kept, this (m) being the
    /// largest |d min| + |d max| of its faces at any update since the
    /// build: the displacement allowed shrinks to skin / 2 - 2.5 box_moved,
    /// LAMMPS's allowance for the images' moves, and pdyn's wrap at every
    /// step (a displacement measured across a wrap is off by the box's
    /// change since the wrap).
    double box_moved = -1.0;
  };
  /// As update(), under `rule`.
  bool update(const Eigen::Ref<const Matrix3X>& x, const Domain& domain,
              const std::vector<std::uint8_t>* members, const UpdateRule& rule);

  /// Rebuilds unconditionally (same arguments and errors as update()). O(N):
  /// bins the particles into cells of side >= reach() / 2 (a counting sort),
  /// then lists each particle's partners within reach() from the cells up to
  /// two away along each axis, in one pass. Allocates only when N grows or the pair count outgrows
  /// the room (1/8 more than the largest count so far) of earlier builds.
  void build(const Eigen::Ref<const Matrix3X>& x, const Domain& domain,
             const std::vector<std::uint8_t>* members = nullptr);

  /// Number of particles N at the last build (0 before the first).
  Index size() const noexcept { return static_cast<Index>(offsets_.size()) - 1; }

  /// The neighbors of particle i (0 <= i < size()), ascending: the j that were
  /// within reach() of i at the last build (only j > i for Kind::Half).
  std::span<const Index> neighbors(Index i) const noexcept {
    const auto begin = static_cast<std::size_t>(offsets_[static_cast<std::size_t>(i)]);
    const auto end = static_cast<std::size_t>(offsets_[static_cast<std::size_t>(i) + 1]);
    return std::span<const Index>(indices_).subspan(begin, end - begin);
  }

  /// CSR row offsets, size() + 1 entries: offsets()[0] = 0, and the last is
  /// indices().size().
  std::span<const Index> offsets() const noexcept { return offsets_; }
  /// CSR column indices: every particle's neighbors, particle after particle.
  std::span<const Index> indices() const noexcept { return indices_; }

  double cutoff() const noexcept { return cutoff_; }         ///< interaction range rc, m
  double skin() const noexcept { return skin_; }             ///< listed margin beyond rc, m
  double reach() const noexcept { return cutoff_ + skin_; }  ///< listing distance, m
  Kind kind() const noexcept { return kind_; }

  /// Since 0.10.0: true when `to` is `from` with only the periodic axes'
  /// bounds moved (a barostat's box): a list built in `from` can then be
  /// kept in `to` (UpdateRule::box_moved).
  static bool resizes(const Domain& from, const Domain& to);

  /// Number of builds so far (update()'s rebuilds and build()'s).
  std::int64_t builds() const noexcept { return builds_; }
  /// A number that changes with every build of any list in the process
  /// (never the same for two builds): what is derived from a list stays
  /// valid while its stamp() is unchanged. 0 before the first build.
  std::uint64_t stamp() const noexcept { return stamp_; }
  /// Changes the cutoff and skin (same ranges as the constructor); the next
  /// update() rebuilds.
  void set_range(double cutoff, double skin);

  /// Number of distinct pairs listed (each counted once, also for Kind::Full,
  /// which stores 2 pair_count() indices).
  Index pair_count() const noexcept {
    const auto n = static_cast<Index>(indices_.size());
    return kind_ == Kind::Full ? n / 2 : n;
  }

 private:
  // One particle's copy in the cell-sorted arrays: its position (wrapped into
  // the box along periodic axes), m.
  using Point = std::array<double, 3>;

  // The cell grid of one build. Cells are about reach / 2 wide (LAMMPS's
  // default binning), so a particle's partners lie within 2 cells along each
  // axis and the scanned volume is about 2.5 times the sphere of reach,
  // against 6.4 times with cells of side reach.
  struct Grid {
    std::array<Index, 3> n{1, 1, 1};      // cells per axis
    std::array<Index, 3> reach{1, 1, 1};  // cells a partner can be away along each axis
    std::array<double, 3> lo{};           // lower edge of cell 0, m
    std::array<double, 3> side{};         // cell side, m (0 along an axis of 1 cell)
    std::array<double, 3> inv_side{};     // 1 / cell side, 1/m
    std::array<double, 3> length{};       // box length along periodic axes, m
    std::array<double, 3> half{};         // length / 2 (periodic), +inf (open), m
    std::array<bool, 3> periodic{};
    // True when some periodic axis has fewer than 2 reach + 1 cells: then one
    // cell can be the neighbor of another through two images, the scan visits
    // it once and the nearest image is found per pair (a fold). Otherwise each
    // scanned cell comes with the image shift that brings it next to the
    // particle's cell, and no pair needs a fold.
    bool fold = false;
  };
  // What a cell coordinate c + o along one axis is: the cell (-1: none, off an
  // open axis or already visited through a smaller |o|) and the shift of its
  // image, m.
  struct Near {
    Index cell = -1;
    double shift = 0.0;
  };
  // One row of the stencil: the cells at offsets (o, dy, dz), |o| <= half_x,
  // that can hold a partner.
  struct StencilRow {
    Index dy = 0, dz = 0, half_x = 0;
  };
  // Cells of side > reach / 2 put partners at most 2 cells away per axis.
  static constexpr Index kMaxReach = 2;
  static constexpr Index kWidth = 2 * kMaxReach + 1;
  // Per axis, what c + o is for the cells c within reach of a face (at most
  // kMaxReach at each end): a row of kWidth entries per such cell. Cells
  // further in have c + o, unshifted.
  using Edges = std::array<Near, 2 * kMaxReach * kWidth>;

  void check(const Eigen::Ref<const Matrix3X>& x, const Domain& domain,
             const std::vector<std::uint8_t>* members) const;
  bool stale(const Eigen::Ref<const Matrix3X>& x, const Domain& domain,
             const std::vector<std::uint8_t>* members) const;  // 0.9.0's; unused
  bool must_rebuild(const Eigen::Ref<const Matrix3X>& x, const Domain& domain,
                    const std::vector<std::uint8_t>* members, bool resized) const;
  bool stale(const Eigen::Ref<const Matrix3X>& x, const Domain& domain,
             const std::vector<std::uint8_t>* members, double box_moved) const;
  void make_grid(const Domain& domain, const std::array<double, 3>& lo,
                 const std::array<double, 3>& hi, Index listed);
  void make_stencil();
  // The entry for o = 0 of cell c's row in edges_[k] (index it with o), or
  // nullptr if c is more than reach cells from both ends of the axis.
  const Near* edge_row(int k, Index c) const;
  Index edge_slot(int k, Index c) const;
  void bin(const Eigen::Ref<const Matrix3X>& x, const Domain& domain);
  template <bool Fold>
  Index fill_row(Index i, std::vector<Index>& buf, Index used) const;
  void fill_rows(Index n);
  // Kind::Half on a grid without a fold: each pair found once (since 0.10).
  Index half_pairs(Index slot, std::vector<Index>& buf, Index used) const;
  void fill_half_rows(Index n);

  double cutoff_, skin_;
  Kind kind_;
  std::int64_t builds_ = 0;
  std::uint64_t stamp_ = 0;

  // The last build's inputs, to tell when the list is stale.
  Domain domain_;
  std::vector<double> x0_;          // positions at the last build, 3N, m
  std::vector<std::uint8_t> mask_;  // its member mask (empty: every particle)
  bool built_ = false;

  // The cell list: a counting sort of the listed particles by cell.
  Grid grid_;
  std::vector<Index> cell_of_;       // per particle: its cell, or -1 if not listed
  std::vector<Index> slot_of_;       // per particle: its slot in sorted_*, or -1
  std::vector<Index> cell_start_;    // per cell c: its slots are [start[c], start[c + 1])
  std::vector<Index> cell_fill_;     // per cell: next free slot while sorting
  std::vector<Index> sorted_index_;  // per slot: the particle, ascending within a cell
  std::vector<Point> sorted_pos_;    // per slot: its (wrapped) position
  std::array<Edges, 3> edges_;
  std::array<StencilRow, kWidth * kWidth> stencil_{};
  int stencil_rows_ = 0;

  // Rows listed by threads 1, 2, ... before they are joined after thread
  // 0's, which it lists in place (one pass, no count).
  std::vector<std::vector<Index>> chunks_;

  // The Verlet list, CSR.
  std::vector<Index> offsets_{0};
  std::vector<Index> indices_;
};

/// A neighbor list shared by every pair force on the same particles. Forces
/// whose lists would hold the same kind of pairs of the same particles (the
/// same positions array, N, box and member mask) share one list, built at
/// the largest of their cutoffs and reaches (cutoff + skin); each force
/// skips the pairs beyond its own cutoff. A Lennard-Jones force and a
/// contact force on one system then bin and search once per rebuild, not
/// twice. Sharing never changes a result: a pair force sums only the pairs
/// within its cutoff, in ascending order of the partner, whatever else the
/// list holds. Forces evaluated on different particle arrays (two systems,
/// a copy of the state) never share. Thread-safe across systems.
class PDYN_API SharedNeighborList {
 public:
  /// As NeighborList's constructor (same errors); what this force needs.
  SharedNeighborList(double cutoff, double skin,
                     NeighborList::Kind kind = NeighborList::Kind::Half);

  /// Joins the list of the forces on these particles (or starts one),
  /// widens it to this force's cutoff and reach if needed, brings it up to
  /// date as NeighborList::update() does (same arguments and errors), and
  /// returns it. Its cutoff() is >= this force's.
  const NeighborList& update(const Eigen::Ref<const Matrix3X>& x, const Domain& domain,
                             const std::vector<std::uint8_t>* members = nullptr);

  /// The list of the last update(), or nullptr before the first.
  const NeighborList* list() const noexcept;

  double cutoff() const noexcept { return cutoff_; }  ///< this force's cutoff, m
  double skin() const noexcept { return skin_; }      ///< this force's skin, m

  struct Entry;  ///< the shared list and what it is for (opaque)

 private:
  double cutoff_, skin_;
  NeighborList::Kind kind_;
  std::shared_ptr<Entry> entry_;
};

}  // namespace pdyn
